"""Typed configs: YAML read into frozen dataclasses (unknown keys, wrong types and ranges refused at load) and
the reference generated from them."""

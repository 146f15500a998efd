"""Device strings: the syntax shared by training and scoring."""

from __future__ import annotations

import pytest

from curate.core.device import DeviceError, parse_device


@pytest.mark.parametrize(
    ("spec", "parsed"),
    [("auto", ("auto", None)), ("cpu", ("cpu", None)), ("cuda", ("cuda", None)), ("CUDA:1", ("cuda", 1))],
)
def test_parse(spec: str, parsed: tuple) -> None:
    assert parse_device(spec) == parsed


@pytest.mark.parametrize("spec", ["gpu", "cpu:0", "cuda:x", "", "mps", "cuda:-1"])
def test_bad_strings_are_named(spec: str) -> None:
    with pytest.raises(DeviceError, match="expected auto | cpu | cuda | cuda:N"):
        parse_device(spec)

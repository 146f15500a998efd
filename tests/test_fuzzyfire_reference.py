"""The generated configuration reference and the commented Method YAMLs equal what the code generates now."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzyfire.reference import generated, sections

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("rel", sorted(generated()))
def test_generated_files_match_the_dataclasses(rel: str) -> None:
    """A changed key, default or comment must be regenerated: python -m fuzzyfire.reference (make reference)."""
    assert (ROOT / rel).read_text(encoding="utf-8") == generated()[rel], f"{rel}: run make reference"


def test_every_key_of_the_command_sections_is_documented() -> None:
    from ground.config.reference import rows

    for heading, _, cls in sections():
        missing = [r.key for r in rows(cls) if not r.doc]
        assert not missing, f"{heading}: keys without a comment in {cls.__name__}: {missing}"


def test_the_method_yamls_load_as_their_defaults() -> None:
    from ground.config.loader import load_config
    from synth.method1 import Method1Config
    from synth.method2 import Method2Config

    for name, schema in (("synth-method1.yaml", Method1Config), ("synth-method2.yaml", Method2Config)):
        assert load_config(ROOT / "configs" / name, schema) == schema()


def _nested(cls: type) -> set[type]:
    """``cls`` and every dataclass its keys hold (Optional unwrapped)."""
    import dataclasses
    import typing

    found = {cls}
    for hint in typing.get_type_hints(cls).values():
        for tp in (hint, *typing.get_args(hint)):
            if dataclasses.is_dataclass(tp) and tp not in found:
                found |= _nested(tp)
    return found


def test_every_commands_settings_are_in_the_reference() -> None:
    """Each command whose flags alias config keys has its dataclass in docs/config.md (a section, or a section's
    part), so --help, the reference and the code state the same defaults."""
    from fuzzyfire.cli import build_parser

    documented = set().union(*(_nested(cls) for _, _, cls in sections()))
    stack, schemas = [build_parser()], set()
    while stack:
        parser = stack.pop()
        for action in parser._actions:
            if hasattr(action, "choices") and isinstance(action.choices, dict):
                stack.extend(action.choices.values())
            partial = getattr(action, "key_defaults", None)
            if partial is not None:
                schema = partial.args[0]
                schemas.add(schema if isinstance(schema, type) else schema())
    assert len(schemas) > 12
    assert sorted(s.__name__ for s in schemas - documented) == []

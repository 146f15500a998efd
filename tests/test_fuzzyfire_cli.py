"""The ``fuzzyfire`` parser (every command, help order) and ``fuzzyfire experiment``: help with examples, clear
errors before any work (exit code 2)."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO
from factories_experiment import write_toy_config

from fuzzyfire.cli import build_parser, main


def test_every_command_has_help_with_an_example(capsys):
    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    assert set(sub.choices) >= {"convert", "validate", "stats", "merge"}
    for name, p in sub.choices.items():
        assert "example:" in p.format_help(), name


def test_help_lists_the_commands_in_order() -> None:
    sub = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    assert [a.dest for a in sub._choices_actions] == [
        "convert",
        "validate",
        "stats",
        "merge",
        "mix",
        "dedup",
        "leakage",
        "curate",
        "synth",
        "train",
        "score",
        "compare",
        "predict",
        "experiment",
    ]


def test_help_has_examples(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["experiment", "--help"])
    text = capsys.readouterr().out
    assert "example:" in text and "configs/demo.yaml" in text and "--executor ray --address" in text


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--executor", "dask"], "executor.name: 'dask' is not one of"),
        (["--address", "ray://head:10001"], "--address (executor.address) needs --executor ray"),
        (["--set", "train.epoch=3"], "train.epoch: unknown key"),
        (["--set", "real.standin=null"], "real: give path"),
    ],
)
def test_bad_arguments_fail_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    config = write_toy_config(tmp_path / "toy.yaml")
    assert main(["experiment", str(config), "--out", str(tmp_path / "out"), *extra]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_missing_real_folder_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = REPO / "configs" / "paper.yaml"
    code = main(["experiment", str(config), "--out", str(tmp_path / "out"), "--set", "real.path=/no/such/folder"])
    assert code == 2 and "/no/such/folder" in capsys.readouterr().err


def _commands(parser, prefix=()):
    """(argv prefix, parser) of every command and subcommand, e.g. (("synth", "method2"), parser)."""
    for action in parser._actions:
        if action.__class__.__name__ == "_SubParsersAction":
            for name, sub in action.choices.items():
                yield (*prefix, name), sub
                yield from _commands(sub, (*prefix, name))


def test_every_option_with_a_default_shows_it_in_help(capsys: pytest.CaptureFixture[str]) -> None:
    checked = 0
    for argv, parser in _commands(build_parser()):
        with pytest.raises(SystemExit):
            main([*argv, "--help"])
        text = capsys.readouterr().out
        for action in parser._actions:
            default = action.default
            if not action.option_strings or default in (None, [], "==SUPPRESS==") or isinstance(default, bool):
                continue
            start = text.index(f"  {action.option_strings[0]}")
            block = text[start : text.find("\n  -", start + 1)]
            assert "default" in block, (argv, action.option_strings, block)
            checked += 1
    assert checked > 50

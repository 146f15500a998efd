"""The ``fuzzyfire`` parser (every command, help order, no flag with a default of its own) and ``fuzzyfire
experiment``: help with examples, clear errors before any work (exit code 2); the Makefile repeats no default."""

from __future__ import annotations

import argparse
import errno
import re
from pathlib import Path

import pytest
import yaml
from conftest import REPO
from factories_experiment import write_toy_config

from fuzzyfire.cli import build_parser, link_loop, main
from fuzzyfire.experiment_config import ExperimentConfig, RealConfig
from ground.config.loader import to_dict


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


def test_a_holdout_conflict_is_named_by_its_file_before_any_work(tmp_path: Path, capsys) -> None:
    config = REPO / "configs" / "own-flames.yaml"
    extra = ["--set", "synth.method2.background_holdout=0.1"]  # the fire-free test set holds out 0.25
    assert main(["experiment", str(config), "--out", str(tmp_path / "out"), *extra]) == 2
    err = capsys.readouterr().err
    assert "own-flames.yaml" in err and "background_holdout 0.1 and tests.fire-free.holdout 0.25" in err
    assert not (tmp_path / "out").exists()


def test_missing_real_folder_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = REPO / "configs" / "paper.yaml"
    code = main(["experiment", str(config), "--out", str(tmp_path / "out"), "--set", "real.path=/no/such/folder"])
    assert code == 2 and "/no/such/folder" in capsys.readouterr().err


@pytest.mark.parametrize("key", ["synth.method2.backgrounds=[{}]", "real.path={}"])
def test_a_symbolic_link_loop_is_named_not_a_traceback(tmp_path: Path, capsys, key: str) -> None:
    (tmp_path / "shared").symlink_to("shared")  # ../shared pointing at itself
    config = REPO / "configs" / "own-flames.yaml"
    where = tmp_path / "shared" / "data"
    assert main(["experiment", str(config), "--out", str(tmp_path / "out"), "--set", key.format(where)]) == 2
    err = capsys.readouterr().err
    assert str(where) in err and "leads back to itself" in err and "Traceback" not in err


def test_other_runtime_errors_are_not_taken_for_a_link_loop() -> None:
    assert link_loop(RuntimeError("Symlink loop from '/a'")) and link_loop(OSError(errno.ELOOP, "Too many levels"))
    assert not link_loop(RuntimeError("CUDA out of memory")) and not link_loop(OSError(errno.ENOSPC, "No space"))


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
            alias = getattr(action, "key_defaults", None) is not None
            if (
                not action.option_strings
                or not alias
                and (default in (None, [], "==SUPPRESS==") or isinstance(default, bool))
            ):
                continue
            flag = re.compile(rf"\n  {re.escape(action.option_strings[0])}[ ,\n]")
            start = flag.search(text, text.index("\noptions:")).start()
            block = text[start : text.find("\n  -", start + 1)]
            assert re.search(r"\[[\w.]+=", block) if alias else "default" in block, (
                argv,
                action.option_strings,
                block,
            )
            checked += 1
    assert checked > 50


def test_every_commands_settings_name_a_section_of_the_reference() -> None:
    """The help of each command's CONFIG.yaml names the docs/config.md section documenting its keys: a heading there."""
    from test_docs import anchors

    headings = anchors((REPO / "docs" / "config.md").read_text(encoding="utf-8"))
    sections = {}
    for argv, parser in _commands(build_parser()):
        for action in parser._actions:
            found = re.search(r"every key: docs/config\.md#([\w-]+)", action.help or "")
            if action.dest == "config" and found:
                sections[" ".join(argv)] = found.group(1)
    assert len(sections) == 17 and sections["synth method2"] == "synth-method2"
    assert {name: s for name, s in sections.items() if s not in headings} == {}


#: What a flag that is no setting defaults to: nothing (an input, an output, a switch, a repeatable option).
NO_DEFAULT = (None, False, [], argparse.SUPPRESS)


def test_no_flag_of_any_command_holds_a_default_of_its_own() -> None:
    """Every default lives once, in a config dataclass: a flag with a value of its own is an alias of a key (its
    help reads the key's default from the dataclass); any other flag defaults to nothing."""
    commands = list(_commands(build_parser()))
    assert len(commands) > 20
    aliases = [a for _, p in commands for a in p._actions if getattr(a, "key_defaults", None) is not None]
    assert len(aliases) > 100
    wrong = [
        f"fuzzyfire {' '.join(name)} {action.option_strings[0]} = {action.default!r}"
        for name, parser in commands
        for action in parser._actions
        if action.option_strings
        and getattr(action, "key_defaults", None) is None
        and not isinstance(action, (argparse._HelpAction, argparse._VersionAction))
        and not any(action.default is d or action.default == [] == d for d in NO_DEFAULT)  # 0 is a default
    ]
    assert wrong == []


def _default(cfg: object, key: str) -> object:
    """The default of the dotted ``key`` in the default ``cfg`` (a key inside a mapping or a null section: None)."""
    node = cfg
    for part in key.split("."):
        if not hasattr(node, part):
            return None
        node = getattr(node, part)
    return to_dict(node)


def test_the_makefile_passes_keys_never_a_default() -> None:
    """``make experiment``'s ``--set KEY=VALUE`` values differ from ExperimentConfig's defaults (a value equal to
    a default would be a second place to change it); values made from the make variables are the user's."""
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    tokens = [a or b for a, b in re.findall(r"--set (?:'([^']*)'|([^\s')]+))", makefile)]
    sets = [tuple(tok.split("=", 1)) for tok in tokens if "$(" not in tok]
    assert ("synth.method2.photo_negatives", "1.0") in sets
    defaults = ExperimentConfig(real=RealConfig())
    same = [f"{k}={v}" for k, v in sets if yaml.safe_load(v) == _default(defaults, k)]
    assert same == []
    assert _default(defaults, "train.epochs") == defaults.train.epochs  # the check can see a default

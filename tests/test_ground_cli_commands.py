"""The helpers every package's commands share: a bad config is ``error: PATH: message`` (the command returns 2), a
dataset written with its provenance or ``error: message``, the reader options, problems one per line."""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path

import pytest
from factories import write_yolo_dataset

from ground.cli.commands import (
    add_command,
    add_reader_args,
    command_args,
    parse_aliases,
    print_problems,
    write_dataset_or_report,
)
from ground.data.formats.yolo import read_yolo
from ground.data.manifest import file_sha256
from ground.data.problems import Problem


@dataclass(frozen=True)
class Toy:
    name: str
    epochs: int = 3


@pytest.mark.parametrize(
    ("text", "overrides", "message"),
    [
        ("sources: []\nclass: [fire]\n", [], "class: unknown key (known: sources, classes, images)"),
        ("classes: [fire]\n", [], "sources: required key is missing"),
        ("sources: []\n", ["--set", "images=many"], "images: 'many' is not one of ['copy', 'hardlink', 'symlink']"),
        ("sources: [fire\n", [], "invalid YAML"),
    ],
)
def test_a_bad_config_is_one_error_naming_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, overrides: list[str], message: str
) -> None:
    from fuzzyfire.cli import main

    path = tmp_path / "m.yaml"
    path.write_text(text)
    assert main(["merge", str(path), "--out", str(tmp_path / "out"), *overrides]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {path}: ") and message in err and err.count("error: ") == 1, err
    assert f"{path}: {path}" not in err and "<unicode string>" not in err  # named once, and in YAML's own mark


def test_the_exit_code_of_a_command_with_a_bad_config_is_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from fuzzyfire.cli import main

    (tmp_path / "m.yaml").write_text("classes: [fire]\nsources: []\nunknown: 1\n")
    assert main(["merge", str(tmp_path / "m.yaml"), "--out", str(tmp_path / "out")]) == 2
    assert (
        capsys.readouterr().err
        == f"error: {tmp_path / 'm.yaml'}: unknown: unknown key (known: sources, classes, images)\n"
    )
    assert not (tmp_path / "out").exists()


def _args(tmp_path: Path, **extra) -> argparse.Namespace:
    return argparse.Namespace(out=tmp_path / "out", overwrite=False, command="convert", func=print, **extra)


def test_a_dataset_is_written_with_the_command_arguments(tmp_path: Path) -> None:
    write_yolo_dataset(tmp_path / "src")
    ds = read_yolo(tmp_path / "src").dataset
    written = write_dataset_or_report(ds, _args(tmp_path, to="coco"), "convert", ["coco"], "copy")
    assert written is not None and written.files["coco"] == "annotations.json"
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["command"] == "convert" and manifest["sources"] == []
    assert manifest["args"] == {"out": str(tmp_path / "out"), "overwrite": False, "to": "coco"}


def test_a_config_driven_dataset_records_the_config_and_its_hash(tmp_path: Path) -> None:
    write_yolo_dataset(tmp_path / "src")
    ds = read_yolo(tmp_path / "src").dataset
    (tmp_path / "toy.yaml").write_text("name: fire\n")
    args = _args(tmp_path, config=str(tmp_path / "toy.yaml"), set=["epochs=7"])
    assert write_dataset_or_report(ds, args, "merge", ("coco", "yolo"), "copy", Toy("fire", 7)) is not None
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["command"] == "merge"
    assert manifest["args"] == {"config": {"name": "fire", "epochs": 7}, "set": ["epochs=7"]}
    assert [s["sha256"] for s in manifest["sources"]] == [file_sha256(tmp_path / "toy.yaml")]


def test_a_refused_output_folder_is_one_error_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    write_yolo_dataset(tmp_path / "src")
    ds = read_yolo(tmp_path / "src").dataset
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "thesis.tex").write_text("precious")
    assert write_dataset_or_report(ds, _args(tmp_path), "convert", ["coco"], "copy") is None
    err = capsys.readouterr().err
    assert err.startswith(f"error: {tmp_path / 'out'}: folder is not empty") and err.count("\n") == 1
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["thesis.tex"]


def test_add_command_keeps_the_description_as_written() -> None:
    parser = argparse.ArgumentParser(prog="fuzzyfire")
    sub = parser.add_subparsers(dest="command")
    p = add_command(sub, "toy", help="a toy command", description="Line one.\n\nexample:\n  fuzzyfire toy --n 3")
    assert "Line one.\n\nexample:\n  fuzzyfire toy --n 3\n" in p.format_help()
    assert "a toy command" in parser.format_help()


def test_reader_args_and_aliases() -> None:
    parser = argparse.ArgumentParser()
    add_reader_args(parser)
    args = parser.parse_args(["--names", "fire, smoke,", "--alias", "flame=fire", "--drop-class", "default"])
    assert (args.fmt, args.names, args.drop_class, args.source) == (None, ["fire", "smoke"], ["default"], None)
    assert parse_aliases([*args.alias, " big = fire "]) == {"flame": "fire", "big": "fire"}
    with pytest.raises(SystemExit, match="expected NAME=CLASS"):
        parse_aliases(["flame"])


def test_command_args_leave_out_the_parser_fields(tmp_path: Path) -> None:
    assert command_args(_args(tmp_path, to="yolo")) == {"out": tmp_path / "out", "overwrite": False, "to": "yolo"}


def test_print_problems_one_line_each_then_the_counts(capsys: pytest.CaptureFixture[str]) -> None:
    problems = [Problem(f"a/{i}.jpg", "unreadable", "error") for i in range(3)] + [Problem("b.txt", "empty", "info")]
    print_problems(problems, limit=2)
    out, err = capsys.readouterr()
    assert out.splitlines() == [
        "a/0.jpg: unreadable",
        "a/1.jpg: unreadable",
        "... and 2 more (fuzzyfire validate DATASET lists every one)",
    ]
    assert err == "3 errors, 0 warnings, 1 info\n"

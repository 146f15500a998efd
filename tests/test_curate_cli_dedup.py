"""``fuzzyfire dedup`` / ``leakage`` end to end on generated images: outputs, bad files, untouched originals."""

from __future__ import annotations

import json
import socket
from pathlib import Path

import pytest
from curate_helpers import save, scene, transformed, use_session_cache

from fuzzyfire.cli import main


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    use_session_cache(tmp_path_factory)
    root = tmp_path_factory.mktemp("cli") / "imgs"
    for i in range(6):
        save(scene(10 + i), root / f"a{i}.jpg")
    save(transformed(scene(10), "resize"), root / "sub" / "a0_small.jpg")
    save(transformed(scene(11), "hflip"), root / "sub" / "a1_flip.png")
    (root / "sub" / "a2_copy.jpg").write_bytes((root / "a2.jpg").read_bytes())
    (root / "bad.jpg").write_bytes(b"\xff\xd8\xff\xe0 garbage")
    return root


def _snapshot(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def test_dedup_writes_json_report_and_histogram(folder: Path, tmp_path: Path, capsys) -> None:
    before = _snapshot(folder)
    out = tmp_path / "out"
    assert (
        main(["dedup", str(folder), "--out", str(out), "--top", "3", "--apply", "copy", "--to", str(tmp_path / "kept")])
        == 0
    )
    doc = json.loads((out / "dedup.json").read_text())
    assert {"kept", "removed", "ranking", "threshold", "model", "groups", "problems"} <= set(doc)
    removed = {(Path(r["path"]).name, Path(r["duplicate_of"]).name, r["kind"]) for r in doc["removed"]}
    pairs = {(a, b) for a, b, _ in removed}
    assert {("a0_small.jpg", "a0.jpg"), ("a2_copy.jpg", "a2.jpg")} <= pairs  # resolution; then path order
    assert {frozenset(p) for p in pairs} == {
        frozenset(("a0_small.jpg", "a0.jpg")),
        frozenset(("a2.jpg", "a2_copy.jpg")),
        frozenset(("a1_flip.png", "a1.jpg")),
    }
    assert {a: k for a, _, k in removed}["a2_copy.jpg"] == "exact"
    assert all(Path(p).is_absolute() for p in doc["kept"]) and len(doc["kept"]) == 6
    assert [Path(p["path"]).name for p in doc["problems"]] == ["bad.jpg"]
    assert len(doc["ranking"]) == 6 and doc["ranking"][0]["score"] >= doc["ranking"][-1]["score"]
    assert len(doc["selected"]) == 3
    html = (out / "report.html").read_text()
    assert "KEPT" in html and "distances.png" in html and (out / "distances.png").stat().st_size > 1000
    assert "Duplicate groups (green = kept): 3 of 3" in html and "a group can keep several images" in html
    assert html.count("<p>2 images: 1 kept, 1 removed</p>") == 3  # each group's counts above its images
    assert len(list((tmp_path / "kept").rglob("*.*"))) == 3
    assert _snapshot(folder) == before  # originals never modified
    out_text, err = capsys.readouterr()
    assert "bad.jpg" in err and "<_io.BytesIO" not in err
    assert "1 unreadable (bad.jpg)" in out_text  # the summary names the file, not only the count
    assert "Unreadable files, skipped: 1" in html and f"{folder / 'bad.jpg'}: truncated JPEG" in html


def test_dedup_of_a_folder_without_readable_images_is_an_input_error(tmp_path: Path, capsys) -> None:
    (tmp_path / "empty").mkdir()
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "readme.txt").write_text("no images here")
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "a.jpg").write_bytes(b"\xff\xd8\xff\xe0 garbage")
    for name, message in [
        ("empty", "no image files in"),
        ("notes", "no image files in"),
        ("broken", "none of the 1 image files in"),
    ]:
        assert main(["dedup", str(tmp_path / name), "--out", str(tmp_path / f"out-{name}")]) == 2
        err = capsys.readouterr().err
        assert f"error: {message} {tmp_path / name}" in err, err
        assert not (tmp_path / f"out-{name}").exists()
    capsys.readouterr()
    assert main(["leakage", str(tmp_path / "empty"), str(tmp_path / "notes")]) == 2
    assert "error: no image files in" in capsys.readouterr().err


def test_dedup_refuses_bad_arguments(folder: Path, tmp_path: Path, capsys) -> None:
    assert main(["dedup", str(folder), "--out", str(tmp_path / "o"), "--apply", "copy"]) == 2
    assert main(["dedup", str(folder), "--out", str(tmp_path / "o"), "--mean", "1,2,3"]) == 2
    assert main(["dedup", str(tmp_path / "missing"), "--out", str(tmp_path / "o")]) == 2
    assert main(["dedup", str(folder), "--out", str(tmp_path / "o"), "--apply", "copy", "--to", str(folder / "x")]) == 2
    err = capsys.readouterr().err
    assert "--to" in err and "need --model" in err and "no such file" in err
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]  # nothing listens there
    for extra, message in (
        (["--address", f"127.0.0.1:{port}"], "--address joins a Ray cluster: it needs --executor ray"),
        (["--executor", "ray", "--address", f"127.0.0.1:{port}"], f"cannot join the Ray cluster at 127.0.0.1:{port}"),
        (["--device", "tpu"], "device 'tpu': expected auto | cpu | cuda | cuda:N"),
    ):
        assert main(["dedup", str(folder), "--out", str(tmp_path / "o"), *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "o").exists()


def test_help_has_examples(capsys) -> None:
    with pytest.raises(SystemExit):
        main(["dedup", "--help"])
    assert "example:" in capsys.readouterr().out


def test_dedup_calibrate_records_threshold(folder: Path, tmp_path: Path, capsys) -> None:
    assert main(["dedup", str(folder), "--out", str(tmp_path / "c"), "--calibrate", "--seed", "1"]) == 0
    doc = json.loads((tmp_path / "c" / "dedup.json").read_text())
    assert doc["threshold"] == doc["calibration"]["threshold"] and doc["calibration"]["images"] == 9
    assert "calibrated threshold" in capsys.readouterr().out


def test_leakage_hints_at_the_json_file_that_holds_every_pair(folder: Path, tmp_path: Path, capsys) -> None:
    assert main(["leakage", str(folder), str(folder / "sub"), "--show", "1"]) == 1  # pairs found: exit 1
    out = capsys.readouterr().out
    assert "more (--json FILE writes every pair)" in out and "use --json" not in out
    assert main(["leakage", str(folder), str(folder / "sub"), "--show", "1", "--json", str(tmp_path / "l.json")]) == 1
    assert f"more (see {tmp_path / 'l.json'})" in capsys.readouterr().out
    assert len(json.loads((tmp_path / "l.json").read_text())["leaks"]) >= 2


def test_settings_print_and_read_back_without_any_image(tmp_path: Path, capsys) -> None:
    assert main(["dedup", "--print-config", "--top", "3", "--exact-only", "--nhwc", "--executor", "ray"]) == 0
    (tmp_path / "d.yaml").write_text(capsys.readouterr().out)
    assert main(["dedup", "--config", str(tmp_path / "d.yaml"), "--print-config"]) == 0
    text = capsys.readouterr().out
    assert (tmp_path / "d.yaml").read_text() == text
    assert "top: 3" in text and "near: false" in text and "layout: nhwc" in text and "name: ray" in text
    assert main(["dedup", "--config", str(tmp_path / "d.yaml"), "--print-config", "--top", "0", "--seed", "0"]) == 0
    assert "top: 0" in capsys.readouterr().out  # a flag given as 0 overrides the file
    assert main(["dedup", "--out", str(tmp_path / "o")]) == 2
    assert "DIR is required (unless --print-config)" in capsys.readouterr().err
    assert main(["leakage", str(tmp_path), "--config", str(tmp_path / "nope.yaml")]) == 2
    assert capsys.readouterr().err == f"error: {tmp_path / 'nope.yaml'}: does not exist, not a settings file\n"

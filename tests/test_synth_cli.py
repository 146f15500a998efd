import json
from pathlib import Path

from fuzzyfire.cli import main


def test_flames_method2_audit_commands(tmp_path, capsys):
    assert (
        main(["synth", "flames", "--out", str(tmp_path / "fl"), "--n", "1", "--frames", "60", "--keep-every", "30"])
        == 0
    )
    out = tmp_path / "m2"
    args = ["synth", "method2", "--n", "3", "--out", str(out), "--size", "64x48", "--scenes", "1"]
    assert main([*args, "--flames", str(tmp_path / "fl")]) == 0
    capsys.readouterr()
    assert main(["synth", "audit", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["images"] == 3 and report["mean_iou"] == 1.0


def test_bad_size_is_rejected(capsys):
    import pytest

    with pytest.raises(SystemExit):
        main(["synth", "method2", "--out", "x", "--size", "big"])
    assert "640x480" in capsys.readouterr().err


def test_method1_command_writes_both_box_modes(tmp_path, capsys):
    assert (
        main(["synth", "flames", "--out", str(tmp_path / "fl"), "--n", "1", "--frames", "60", "--keep-every", "30"])
        == 0
    )
    out = tmp_path / "m1"
    args = [
        "synth",
        "method1",
        "--n",
        "3",
        "--out",
        str(out),
        "--size",
        "64x48",
        "--scenes",
        "1",
        "--box-mode",
        "paper",
    ]
    assert main([*args, "--flames", str(tmp_path / "fl")]) == 0
    capsys.readouterr()
    assert main(["synth", "audit", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["images"] == 3 and set(report["modes"]) == {"paper", "visible"}
    assert report["modes"]["visible"]["mean_iou"] == 1.0


def test_method1_and_method2_in_a_file_environment(tmp_path, capsys):
    from factories import write_textured_room

    room = write_textured_room(tmp_path / "rooms" / "den.glb")
    flames = ["synth", "flames", "--out", str(tmp_path / "fl"), "--n", "1", "--frames", "60", "--keep-every", "30"]
    assert main(flames) == 0
    for method in ("method1", "method2"):
        out = tmp_path / method
        args = ["synth", method, "--n", "4", "--out", str(out), "--size", "96x64", "--scenes", "0"]
        assert main([*args, "--environments", str(room.parent), "--flames", str(tmp_path / "fl")]) == 0
        manifest = json.loads((out / "manifest.json").read_text())
        assert {img["environment"] for img in manifest["args"]["per_image"]} == {"den"}
        capsys.readouterr()
        assert main(["synth", "audit", str(out), "--json"]) == 0
        report = json.loads(capsys.readouterr().out)
        iou = report["modes"]["visible"]["mean_iou"] if method == "method1" else report["mean_iou"]
        assert report["images"] == 4 and iou == 1.0


def test_method2_on_photographs(tmp_path, capsys):
    from factories import write_image

    for k in range(3):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 200, 150, seed=k)
    flames = ["synth", "flames", "--out", str(tmp_path / "fl"), "--n", "1", "--frames", "60", "--keep-every", "30"]
    assert main(flames) == 0
    out = tmp_path / "m2"
    args = ["synth", "method2", "--n", "6", "--out", str(out), "--size", "96x64", "--scenes", "0"]
    assert main([*args, "--backgrounds", str(tmp_path / "photos"), "--flames", str(tmp_path / "fl")]) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert {Path(img["photo"]).name for img in manifest["args"]["per_image"]} <= {"p0.jpg", "p1.jpg", "p2.jpg"}
    capsys.readouterr()
    assert main(["synth", "audit", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["mean_iou"] == 1.0

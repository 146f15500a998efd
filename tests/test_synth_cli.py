import json
from pathlib import Path

import pytest

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
    assert report["visibility"]["boxes"] == report["boxes"]
    assert main(["synth", "audit", str(out)]) == 0
    assert "visibility: " in capsys.readouterr().out


def test_flames_write_a_preview_and_no_empty_layer(tmp_path, capsys):
    import cv2

    out = tmp_path / "fl"
    assert main(["synth", "flames", "--out", str(out), "--n", "3", "--frames", "60", "--keep-every", "30"]) == 0
    assert f"preview {out / 'preview.png'}" in capsys.readouterr().out
    seqs = sorted(p for p in out.iterdir() if p.is_dir())
    sheet = cv2.imread(str(out / "preview.png"))
    assert len(seqs) == 3 and sheet.shape == (3 * (18 + 2 * 96 + 1), 8 * 96, 3)
    pngs = [p for p in out.rglob("*.png") if p.parent != out]
    assert pngs and not list(out.rglob("*_over.png"))
    for path in pngs:  # every layer file shows something (a frame without smoke has no smoke file)
        assert cv2.imread(str(path), cv2.IMREAD_UNCHANGED).max() > 0, path
    meta = json.loads((seqs[0] / "sequence.json").read_text())
    assert "NNNN_emission.png" in meta["layers"]


def test_bad_size_is_rejected(capsys):

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
        args = ["synth", method, "--n", "4", "--out", str(out), "--size", "96x64"]
        assert main([*args, "--environments", str(room.parent), "--flames", str(tmp_path / "fl")]) == 0
        manifest = json.loads((out / "manifest.json").read_text())
        assert manifest["args"]["scenes"] == 0  # the user's environments alone: no procedural room mixed in
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
    whole = (tmp_path / "photos" / "p0.jpg").read_bytes()
    (tmp_path / "photos" / "cut.jpg").write_bytes(whole[: len(whole) // 2])  # a truncated download
    (tmp_path / "photos" / "notes.jpg").write_text("not an image\n")  # a text file named .jpg
    flames = ["synth", "flames", "--out", str(tmp_path / "fl"), "--n", "1", "--frames", "60", "--keep-every", "30"]
    assert main(flames) == 0
    out = tmp_path / "m2"
    args = ["synth", "method2", "--n", "6", "--out", str(out), "--size", "96x64"]
    capsys.readouterr()
    assert main([*args, "--backgrounds", str(tmp_path / "photos"), "--flames", str(tmp_path / "fl")]) == 0
    skipped = [line for line in capsys.readouterr().err.splitlines() if "skipped background" in line]
    assert sorted(Path(line.split(": ")[0]).name for line in skipped) == ["cut.jpg", "notes.jpg"]
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["args"]["scenes"] == 0  # the user's photos alone
    assert [Path(img["photo"]).name in {"p0.jpg", "p1.jpg", "p2.jpg"} for img in manifest["args"]["per_image"]] == [
        True
    ] * 6
    capsys.readouterr()
    assert main(["synth", "audit", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["mean_iou"] == 1.0


def _flames(tmp_path: Path, *extra: str) -> Path:
    flames = ["synth", "flames", "--out", str(tmp_path / "fl"), "--n", "1", "--frames", "60", "--keep-every", "30"]
    assert main([*flames, *extra]) == 0
    return tmp_path / "fl"


def test_exposed_flames_are_written_with_their_gain(tmp_path):
    params = json.loads((_flames(tmp_path, "--exposed", "--rare", "0") / "fluid-0-000" / "sequence.json").read_text())
    assert params["params"]["gain"] > 0


def test_what_can_be_checked_fails_in_one_line_before_rendering(tmp_path, capsys):

    from synth.staging import staging_dir

    fl = _flames(tmp_path)
    out = tmp_path / "m2"
    args = ["synth", "method2", "--n", "2", "--out", str(out), "--size", "64x48", "--scenes", "1", "--flames", str(fl)]
    assert main(args) == 0
    capsys.readouterr()
    cases = [
        ([], "a fuzzyfire dataset is already there; pass --overwrite to replace it"),
        (["--overwrite", "--environments", str(tmp_path / "nowhere")], "nowhere: no such environment file or folder"),
        (["--overwrite", "--backgrounds", str(tmp_path / "nophotos")], "nophotos: no such file or folder"),
        (["--overwrite", "--photo-negatives", "1"], "photo_negatives is the share of the backgrounds photos"),
        (["--overwrite", "--photo-share", "1.5"], "photo_share must be in 0..1, got 1.5"),
        (["--overwrite", "--set", "flames.rare=2"], "flames.rare must be in 0..1, got 2"),
        (["--overwrite", "--set", "flame_jitter=true"], "flame_jitter: unknown key"),
        (["--overwrite", "--address", "127.0.0.1:6379"], "--address joins a Ray cluster: it needs --executor ray"),
    ]
    for extra, message in cases:
        assert main([*args, *extra]) == 2
        err = capsys.readouterr().err
        assert err == f"error: {err[7:]}" and err.count("\n") == 1 and message in err, err
        assert not staging_dir(out).exists()
    with pytest.raises(SystemExit):
        main([*args, "--overwrite", "--out", str(tmp_path / "x"), "--scenes", "-"])


def test_a_failed_run_keeps_its_finished_images_and_says_so_or_leaves_nothing(tmp_path, capsys, monkeypatch):

    import synth.method2 as method2
    from synth.staging import staging_dir

    fl = _flames(tmp_path)
    out = tmp_path / "m2"
    args = ["synth", "method2", "--n", "4", "--out", str(out), "--size", "64x48", "--scenes", "1", "--flames", str(fl)]
    make_image = method2.make_image
    for fail_at, kept in ((0, 0), (2, 2)):

        def failing(cfg, i, library, views, fail_at=fail_at):
            if i == fail_at:
                raise RuntimeError("renderer lost")
            return make_image(cfg, i, library, views)

        monkeypatch.setattr(method2, "make_image", failing)
        with pytest.raises(RuntimeError):
            main(args)
        err = capsys.readouterr().err
        if kept:
            assert f"2 of 4 images are kept in {staging_dir(out)}: run the same command again to resume" in err
            assert len(list((staging_dir(out) / "records").glob("*.json"))) == 2
        else:
            assert not staging_dir(out).exists() and not out.exists()
    monkeypatch.setattr(method2, "make_image", make_image)
    assert main([*args, "--seed", "1"]) == 0  # other options: the staged images are not theirs
    assert "discarding 2 images staged with other options" in capsys.readouterr().err
    assert not staging_dir(out).exists()


def test_method2_on_a_fixed_camera_puts_every_flame_on_its_floor(tmp_path, capsys):
    """A folder of one camera's fire-free frames with a site sidecar: every flame's foot is on the floor polygon
    (the right half below the horizon), whatever the crop."""
    import numpy as np
    from factories import write_image

    for k in range(4):
        write_image(tmp_path / "cam" / f"f{k}.jpg", 160, 120, seed=k)
    (tmp_path / "cam" / "_site.yaml").write_text(
        "horizon: 0.3\ncamera_height: 3\nground: [[0.5, 0.3], [1, 0.3], [1, 1], [0.5, 1]]\n"
    )
    out = tmp_path / "m2"
    flat = _flames(tmp_path, "--texture", "0")  # the flat look, where a flame's seen box is its whole flame (a
    # softened edge can leave a dim foot unseen: the box's bottom is then above the foot)
    args = ["synth", "method2", "--n", "16", "--out", str(out), "--size", "96x72", "--flames", str(flat)]
    assert main([*args, "--backgrounds", str(tmp_path / "cam")]) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    coco = json.loads((out / "annotations.json").read_text())
    metas = {img["id"]: meta for img, meta in zip(coco["images"], manifest["args"]["per_image"])}
    feet = 0
    for ann in coco["annotations"]:
        meta = metas[ann["image_id"]]
        x, y, w, h = meta["crop"]
        bx, by, bw, bh = ann["bbox"]
        if by + bh >= 71.5 or bx <= 0.5 or bx + bw >= 95.5:
            continue  # cut by the frame: its foot is not the box's bottom centre
        foot = (x + (bx + bw / 2) * w / 96, y + (by + bh) * h / 72)  # in photo pixels
        assert foot[0] >= 80 - (2 + bw / 2) * w / 96 and foot[1] >= 36 - 2 * h / 72, (ann, meta)  # a seen part
        feet += 1
    assert feet >= 5 and all(meta["site"] == "sidecar" for meta in metas.values())
    assert np.mean([bool(meta["flames"]) for meta in metas.values()]) > 0.5


def test_method2_auto_exposure_from_the_command_line(tmp_path):
    """--auto-exposure: each fire image's metered exposure is in its manifest record."""
    from factories import write_image

    for k in range(2):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 160, 120, seed=k)
    out = tmp_path / "m2"
    flames = _flames(tmp_path)
    args = ["synth", "method2", "--n", "4", "--out", str(out), "--size", "96x72", "--flames", str(flames)]
    assert main([*args, "--backgrounds", str(tmp_path / "photos"), "--auto-exposure"]) == 0
    per_image = json.loads((out / "manifest.json").read_text())["args"]["per_image"]
    assert all(0.25 <= m["exposure_gain"] <= 1.0 for m in per_image if m["flames"])
    assert any(m["flames"] for m in per_image)


def test_method2_says_which_backgrounds_it_took_for_panoramas_and_keeps_small_2_to_1_photos(tmp_path, capsys):
    import cv2
    import numpy as np
    from factories import write_image

    for k in range(2):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 200, 150, seed=k)
    write_image(tmp_path / "photos" / "conference.jpg", 450, 225, seed=5)  # a wide photo, 2:1 by chance
    pano = np.random.default_rng(0).integers(0, 255, (512, 1024, 3), dtype=np.uint8)
    cv2.imwrite(str(tmp_path / "photos" / "plaza360.jpg"), pano)
    out = tmp_path / "m2"
    args = ["synth", "method2", "--n", "4", "--out", str(out), "--size", "96x64", "--flames", str(_flames(tmp_path))]
    capsys.readouterr()
    assert main([*args, "--backgrounds", str(tmp_path / "photos")]) == 0
    note = "took 1 of 4 backgrounds as 360° panoramas (2:1, >= 1024 px wide): plaza360.jpg"
    assert note in capsys.readouterr().err.splitlines()


def test_cutouts_refuse_settings_out_of_range_before_reading(tmp_path, capsys):
    for extra in (["--min-cover", "3"], ["--min-side", "0"]):
        assert main(["synth", "cutouts", str(tmp_path / "nowhere"), "--out", str(tmp_path / "c"), *extra]) == 2
        assert "min_side must be >= 1 and min_cover in 0..1" in capsys.readouterr().err

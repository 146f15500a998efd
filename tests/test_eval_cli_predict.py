"""``fuzzyfire predict`` as a user types it, on real ONNX "oracle" detectors (tests/detector_factories.py): a
folder of images and a short video, parity with ``score``'s predictions, pictures changed only where boxes are."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from detector_factories import IMAGES, oracle_model, rows_for, write_test_set
from detector_factories import TestImage as Still

from eval.draw import draw_detections, line_width
from fuzzyfire.cli import main
from ground.data.boxes import xywh_to_xyxy
from ground.image.imageio import read_image

NAMES = ["fire", "smoke"]
PICKED = {"wide": "a/wide.png", "big": "a/b/big.png", "neg1": "neg1.png"}  # 3 images, nested folders


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    root = tmp_path_factory.mktemp("predict")
    test = write_test_set(root / "test")
    folder = root / "photos"
    for name, rel in PICKED.items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(test / "images" / f"{name}.png", folder / rel)
    (folder / "a" / "broken.jpg").write_bytes(b"\xff\xd8\xff\xe0 not really a jpeg")
    model = oracle_model(root / "shifted.onnx", rows=rows_for(shift=3.0))  # fractional boxes, duplicates for NMS
    return {"root": root, "test": test, "folder": folder, "model": model}


def _detections(out: Path) -> list[dict]:
    return json.loads((out / "detections.json").read_text())


def test_boxes_equal_what_score_predicts_for_the_same_images(work, tmp_path, capsys):
    out = tmp_path / "pred"
    assert main(["predict", str(work["model"]), str(work["folder"]), "--out", str(out), "--conf", "0.001"]) == 0
    captured = capsys.readouterr()
    assert "a/broken.jpg: skipped: " in captured.err and "Traceback" not in captured.err
    assert "3 images" in captured.out
    assert main(["score", str(work["model"]), "--data", str(work["test"]), "--out", str(tmp_path / "s")]) == 0
    coco = json.loads((work["test"] / "annotations.json").read_text())
    files = {img["id"]: Path(img["file_name"]).stem for img in coco["images"]}
    cats = {c["id"]: c["name"] for c in coco["categories"]}
    scored = [
        {
            "file_name": PICKED[files[r["image_id"]]],
            "category": cats[r["category_id"]],
            "bbox": r["bbox"],
            "score": r["score"],
        }
        for r in json.loads((tmp_path / "s" / "predictions.json").read_text())
        if files[r["image_id"]] in PICKED
    ]
    got = _detections(out)
    key = lambda r: (r["file_name"], -r["score"])  # noqa: E731
    assert got and sorted(got, key=key) == sorted(scored, key=key)
    assert {r["file_name"] for r in got} == {"a/wide.png", "a/b/big.png"}  # the negative has none


def test_drawn_images_differ_from_the_inputs_exactly_where_boxes_are(work, tmp_path):
    out = tmp_path / "pred"
    assert main(["predict", str(work["model"]), str(work["folder"]), "--out", str(out)]) == 0
    found = _detections(out)
    assert all(r["score"] >= 0.25 for r in found)
    for rel in PICKED.values():
        src, drawn = read_image(work["folder"] / rel), read_image(out / rel)
        mine = [r for r in found if r["file_name"] == rel]
        boxes = xywh_to_xyxy(np.array([r["bbox"] for r in mine], float).reshape(-1, 4))
        labels = [NAMES.index(r["category"]) for r in mine]
        assert np.array_equal(drawn, draw_detections(src, boxes, [r["score"] for r in mine], labels, NAMES))
        changed = (drawn != src).any(axis=-1)
        assert changed.any() == bool(mine)  # a negative comes out untouched
        t = line_width(src.shape)
        for x0, y0, x1, y1 in np.round(boxes).astype(int):  # every outline drawn, no interior touched below labels
            assert changed[y1 - 1, x0:x1].all() and changed[y0 + t : y1 - t, x0].all()
            assert not changed[y0 + 14 : y1 - t, x0 + t : x1 - t].any()


def test_classes_overwrite_and_refusals(work, tmp_path, capsys):
    out = tmp_path / "pred"
    argv = ["predict", str(work["model"]), str(work["folder"]), "--out", str(out)]
    assert main([*argv, "--classes", "Smoke"]) == 0
    assert {r["category"] for r in _detections(out)} == {"smoke"}
    capsys.readouterr()
    assert main(argv) == 2  # not empty: refused before any work
    assert (
        capsys.readouterr().err.strip() == f"error: {out}: folder is not empty; choose a new --out or pass --overwrite"
    )
    assert main([*argv, "--overwrite", "--classes", "fire"]) == 0
    assert {r["category"] for r in _detections(out)} == {"fire"}
    assert main([*argv, "--overwrite", "--classes", "flame"]) == 2
    assert "--classes flame: the model's classes are fire, smoke" in capsys.readouterr().err
    assert main(["predict", str(work["model"]), str(work["folder"] / "a"), "--out", str(work["folder"])]) == 2
    assert "holds the input" in capsys.readouterr().err  # an output around the input would overwrite it
    assert main(["predict", str(work["model"]), str(tmp_path / "none"), "--out", str(tmp_path / "o2")]) == 2
    assert "none: no such file or folder" in capsys.readouterr().err
    assert main(["predict", str(tmp_path / "no.onnx"), str(work["folder"]), "--out", str(tmp_path / "o3")]) == 2
    assert "no.onnx: file not found" in capsys.readouterr().err


def test_output_inside_the_input_folder_is_not_read_back(work, tmp_path):
    folder = tmp_path / "photos"
    shutil.copytree(work["folder"], folder)
    argv = ["predict", str(work["model"]), str(folder), "--out", str(folder / "drawn")]
    assert main(argv) == 0 and main([*argv, "--overwrite"]) == 0
    assert not list((folder / "drawn").rglob("drawn"))
    assert {r["file_name"] for r in _detections(folder / "drawn")} == {"a/wide.png", "a/b/big.png"}


def _write_video(path: Path, greys: list[int], width: int, height: int) -> list[np.ndarray]:
    """An mp4v video of flat grey frames; returns its frames as OpenCV decodes them (RGB)."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 10, (width, height))
    for g in greys:
        writer.write(np.full((height, width, 3), g, np.uint8))
    writer.release()
    cap, frames = cv2.VideoCapture(str(path)), []
    while (got := cap.read())[0]:
        frames.append(cv2.cvtColor(got[1], cv2.COLOR_BGR2RGB))
    cap.release()
    return frames


def test_video_frames_get_the_boxes_their_images_get(work, tmp_path, capsys):
    video = tmp_path / "cctv.mp4"
    large = next(i for i in IMAGES if i.name == "large")  # 200x150: letterboxed with padding
    frames = _write_video(video, [240, 240, 60, 240, 60], large.width, large.height)
    grey = int(frames[0][large.height // 2, large.width // 2, 0])  # the grey the oracle will see, as decoded
    fire = Still("fire", large.width, large.height, grey, large.scale, large.pad, large.boxes)
    model = oracle_model(tmp_path / "video.onnx", rows=rows_for([fire], shift=3.0))
    assert main(["predict", str(model), str(video), "--out", str(tmp_path / "v")]) == 0
    assert "5 frames, 3 detections" in capsys.readouterr().out
    got = _detections(tmp_path / "v")
    assert sorted({r["frame"] for r in got}) == [0, 1, 3] and {r["file_name"] for r in got} == {"cctv.mp4"}
    stills = tmp_path / "stills"
    stills.mkdir()
    for k, frame in enumerate(frames):
        cv2.imwrite(str(stills / f"{k}.png"), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    assert main(["predict", str(model), str(stills), "--out", str(tmp_path / "s")]) == 0
    as_images = [{**r, "file_name": "cctv.mp4", "frame": int(r["file_name"][:-4])} for r in _detections(tmp_path / "s")]
    key = lambda r: (r["frame"], -r["score"])  # noqa: E731
    assert sorted(got, key=key) == sorted(as_images, key=key)
    cap = cv2.VideoCapture(str(tmp_path / "v" / "cctv.mp4"))
    assert cap.get(cv2.CAP_PROP_FRAME_COUNT) == 5 and cap.get(cv2.CAP_PROP_FPS) == 10
    drawn = [cv2.cvtColor(cap.read()[1], cv2.COLOR_BGR2RGB).astype(int) for _ in frames]
    x0, y0, x1, y1 = (int(v) for v in xywh_to_xyxy(np.array(got[0]["bbox"])))
    for k, (before, after) in enumerate(zip(frames, drawn)):
        diff = np.abs(after - before).max(axis=-1)
        on_box = diff[y1 - 1, x0 + 4 : x1 - 4].mean()  # the bottom edge of the first fire box
        assert (on_box > 60) == (k in (0, 1, 3))  # drawn on frames with fire only (mp4v is lossy: by margin)
        assert np.median(diff) < 8  # the rest of the frame as it was


def test_unreadable_video_is_a_one_line_error(tmp_path, work, capsys):
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(b"not a video")
    assert main(["predict", str(work["model"]), str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "bad.mp4" in err and len(err.strip().splitlines()) == 1


def test_help_shows_an_example_and_the_drawing_confidence(capsys):
    with pytest.raises(SystemExit):
        main(["predict", "--help"])
    text = capsys.readouterr().out
    assert "example:" in text and "[inference.postprocess.conf=0.25]" in " ".join(text.split())


def test_out_is_required_unless_the_settings_are_printed(work, tmp_path, capsys):
    assert main(["predict", str(work["model"]), str(work["folder"])]) == 2
    assert "--out is required (unless --print-config)" in capsys.readouterr().err
    assert main(["predict", str(work["model"]), str(work["folder"]), "--print-config", "--conf", "0.5"]) == 0
    assert "conf: 0.5" in capsys.readouterr().out and not (tmp_path / "o").exists()

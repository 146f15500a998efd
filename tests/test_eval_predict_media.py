"""Inputs of ``fuzzyfire predict``: which files are read, where drawn copies go, records as score rounds them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from eval import predict_media as M
from ground.data.problems import Problem
from ground.detect.cocoeval import ClassMatch, detection_records
from ground.detect.detections import ImageDetections, Predictions


def _det(boxes, scores, labels) -> ImageDetections:
    return ImageDetections(np.array(boxes, float).reshape(-1, 4), np.array(scores, float), np.array(labels, np.int64))


def test_source_kinds(tmp_path):
    (tmp_path / "a.JPG").write_bytes(b"x")
    (tmp_path / "b.mov").write_bytes(b"x")
    (tmp_path / "c.txt").write_bytes(b"x")
    assert M.source_kind(tmp_path) == "images" and M.source_kind(tmp_path / "a.JPG") == "images"
    assert M.source_kind(tmp_path / "b.mov") == "video"
    with pytest.raises(M.SourceError, match="neither an image"):
        M.source_kind(tmp_path / "c.txt")
    with pytest.raises(M.SourceError, match="no such file"):
        M.source_kind(tmp_path / "d.png")


def test_image_files_are_recursive_sorted_and_leave_out_the_output(tmp_path):
    for rel in ("z.png", "a/b/y.jpg", "a/x.webp", "a/notes.txt", ".hidden/w.png", "out/drawn.png"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes(b"x")
    found = [p.relative_to(tmp_path).as_posix() for p in M.image_files(tmp_path, tmp_path / "out")]
    assert found == ["a/b/y.jpg", "a/x.webp", "z.png"]
    assert M.image_files(tmp_path / "z.png") == [tmp_path / "z.png"]


def test_unreadable_files_are_problems_not_images(tmp_path):
    from factories import write_image

    write_image(tmp_path / "ok.png", 40, 30)
    (tmp_path / "empty.jpg").write_bytes(b"")
    problems: list[Problem] = []
    ds = M.images_dataset(tmp_path, M.image_files(tmp_path), ("fire",), problems)
    assert [(i.file_name, i.width, i.height) for i in ds.images] == [("ok.png", 40, 30)]
    assert [Path(p.path).name for p in problems] == ["empty.jpg"] and problems[0].reason.startswith("skipped: ")


@pytest.mark.parametrize(
    ("name", "written"), [("a/b.jpg", "a/b.jpg"), ("c.PNG", "c.PNG"), ("d.gif", "d.gif.png"), ("e.pgm", "e.pgm.png")]
)
def test_drawn_copies_keep_the_relative_path(tmp_path, name, written):
    assert M.drawn_path(tmp_path, name) == tmp_path / written


def test_keep_classes_and_records_round_as_score_does():
    det = _det([[1.00004, 2, 11.5, 22.25], [5, 5, 9, 9], [0, 0, 3, 3]], [0.9, 0.8123456, 0.5], [0, 1, 0])
    assert M.keep_classes(det, None) is det
    only_smoke = M.keep_classes(det, frozenset({1}))
    assert only_smoke.labels.tolist() == [1] and only_smoke.scores.tolist() == [0.8123456]
    preds = Predictions(("fire", "smoke"), {1: det, 2: _det([], [], [])})
    records = M.to_records(preds, {1: ("cam.mp4", 7), 2: ("cam.mp4", 8)})
    coco = detection_records(preds, ClassMatch({0: 1, 1: 2}, ("fire", "smoke"), (), ()))
    assert [r["bbox"] for r in records] == [r["bbox"] for r in coco] and records[0]["bbox"] == [1.0, 2.0, 10.5, 20.25]
    assert [r["score"] for r in records] == [0.9, 0.81235, 0.5]
    assert [r["category"] for r in records] == ["fire", "smoke", "fire"]
    assert records[0] == {
        "file_name": "cam.mp4",
        "frame": 7,
        **{k: records[0][k] for k in ("category", "bbox", "score")},
    }
    still = M.to_records(preds, {1: ("a.png", None), 2: ("b.png", None)})
    assert "frame" not in still[0] and still[0]["file_name"] == "a.png"


def test_write_image_encodes_by_suffix(tmp_path):
    from ground.image.imageio import read_image

    rgb = np.zeros((10, 12, 3), np.uint8)
    rgb[:, :6] = (250, 10, 10)
    M.write_image(tmp_path / "x" / "a.png", rgb)
    assert np.array_equal(read_image(tmp_path / "x" / "a.png"), rgb)  # lossless, RGB kept
    M.write_image(tmp_path / "b.jpg", rgb)
    assert (tmp_path / "b.jpg").read_bytes()[:3] == b"\xff\xd8\xff"

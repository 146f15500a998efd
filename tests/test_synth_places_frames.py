"""Labelled frames: their fire boxes are read from any dataset layout, follow a crop by the keep rule, and a
frame dataset is identified by content."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from factories import write_frames

from synth.places.frames import MIN_KEPT, crop_boxes, frame_classes, frame_fingerprints, load_frames


def test_frames_keep_only_their_fire_boxes_in_pixels(tmp_path: Path) -> None:
    frames = load_frames([write_frames(tmp_path)])
    assert len(frames) == 3 and all(p.is_file() for p in frames)
    assert all(set(labels) == {"fire"} for labels in frames.values())  # smoke is not a fire-only pool's label
    assert sorted(len(labels["fire"]) for labels in frames.values()) == [1, 2, 3]
    assert all(b[1:] == (50.0, 20.0, 30.0) for labels in frames.values() for b in labels["fire"])


def test_a_pool_that_boxes_smoke_keeps_its_frames_smoke(tmp_path: Path) -> None:
    root = write_frames(tmp_path)
    both = load_frames([root], classes=frame_classes(True))
    assert all(labels["smoke"] == ((2.0, 2.0, 30.0, 20.0),) for labels in both.values())
    assert [labels["fire"] for labels in both.values()] == [labels["fire"] for labels in load_frames([root]).values()]
    assert frame_fingerprints([root], frame_classes(True)) != frame_fingerprints([root])  # its smoke is content


def test_an_unreadable_frame_is_skipped_and_named(tmp_path: Path) -> None:
    root = write_frames(tmp_path)
    broken = next(root.rglob("f1.png"))
    broken.write_bytes(broken.read_bytes()[:200])  # a truncated PNG
    problems: list = []
    frames = load_frames([root], problems)
    assert len(frames) == 2 and broken not in frames
    assert [(Path(p.path).name, p.reason.split(":")[0]) for p in problems] == [("f1.png", "unreadable image")]
    assert "truncated PNG" in problems[0].reason


def test_a_frame_dataset_is_identified_by_content_not_by_place(tmp_path: Path) -> None:
    a = write_frames(tmp_path / "a")
    b = tmp_path / "b"
    shutil.copytree(a, b)
    assert frame_fingerprints([a]) == frame_fingerprints([b])
    assert frame_fingerprints([a]) != frame_fingerprints([write_frames(tmp_path / "c", n=2)])


def test_a_box_follows_the_crop_and_scale() -> None:
    # crop [10, 20, 50, 40] of the photo shown at 100 x 80: scale 2 both ways
    assert crop_boxes([(20.0, 30.0, 10.0, 5.0)], [10, 20, 50, 40], 100, 80) == [[20.0, 20.0, 20.0, 10.0]]
    assert crop_boxes([(0.0, 0.0, 5.0, 5.0)], [10, 20, 50, 40], 100, 80) == []  # outside
    clipped = crop_boxes([(0.0, 30.0, 20.0, 10.0)], [10, 20, 50, 40], 100, 80)  # half of it inside
    assert clipped == [[0.0, 20.0, 20.0, 20.0]]


@pytest.mark.parametrize("seed", range(20))
def test_kept_boxes_lie_in_the_image_and_keep_enough_of_themselves(seed: int) -> None:
    rng = np.random.default_rng(seed)
    boxes = [tuple(float(v) for v in (*rng.uniform(-20, 200, 2), *rng.uniform(1, 80, 2))) for _ in range(8)]
    crop = [int(rng.integers(0, 60)), int(rng.integers(0, 40)), int(rng.integers(40, 140)), int(rng.integers(30, 100))]
    for x, y, w, h in crop_boxes(boxes, crop, 64, 48):
        assert 0 <= x and 0 <= y and x + w <= 64.01 and y + h <= 48.01 and min(w, h) >= 2
    scale = 64 * 48 / (crop[2] * crop[3])
    for box in boxes:  # each kept box keeps MIN_KEPT of its area at least
        for _, _, w, h in crop_boxes([box], crop, 64, 48):
            assert w * h >= MIN_KEPT * scale * box[2] * box[3] - 1e-6


def test_a_frame_without_fire_stays_a_frame(tmp_path: Path) -> None:
    from factories import write_yolo_dataset

    write_yolo_dataset(tmp_path / "ds")  # a: fire + smoke, b: fire, c: no box, d: no label file
    only_smoke = tmp_path / "ds" / "train" / "labels" / "b.txt"
    only_smoke.write_text("1 0.125 0.75 0.25 0.1\n")  # b now holds smoke alone
    frames = {p.stem: labels["fire"] for p, labels in load_frames([tmp_path / "ds"]).items()}
    assert sorted(frames) == ["a", "b", "c", "d"] and frames["b"] == () and len(frames["a"]) == 1

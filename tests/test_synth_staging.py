"""Staging of synthetic images: instance maps and mask boxes are exact, a staged image counts only once its record
is written (resume), and finishing writes the dataset, its masks and a contact sheet and removes the staging."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from ground.data.formats.registry import read_dataset
from synth.staging import Staging, boxes_from_masks, finish, instance_map, staging_dir


def _mask(shape: tuple[int, int], x: int, y: int, w: int, h: int) -> np.ndarray:
    m = np.zeros(shape, bool)
    m[y : y + h, x : x + w] = True
    return m


def test_instance_map_and_mask_boxes_are_exact() -> None:
    masks = [_mask((40, 60), 2, 3, 10, 5), _mask((40, 60), 30, 20, 2, 9), _mask((40, 60), 40, 1, 8, 8)]
    labels = instance_map((40, 60), masks)
    assert labels.dtype == np.uint8 and set(np.unique(labels)) == {0, 1, 2, 3}
    assert all(((labels == k + 1) == m).all() for k, m in enumerate(masks))
    kept, boxes, index = boxes_from_masks(masks, min_box_px=3)
    assert index == [0, 2] and boxes == [[2.0, 3.0, 10.0, 5.0], [40.0, 1.0, 8.0, 8.0]] and kept[1] is masks[2]
    with pytest.raises(ValueError, match="255"):
        instance_map((2, 2), [np.zeros((2, 2), bool)] * 256)


def _stage(staging: Staging, i: int) -> list[list[float]]:
    rng = np.random.default_rng(i)
    image = rng.integers(0, 255, (48, 64, 3), dtype=np.uint8)
    masks = [_mask((48, 64), 4 + i, 5, 12, 9)]
    _, boxes, _ = boxes_from_masks(masks, 1)
    staging.save(i, image, masks, {"width": 64, "height": 48, "boxes": boxes, "meta": {"i": i}})
    return boxes


def test_a_staged_image_is_done_once_its_record_is_written(tmp_path: Path) -> None:
    out = tmp_path / "pool"
    staging = Staging(out)
    assert staging.root == staging_dir(out) and staging.root.name == ".pool.parts" and not staging.done(0)
    boxes = _stage(staging, 0)
    assert staging.done(0) and staging.load(0)["boxes"] == boxes and not staging.done(1)
    assert not list(staging.root.glob("records/*.tmp"))
    again = Staging(out)  # a resumed run sees what was staged
    assert again.done(0) and not again.done(1)


def test_finish_writes_the_dataset_masks_and_sheet_and_removes_the_staging(tmp_path: Path) -> None:
    out = tmp_path / "pool"
    staging = Staging(out)
    staged = [_stage(staging, i) for i in range(3)]
    result = finish(staging, out, 3, "synth:test", "synth test", {"n": 3}, smoke=False, overwrite=False)
    assert not staging.root.exists() and (out / result.files["contact_sheet"]).is_file()
    ds = read_dataset(out, "coco").dataset
    by_image = ds.annotations_by_image()
    for img, boxes in zip(ds.images, staged):
        assert [list(a.bbox) for a in by_image[img.id]] == boxes and img.source == "synth:test"
        mask = cv2.imread(str(out / "masks" / Path(img.file_name).relative_to("images").with_suffix(".png")), 0)
        x, y, w, h = (int(v) for v in boxes[0])
        assert (mask[y : y + h, x : x + w] == 1).all() and mask.sum() == w * h
    manifest = json.loads((out / "manifest.json").read_text())
    assert [m["i"] for m in manifest["args"]["per_image"]] == [0, 1, 2]

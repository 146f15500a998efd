"""Validation post-processing and COCO AP: AP = 1 on ground truth fed back, class-aware NMS."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from curate.dataset import DatasetBuilder
from train.validate import coco_ap, fitness, postprocess


def _pred(rows: list[list[float]]) -> np.ndarray:
    return np.asarray(rows, dtype=np.float32)


def test_postprocess_scores_nms_and_classes() -> None:
    pred = _pred(
        [
            [20, 20, 10, 10, 0.9, 0.9, 0.1],  # fire 0.81
            [21, 20, 10, 10, 0.8, 0.9, 0.1],  # overlaps the first, same class: suppressed
            [21, 20, 10, 10, 0.8, 0.1, 0.9],  # same place, other class: kept
            [60, 60, 8, 8, 0.0005, 1.0, 1.0],  # below conf
        ]
    )
    boxes, scores, labels = postprocess(pred, conf=0.001, iou=0.6, max_det=10)
    pairs = [(int(lbl), round(float(s), 3)) for lbl, s in zip(labels, scores)]
    assert pairs == [(0, 0.81), (1, 0.72)]  # best first; each class suppresses only its own boxes
    assert np.allclose(boxes[0], [15, 15, 25, 25]) and np.allclose(boxes[1], [16, 15, 26, 25])
    assert len(postprocess(pred, 0.001, 0.6, max_det=1)[0]) == 1


def test_ap_is_one_on_ground_truth(tmp_path: Path) -> None:
    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    i1 = b.add_image("a.jpg", 100, 80)
    b.add_box(i1, "fire", (10, 10, 30, 20))
    b.add_box(i1, "smoke", (50, 30, 20, 40))
    b.add_image("negative.jpg", 100, 80)
    ds = b.build()
    dets = [
        {"image_id": a.image_id, "category_id": a.category_id, "bbox": list(a.bbox), "score": 0.9}
        for a in ds.annotations
    ]
    metrics = coco_ap(ds, dets)
    assert metrics == {"AP": pytest.approx(1.0), "AP50": pytest.approx(1.0)}
    assert fitness(metrics) == pytest.approx(1.0)
    shifted = [{**d, "bbox": [d["bbox"][0] + 8, *d["bbox"][1:]]} for d in dets]
    worse = coco_ap(ds, shifted)
    assert worse["AP"] < 1.0 and coco_ap(ds, []) == {"AP": 0.0, "AP50": 0.0}

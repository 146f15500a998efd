"""NMS against a brute-force reference, class awareness, limits and post-processing."""

from __future__ import annotations

import numpy as np
import pytest

from curate.boxes import nms_xyxy
from eval.nms import batched_nms_xyxy, postprocess


def _iou(a, b) -> float:
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = w * h
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def brute_force_nms(boxes, scores, labels, thr) -> list[int]:
    """Plain-Python greedy NMS: visit boxes best first, keep one unless a kept box of its class overlaps."""
    kept: list[int] = []
    for i in sorted(range(len(scores)), key=lambda i: (-scores[i], i)):
        if all(labels[j] != labels[i] or _iou(boxes[i], boxes[j]) <= thr for j in kept):
            kept.append(i)
    return kept


def random_boxes(rng: np.random.Generator, n: int):
    xy = rng.uniform(0, 100, (n, 2))
    wh = rng.uniform(2, 40, (n, 2))
    return np.concatenate([xy, xy + wh], axis=1), rng.uniform(0, 1, n), rng.integers(0, 3, n)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("thr", [0.3, 0.6])
def test_matches_brute_force(seed, thr):
    boxes, scores, labels = random_boxes(np.random.default_rng(seed), 300)
    assert batched_nms_xyxy(boxes, scores, labels, thr).tolist() == brute_force_nms(boxes, scores, labels, thr)
    single = np.zeros_like(labels)
    assert nms_xyxy(boxes, scores, thr).tolist() == brute_force_nms(boxes, scores, single, thr)


def test_class_aware_and_max_keep():
    boxes = np.array([[0, 0, 10, 10], [0, 0, 10, 10], [1, 1, 10, 10], [50, 50, 60, 60]], float)
    scores = np.array([0.9, 0.8, 0.7, 0.6])
    labels = np.array([0, 1, 0, 0])
    assert batched_nms_xyxy(boxes, scores, labels, 0.5).tolist() == [0, 1, 3]
    assert batched_nms_xyxy(boxes, scores, labels, 0.5, max_keep=2).tolist() == [0, 1]
    assert batched_nms_xyxy(boxes[:0], scores[:0], labels[:0], 0.5).tolist() == []


def test_postprocess_multi_label_and_thresholds():
    cxcywh = np.array([[10, 10, 4, 4], [30, 30, 4, 4]], np.float32)
    scores = np.array([[0.9, 0.5], [0.0005, 0.002]], np.float32)
    det = postprocess(cxcywh, scores, conf=0.001)
    assert det.labels.tolist() == [0, 1, 1] and det.scores.tolist() == pytest.approx([0.9, 0.5, 0.002])
    np.testing.assert_allclose(det.boxes[0], [8, 8, 12, 12])
    best = postprocess(cxcywh, scores, conf=0.001, multi_label=False)
    assert best.labels.tolist() == [0, 1] and len(postprocess(cxcywh, scores, conf=0.95)) == 0
    assert len(postprocess(cxcywh[:0], scores[:0])) == 0

"""Greedy and class-aware NMS against a plain-Python reference (the boxes themselves: test_ground_data_boxes.py)."""

import numpy as np
import pytest

from ground.detect import nms


def test_nms_xyxy_keeps_best_and_disjoint():
    b = np.array([[0, 0, 10, 10], [1, 1, 11, 11], [20, 20, 30, 30], [0, 0, 10, 10]], dtype=float)
    s = np.array([0.5, 0.9, 0.3, 0.9])
    assert nms.nms_xyxy(b, s, 0.5).tolist() == [1, 2]  # 3 ties with 1 (lower index first), overlaps it
    assert nms.nms_xyxy(b, s, 0.99).tolist() == [1, 3, 2]  # 0 duplicates 3 exactly (IoU 1)
    assert nms.nms_xyxy(b, s, 0.5, max_keep=1).tolist() == [1]
    assert nms.nms_xyxy(np.zeros((0, 4)), np.zeros(0), 0.5).tolist() == []


def _iou(a, b) -> float:
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = w * h
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def brute_force_nms(bxs, scores, labels, thr) -> list[int]:
    """Plain-Python greedy NMS: visit boxes best first, keep one unless a kept box of its class overlaps."""
    kept: list[int] = []
    for i in sorted(range(len(scores)), key=lambda i: (-scores[i], i)):
        if all(labels[j] != labels[i] or _iou(bxs[i], bxs[j]) <= thr for j in kept):
            kept.append(i)
    return kept


def random_boxes(rng: np.random.Generator, n: int):
    xy = rng.uniform(0, 100, (n, 2))
    wh = rng.uniform(2, 40, (n, 2))
    return np.concatenate([xy, xy + wh], axis=1), rng.uniform(0, 1, n), rng.integers(0, 3, n)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("thr", [0.3, 0.6])
def test_nms_matches_brute_force(seed, thr):
    bxs, scores, labels = random_boxes(np.random.default_rng(seed), 300)
    assert nms.batched_nms_xyxy(bxs, scores, labels, thr).tolist() == brute_force_nms(bxs, scores, labels, thr)
    single = np.zeros_like(labels)
    assert nms.nms_xyxy(bxs, scores, thr).tolist() == brute_force_nms(bxs, scores, single, thr)


def test_batched_nms_class_aware_and_max_keep():
    bxs = np.array([[0, 0, 10, 10], [0, 0, 10, 10], [1, 1, 10, 10], [50, 50, 60, 60]], float)
    scores = np.array([0.9, 0.8, 0.7, 0.6])
    labels = np.array([0, 1, 0, 0])
    assert nms.batched_nms_xyxy(bxs, scores, labels, 0.5).tolist() == [0, 1, 3]
    assert nms.batched_nms_xyxy(bxs, scores, labels, 0.5, max_keep=2).tolist() == [0, 1]
    assert nms.batched_nms_xyxy(bxs[:0], scores[:0], labels[:0], 0.5).tolist() == []


@pytest.mark.parametrize("max_keep", [1, 7, 300, 5000])
def test_nms_in_blocks_equals_one_greedy_pass(max_keep):
    bxs, scores, _ = random_boxes(np.random.default_rng(11), 6000)  # > one block of candidates
    scores[::3] = 0.5  # many ties: the order must still be score, then index
    full = nms.nms_xyxy(bxs, scores, 0.5)  # no max_keep: a single greedy pass over every box
    assert nms.nms_xyxy(bxs, scores, 0.5, max_keep).tolist() == full[:max_keep].tolist()


def test_nms_counts_two_empty_boxes_as_duplicates_and_keeps_an_empty_box_beside_a_real_one():
    bxs = np.array([[5, 5, 5, 5], [5, 5, 5, 5], [0, 0, 10, 10]], float)
    assert nms.nms_xyxy(bxs, np.array([0.9, 0.8, 0.7]), 0.5).tolist() == [0, 2]

"""Anchor fit metric and k-means anchors."""

from __future__ import annotations

import numpy as np

from ground.data.dataset import DatasetBuilder
from train.anchors import anchor_fit, check_anchors, kmeans_anchors, label_sizes
from train.config import DEFAULT_ANCHORS


def test_fit_metric_by_hand() -> None:
    wh = np.array([[10.0, 10.0], [100.0, 10.0]])
    fit = anchor_fit(wh, np.array([[10.0, 10.0]]), anchor_t=4.0)
    assert fit["bpr"] == 0.5 and fit["fitness"] == 0.5  # second label: ratio 0.1 < 1/4


def test_label_sizes_follow_the_letterbox(tmp_path) -> None:
    b = DatasetBuilder(tmp_path, ["fire"])
    image = b.add_image("a.jpg", 640, 320)
    b.add_box(image, "fire", (0, 0, 64, 32))
    b.add_box(image, "fire", (0, 0, 8, 8), iscrowd=1)
    assert np.allclose(label_sizes(b.build(), 320), [[32.0, 16.0]])


def test_kmeans_recovers_clusters_and_check_refits() -> None:
    rng = np.random.default_rng(0)
    centres = np.array([[4, 40], [30, 3], [60, 60], [150, 20], [20, 150], [8, 8], [200, 200], [90, 250], [250, 90]])
    wh = np.concatenate([c * rng.uniform(0.9, 1.1, size=(50, 2)) for c in centres])
    fitted = kmeans_anchors(wh, 9, np.random.default_rng(1))
    assert anchor_fit(wh, fitted)["bpr"] == 1.0
    assert np.all(np.diff(fitted.prod(axis=1)) >= 0)  # sorted by area
    anchors, report = check_anchors(wh, DEFAULT_ANCHORS, np.random.default_rng(1))
    assert report["bpr_before"] < 0.98 and report["refitted"] == 1.0 and report["bpr"] == 1.0
    assert anchors.shape == (3, 3, 2)
    same = np.asarray(DEFAULT_ANCHORS, dtype=float).reshape(-1, 2)
    kept, report = check_anchors(same * 1.05, DEFAULT_ANCHORS, np.random.default_rng(1))
    assert report["refitted"] == 0.0 and np.array_equal(kept, np.asarray(DEFAULT_ANCHORS, dtype=float))

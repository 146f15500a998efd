"""Training-time validation: the shared post-processing and COCO evaluation, AP = 1 on ground truth fed back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from ground.data.dataset import DatasetBuilder, ImageRecord
from ground.detect.detections import PostprocessConfig
from train.validate import evaluate, fitness


class _FixedDetector(torch.nn.Module):
    """Returns a fixed decoded output (B, N, 5 + C) whatever the input (stands in for a Detector)."""

    def __init__(self, rows: np.ndarray) -> None:
        super().__init__()
        self.rows = torch.from_numpy(rows)

    def predict_frozen(self, feats):
        return self.rows.expand(feats[0].shape[0], *self.rows.shape).clone()


class _Inputs:
    """One batch of one record (what ValidationInputs yields)."""

    def __init__(self, record: ImageRecord) -> None:
        self.record = record

    def __iter__(self):
        yield [self.record], (torch.zeros(1, 3, 64, 64),)


def _dataset(tmp_path: Path):
    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    image = b.add_image("a.jpg", 128, 64)  # letterboxed to 64 x 64: scale 0.5, 16 px bands above and below
    b.add_box(image, "fire", (20, 20, 40, 20))
    b.add_box(image, "smoke", (80, 10, 30, 40))
    return b.build()


def test_ground_truth_fed_back_scores_one(tmp_path: Path) -> None:
    ds = _dataset(tmp_path)
    # the two boxes in letterboxed input pixels (cx, cy, w, h), obj, p_fire, p_smoke
    rows = np.array([[20, 31, 20, 10, 0.9, 1.0, 0.0], [47.5, 31, 15, 20, 0.9, 0.0, 1.0]], np.float32)
    metrics = evaluate(_FixedDetector(rows), _Inputs(ds.images[0]), ds, ["fire", "smoke"], 64, PostprocessConfig())
    assert metrics["AP"] == pytest.approx(1.0) and metrics["AP50"] == pytest.approx(1.0)
    assert metrics["fitness"] == pytest.approx(1.0) and metrics["detections"] == 2.0
    shifted = rows + np.array([[6, 0, 0, 0, 0, 0, 0]], np.float32)
    worse = evaluate(_FixedDetector(shifted), _Inputs(ds.images[0]), ds, ["fire", "smoke"], 64, PostprocessConfig())
    assert worse["AP"] < 1.0


def test_no_detection_scores_zero(tmp_path: Path) -> None:
    ds = _dataset(tmp_path)
    rows = np.array([[20, 31, 20, 10, 0.0, 1.0, 0.0]], np.float32)  # below every threshold
    metrics = evaluate(_FixedDetector(rows), _Inputs(ds.images[0]), ds, ["fire", "smoke"], 64, PostprocessConfig())
    assert metrics == {"AP": 0.0, "AP50": 0.0, "fitness": 0.0, "detections": 0.0}


def test_fitness_weights() -> None:
    assert fitness({"AP": 0.5, "AP50": 1.0}) == pytest.approx(0.55)

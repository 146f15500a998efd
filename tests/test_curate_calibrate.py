"""Threshold calibration: augmentations are new arrays, the precision rule, and a threshold that separates
planted copies from distinct scenes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from curate_helpers import save, scene, use_session_cache

from curate.calibrate import AUGMENTATIONS, augment, calibrate_threshold, centre_crop, hflip, threshold_at_precision
from curate.embed import load_embedder


@pytest.mark.parametrize("kind", sorted(AUGMENTATIONS))
def test_augmentations_return_new_images(kind: str) -> None:
    img = scene(3)
    before = img.copy()
    out = augment(img, kind, np.random.default_rng(0))
    assert out.dtype == np.uint8 and out.ndim == 3 and out.shape[2] == 3
    assert np.array_equal(img, before)  # input untouched
    again = augment(img, kind, np.random.default_rng(0))
    assert np.array_equal(out, again)  # seeded


def test_hflip_and_centre_crop_are_exact() -> None:
    img = scene(2, size=(41, 30))  # (30, 41, 3): odd width
    assert np.array_equal(hflip(hflip(img)), img) and np.array_equal(hflip(img)[:, 0], img[:, -1])
    crop = centre_crop(img, 10)  # 30 // 10 = 3 rows, 41 // 10 = 4 columns off each side
    assert crop.shape == (24, 33, 3) and np.array_equal(crop, img[3:27, 4:37]) and crop.flags.c_contiguous


def test_unknown_augmentation() -> None:
    with pytest.raises(ValueError, match="unknown augmentation"):
        augment(scene(1), "sepia", np.random.default_rng(0))


def test_threshold_at_precision_rule() -> None:
    pos = np.array([0.1, 0.2, 0.3, 0.9], np.float32)
    neg = np.array([0.5, 0.6, 0.7, 0.8] * 25, np.float32)
    t, p, r = threshold_at_precision(pos, neg, 0.99)
    assert 0.3 < t < 0.5 and p == 1.0 and r == 0.75
    t, p, r = threshold_at_precision(pos, neg, 0.5)
    assert t > 0.9 and r == 1.0
    assert threshold_at_precision(np.zeros(0, np.float32), neg, 0.9) == (0.0, 1.0, 0.0)


def test_calibration_on_generated_scenes(tmp_path: Path, tmp_path_factory: pytest.TempPathFactory) -> None:
    use_session_cache(tmp_path_factory)
    paths = [save(scene(200 + i), tmp_path / f"c{i}.jpg") for i in range(16)]
    calib = calibrate_threshold(paths, load_embedder(), precision=0.99, seed=0, sample=16)
    assert calib.images == 16 and calib.positives == 16 * len(AUGMENTATIONS) and calib.negatives == 16 * 15 // 2
    assert 0.2 < calib.threshold < 1.0 and calib.precision >= 0.99 and calib.recall > 0.5
    with pytest.raises(ValueError):
        calibrate_threshold(paths[:1], load_embedder())
    with pytest.raises(ValueError):
        calibrate_threshold(paths, load_embedder(), precision=1.5)

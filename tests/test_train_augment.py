"""Augmentations keep boxes on the pixels: a painted rectangle is still framed by its box."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from train.augment import PAD_VALUE, Sample, augment, hflip, hsv_jitter, letterbox, mosaic_canvas, resize_longest
from train.config import AugmentConfig

PAINT = (255, 0, 0)  # pure red on a grey image survives interpolation as "red dominant" pixels


def _painted(seed: int, h: int = 96, w: int = 128) -> Sample:
    rng = np.random.default_rng(seed)
    image = np.full((h, w, 3), 60, dtype=np.uint8)
    x0, y0 = int(rng.integers(5, w // 2)), int(rng.integers(5, h // 2))
    x1, y1 = x0 + int(rng.integers(16, w // 2 - 4)), y0 + int(rng.integers(16, h // 2 - 4))
    image[y0:y1, x0:x1] = PAINT
    return Sample(image, np.array([[x0, y0, x1, y1]], dtype=np.float64), np.array([0]))


def _paint_box(image: np.ndarray) -> np.ndarray | None:
    """xyxy of the pixels where red dominates (pixel edges), or None."""
    r, g, b = (image[..., i].astype(int) for i in range(3))
    ys, xs = np.nonzero((r - np.maximum(g, b)) > 60)
    if not len(xs):
        return None
    return np.array([xs.min(), ys.min(), xs.max() + 1, ys.max() + 1], dtype=np.float64)


def _assert_frames(sample: Sample, tol: float = 2.0) -> None:
    found = _paint_box(sample.image)
    if found is None:
        assert len(sample.boxes) == 0
        return
    assert len(sample.boxes) >= 1
    errors = np.abs(sample.boxes - found).max(axis=1)
    assert errors.min() <= tol, (sample.boxes, found)


def test_letterbox_and_resize_keep_the_box() -> None:
    s = _painted(0)
    _assert_frames(resize_longest(s, 64))
    out = letterbox(s, 160)
    assert out.image.shape == (160, 160, 3) and out.image[0, 0, 0] == PAD_VALUE
    _assert_frames(out)


def test_flip_mirrors_the_box() -> None:
    s = _painted(1)
    _assert_frames(hflip(s), tol=0.0)
    assert np.array_equal(hflip(hflip(s)).image, s.image)


def test_mosaic_keeps_every_box_on_its_paint() -> None:
    samples = [_painted(i, 48, 64) for i in range(4)]  # already longest side 64: exact pixels
    canvas = mosaic_canvas(samples, 64, np.random.default_rng(3))
    assert canvas.image.shape == (128, 128, 3)
    for box in canvas.boxes:
        x0, y0, x1, y1 = (int(round(v)) for v in box)
        if x1 - x0 > 0 and y1 - y0 > 0:
            assert np.all(canvas.image[y0:y1, x0:x1] == PAINT)


def _component_box(image: np.ndarray, x: int, y: int) -> np.ndarray:
    """xyxy (pixel edges) of the red connected component through pixel (x, y)."""
    r, g, b = (image[..., i].astype(int) for i in range(3))
    mask = ((r - np.maximum(g, b)) > 60).astype(np.uint8)
    assert mask[y, x], "box centre is not on paint"
    _, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=4)
    left, top, w, h, _ = stats[labels[y, x]]
    return np.array([left, top, left + w, top + h], dtype=np.float64)


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("mosaic", [0.0, 1.0])
def test_full_augmentation_keeps_each_box_on_its_paint(seed: int, mosaic: float) -> None:
    cfg = AugmentConfig(mosaic=mosaic, hsv_h=0.0, hsv_s=0.0, hsv_v=0.0)  # keep the paint red
    pool = [resize_longest(_painted(100 + seed * 4 + k), 96) for k in range(4)]
    out = augment(lambda i: pool[i], 0, 4, 96, cfg, np.random.default_rng(seed))
    assert out.image.shape == (96, 96, 3) and out.image.dtype == np.uint8
    assert len(out.boxes) == len(out.classes)
    for box in out.boxes:
        cx, cy = int((box[0] + box[2]) / 2), int((box[1] + box[3]) / 2)
        np.testing.assert_allclose(box, _component_box(out.image, cx, cy), atol=2.0)


def test_boxes_survive_ordinary_augmentation() -> None:
    cfg = AugmentConfig(mosaic=0.0)
    pool = [resize_longest(_painted(k), 96) for k in range(10)]
    kept = [len(augment(lambda i: pool[i], k, 10, 96, cfg, np.random.default_rng(k)).boxes) for k in range(10)]
    assert sum(kept) >= 8  # translate 0.1 / scale 0.5 rarely pushes a central box out


def test_augment_is_deterministic_and_does_not_touch_inputs() -> None:
    pool = [_painted(k) for k in range(4)]
    before = [p.image.copy() for p in pool]
    cfg = AugmentConfig()
    a = augment(lambda i: pool[i], 1, 4, 64, cfg, np.random.default_rng(9))
    b = augment(lambda i: pool[i], 1, 4, 64, cfg, np.random.default_rng(9))
    assert np.array_equal(a.image, b.image) and np.array_equal(a.boxes, b.boxes)
    assert all(np.array_equal(p.image, q) for p, q in zip(pool, before))


def test_hsv_jitter_changes_colour_not_shape() -> None:
    image = _painted(2).image
    out = hsv_jitter(image, (0.015, 0.7, 0.4), np.random.default_rng(0))
    assert out.shape == image.shape and not np.array_equal(out, image)
    assert np.array_equal(hsv_jitter(image, (0, 0, 0), np.random.default_rng(0)), image)


def test_mosaic_partners_come_from_the_given_indices_and_a_full_range_changes_nothing() -> None:
    pool = [resize_longest(_painted(k), 64) for k in range(6)]
    cfg = AugmentConfig(mosaic=1.0)
    for seed in range(5):
        loaded: list[int] = []

        def load(i: int, loaded: list[int] = loaded) -> Sample:
            loaded.append(i)
            return pool[i]

        out = augment(load, 0, np.array([0, 4, 5]), 64, cfg, np.random.default_rng(seed))
        assert loaded[0] == 0 and set(loaded[1:]) <= {0, 4, 5} and len(loaded) == 4
        every = augment(lambda i: pool[i], 0, np.arange(6), 64, cfg, np.random.default_rng(seed))
        counted = augment(lambda i: pool[i], 0, 6, 64, cfg, np.random.default_rng(seed))
        assert np.array_equal(every.image, counted.image) and np.array_equal(every.boxes, counted.boxes)
        assert out.image.shape == (64, 64, 3)

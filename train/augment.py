"""Training augmentations (YOLOv5's published recipe; our code): mosaic, random affine (translate, scale),
HSV jitter, horizontal flip, letterbox.

Every function takes ``rng: np.random.Generator`` where it draws, returns new arrays and never modifies its
inputs. Images are (H, W, 3) uint8 RGB; boxes are (N, 4) float64 xyxy pixels of the image they travel with;
classes are (N,) int64. Geometry is expressed as 3x3 matrices applied to pixels (``cv2.warpAffine``) and to
boxes (:func:`ground.data.boxes.affine_xyxy`) alike, so boxes always stay consistent with pixels.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.data import boxes as bx
from train.config import AugmentConfig

#: Padding grey of YOLO-family detectors (114 of 255).
PAD_VALUE = 114

Image = NDArray[np.uint8]


@dataclass(frozen=True)
class Sample:
    """One training image and its labels: ``boxes`` (N, 4) xyxy pixels of ``image``, ``classes`` (N,)."""

    image: Image
    boxes: NDArray[np.float64]
    classes: NDArray[np.int64]


def resize_longest(sample: Sample, size: int) -> Sample:
    """Resize so the longest side is ``size`` (area filter when shrinking); boxes scaled with the pixels."""
    h, w = sample.image.shape[:2]
    new_w, new_h, _, _ = bx.letterbox_params(w, h, size, size)
    if (new_w, new_h) == (w, h):
        return sample
    interp = cv2.INTER_AREA if new_w < w else cv2.INTER_LINEAR
    image = cv2.resize(sample.image, (new_w, new_h), interpolation=interp)
    m = np.diag([new_w / w, new_h / h, 1.0])
    return Sample(image, bx.affine_xyxy(sample.boxes, m), sample.classes.copy())


def letterbox(sample: Sample, size: int, pad_value: int = PAD_VALUE) -> Sample:
    """Fit into ``size`` x ``size`` at one aspect-preserving scale, centred on a grey canvas."""
    h, w = sample.image.shape[:2]
    new_w, new_h, pad_x, pad_y = bx.letterbox_params(w, h, size, size)
    m = np.array([[new_w / w, 0, pad_x], [0, new_h / h, pad_y], [0, 0, 1]], dtype=np.float64)
    return warp(sample, m, (size, size), pad_value)


def warp(sample: Sample, matrix: NDArray[np.float64], out_hw: tuple[int, int], pad_value: int = PAD_VALUE) -> Sample:
    """Apply the 3x3 affine ``matrix`` (input pixels -> output pixels) to the image and the boxes.

    Boxes become the enclosing box of their transformed corners, clipped to the output; nothing is dropped
    here (see :func:`filter_boxes`).
    """
    out_h, out_w = out_hw
    image = cv2.warpAffine(
        sample.image, matrix[:2], (out_w, out_h), flags=cv2.INTER_LINEAR, borderValue=(pad_value,) * 3
    )
    moved = bx.clip_xyxy(bx.affine_xyxy(sample.boxes, matrix), out_w, out_h).reshape(-1, 4)
    return Sample(image, moved, sample.classes.copy())


def random_affine_matrix(
    in_hw: tuple[int, int], out_size: int, translate: float, scale: float, rng: np.random.Generator
) -> NDArray[np.float64]:
    """3x3 matrix: centre the input on the origin, scale by U(1 - scale, 1 + scale), move the centre to
    U(0.5 - translate, 0.5 + translate) * ``out_size`` on each axis."""
    h, w = in_hw
    centre = np.array([[1, 0, -w / 2], [0, 1, -h / 2], [0, 0, 1]], dtype=np.float64)
    s = rng.uniform(1 - scale, 1 + scale)
    tx, ty = rng.uniform(0.5 - translate, 0.5 + translate, size=2) * out_size
    move = np.array([[s, 0, tx], [0, s, ty], [0, 0, 1]], dtype=np.float64)
    return move @ centre


def filter_boxes(
    before: NDArray[np.float64], after: Sample, gain: float, min_px: float, min_area_ratio: float
) -> Sample:
    """Drop boxes narrower/lower than ``min_px``, keeping under ``min_area_ratio`` of their area (``before``
    scaled by ``gain``), or with an aspect ratio above 20 (YOLOv5's candidate rule)."""
    w = after.boxes[:, 2] - after.boxes[:, 0]
    h = after.boxes[:, 3] - after.boxes[:, 1]
    area_before = (before[:, 2] - before[:, 0]) * (before[:, 3] - before[:, 1]) * gain**2
    aspect = np.maximum(w / (h + 1e-9), h / (w + 1e-9))
    keep = (w > min_px) & (h > min_px) & (w * h / (area_before + 1e-9) > min_area_ratio) & (aspect < 20)
    return Sample(after.image, after.boxes[keep], after.classes[keep])


def mosaic_canvas(samples: list[Sample], size: int, rng: np.random.Generator) -> Sample:
    """Four samples (longest side ``size``) around a random centre in [0.5, 1.5] * ``size`` of a
    2 ``size`` x 2 ``size`` grey canvas: top-left, top-right, bottom-left, bottom-right."""
    assert len(samples) == 4
    canvas = np.full((2 * size, 2 * size, 3), PAD_VALUE, dtype=np.uint8)
    xc, yc = (int(v) for v in rng.uniform(0.5 * size, 1.5 * size, size=2))
    all_boxes, all_classes = [], []
    for k, s in enumerate(samples):
        h, w = s.image.shape[:2]
        x0 = xc - w if k in (0, 2) else xc  # where the image's top-left corner lands on the canvas
        y0 = yc - h if k in (0, 1) else yc
        cx0, cy0 = max(x0, 0), max(y0, 0)
        cx1, cy1 = min(x0 + w, 2 * size), min(y0 + h, 2 * size)
        canvas[cy0:cy1, cx0:cx1] = s.image[cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0]
        shift = np.array([[1, 0, x0], [0, 1, y0], [0, 0, 1]], dtype=np.float64)
        moved = bx.affine_xyxy(s.boxes, shift).reshape(-1, 4)
        # Clip to the pasted region: parts of a box outside it are not in the pixels.
        moved[:, 0::2] = np.clip(moved[:, 0::2], cx0, cx1)
        moved[:, 1::2] = np.clip(moved[:, 1::2], cy0, cy1)
        all_boxes.append(moved)
        all_classes.append(s.classes)
    return Sample(canvas, np.concatenate(all_boxes), np.concatenate(all_classes))


def hsv_jitter(image: Image, gains: tuple[float, float, float], rng: np.random.Generator) -> Image:
    """Multiply hue, saturation and value by U(1 - g, 1 + g) each (hue wraps at OpenCV's 180)."""
    r = rng.uniform(-1, 1, 3) * np.asarray(gains) + 1
    if np.allclose(r, 1.0):
        return image.copy()
    hue, sat, val = cv2.split(cv2.cvtColor(image, cv2.COLOR_RGB2HSV))
    x = np.arange(256, dtype=np.float64)
    lut_h = ((x * r[0]) % 180).astype(np.uint8)
    lut_s = np.clip(x * r[1], 0, 255).astype(np.uint8)
    lut_v = np.clip(x * r[2], 0, 255).astype(np.uint8)
    hsv = cv2.merge((cv2.LUT(hue, lut_h), cv2.LUT(sat, lut_s), cv2.LUT(val, lut_v)))
    return cv2.cvtColor(hsv, cv2.COLOR_HSV2RGB)


def hflip(sample: Sample) -> Sample:
    """Mirror left-right; boxes mirrored with the pixels."""
    w = sample.image.shape[1]
    m = np.array([[-1, 0, w], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    return Sample(np.ascontiguousarray(sample.image[:, ::-1]), bx.affine_xyxy(sample.boxes, m), sample.classes.copy())


def augment(
    load: Callable[[int], Sample],
    index: int,
    partners: int | NDArray[np.int64],
    size: int,
    cfg: AugmentConfig,
    rng: np.random.Generator,
) -> Sample:
    """The training view of sample ``index``, ``size`` x ``size``.

    ``load(i)`` returns sample ``i`` resized to longest side ``size``. With probability ``cfg.mosaic`` the
    sample and three random others form a mosaic, drawn from ``range(partners)`` or from the given sample
    indices (the same draws either way when those are ``0 .. n-1``); the result (or the letterboxed sample) goes through a
    random affine, then HSV jitter and a horizontal flip with probability ``cfg.fliplr``.
    """
    if rng.random() < cfg.mosaic:
        pool = np.arange(partners) if isinstance(partners, int) else partners
        others = pool[rng.integers(0, len(pool), size=3)]
        base = mosaic_canvas([load(index), *(load(int(i)) for i in others)], size, rng)
    else:
        base = letterbox(load(index), size)
    matrix = random_affine_matrix(base.image.shape[:2], size, cfg.translate, cfg.scale, rng)
    out = warp(base, matrix, (size, size))
    out = filter_boxes(base.boxes, out, float(matrix[0, 0]), cfg.min_box_px, cfg.min_area_ratio)
    image = hsv_jitter(out.image, (cfg.hsv_h, cfg.hsv_s, cfg.hsv_v), rng)
    out = Sample(image, out.boxes, out.classes)
    return hflip(out) if rng.random() < cfg.fliplr else out

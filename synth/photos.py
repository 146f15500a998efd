"""Photographs as Method 2 backgrounds: a user's fire-free pictures (e.g. the negatives of a real dataset),
randomly cropped to the output size, with a ground-plane pseudo depth so flames stand on the lower part of the
picture and grow towards the bottom (nearer) as they would on a floor seen from eye height.

Pseudo depth: a level camera ``CAMERA_HEIGHT_M`` above flat ground with vertical field of view ``YFOV`` and the
horizon at ``horizon`` x the image height sees row ``v`` below the horizon at distance
``CAMERA_HEIGHT_M * fy / (v - horizon_px)`` metres; rows above it get ``FAR_M``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.core.imageio import ImageError, read_image
from curate.scan import list_image_files
from synth import render

CAMERA_HEIGHT_M = 1.6
YFOV = np.deg2rad(60.0)
FAR_M = 30.0


def list_photos(paths: Iterable[Path | str]) -> list[Path]:
    """Image files under ``paths`` (files or folders, recursive), sorted."""
    photos = list_image_files(paths)
    if not photos:
        raise ValueError(f"no images in {', '.join(map(str, paths))}")
    return photos


def photo_fingerprints(paths: Iterable[Path | str]) -> list[dict[str, str]]:
    """The photos under ``paths`` (:func:`list_photos` order) as name and sha256 of their bytes: what a pool
    composited on them is made of, wherever the folder lies."""
    from curate.core.manifest import file_sha256

    return [{"name": p.name, "sha256": file_sha256(p)} for p in list_photos(paths)]


def ground_depth(width: int, height: int, horizon: float) -> NDArray[np.float32]:
    """(H, W) float32 metres of the ground-plane pseudo depth (module docstring); ``horizon`` in 0..1 of H."""
    fy = render.intrinsics(YFOV, width, height)[1, 1]
    rows = np.arange(height, dtype=np.float64) + 0.5 - horizon * height
    d = np.where(rows > 0.5, CAMERA_HEIGHT_M * fy / np.maximum(rows, 0.5), FAR_M)
    return np.repeat(np.minimum(d, FAR_M).astype(np.float32)[:, None], width, axis=1)


def crop_to(image: NDArray[np.uint8], width: int, height: int, rng: np.random.Generator) -> tuple[NDArray, list]:
    """A random crop of ``image`` (H, W, 3) with the output's aspect, 70-100 % of the largest such crop, resized
    to ``height`` x ``width``; and the crop as [x, y, w, h] pixels of the photo."""
    h, w = image.shape[:2]
    aspect = width / height
    cw, ch = (w, int(round(w / aspect))) if w / h < aspect else (int(round(h * aspect)), h)
    scale = rng.uniform(0.7, 1.0)
    cw, ch = max(int(cw * scale), 1), max(int(ch * scale), 1)
    x, y = int(rng.integers(0, w - cw + 1)), int(rng.integers(0, h - ch + 1))
    interp = cv2.INTER_AREA if cw > width else cv2.INTER_LINEAR
    return cv2.resize(image[y : y + ch, x : x + cw], (width, height), interpolation=interp), [x, y, cw, ch]


class PhotoBackgrounds:
    """Background ``v`` is photo ``v % len(photos)`` cropped by ``default_rng([seed, 5, v])``; unreadable photos
    are skipped (the next one is used) and named in :attr:`problems`."""

    def __init__(self, photos: Sequence[Path], width: int, height: int, seed: int) -> None:
        if not photos:
            raise ValueError("no background photos")
        self.photos, self.width, self.height, self.seed = list(photos), width, height, seed
        self.problems: dict[str, str] = {}

    def background(self, view_index: int) -> tuple[NDArray[np.uint8], NDArray[np.float32], dict]:
        """((H, W, 3) uint8 RGB, (H, W) float32 pseudo depth, metadata) of background ``view_index``."""
        rng = np.random.default_rng([self.seed, 5, view_index])
        for k in range(len(self.photos)):
            path = self.photos[(view_index + k) % len(self.photos)]
            try:
                image = read_image(path)
            except ImageError as exc:
                self.problems[str(path)] = str(exc)
                continue
            rgb, crop = crop_to(image, self.width, self.height, rng)
            horizon = float(rng.uniform(0.3, 0.5))
            depth = ground_depth(self.width, self.height, horizon)
            meta = {"photo": path.as_posix(), "crop": crop, "horizon": round(horizon, 4), "camera": {"yfov": YFOV}}
            return rgb, depth, meta
        raise ValueError(f"none of the {len(self.photos)} background photos can be read")

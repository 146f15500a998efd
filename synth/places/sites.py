"""Where fire can stand in a photograph: the ground below the horizon, not the sky, water or people.

A **site** is read from a sidecar when there is one (a fixed camera whose floor the user knows), else estimated:

- **Sidecar**: ``NAME.yaml`` beside ``NAME.jpg``, or ``_site.yaml`` in the folder for every photo in it (a CCTV
  camera's fire-free frames)::

      horizon: 0.35          # row of the horizon, fraction of the image height (< 0: the camera looks down)
      camera_height: 3.0     # metres above the floor (default 1.6)
      yfov: 60               # vertical field of view of the camera, degrees (default 60)
      ground: [[0.05, 0.55], [0.95, 0.55], [1.0, 1.0], [0.0, 1.0]]   # polygon (x, y fractions): fire only here

- **Estimate** (no sidecar): *sky* is the smooth, bright or blue region connected to the top edge; the
  *horizon* is the median lowest sky row over the columns that show sky when the sky spans 40 % of them
  (otherwise - rooms, streets between buildings - it is drawn in 0.3..0.5 of the height, and never above the
  lowest sky pixel); *water* is sky-like pixels below the horizon (a lake mirrors the sky) and fairly smooth,
  saturated blue or blue-green ones; *people* are OpenCV's HOG pedestrian detections (upright people only: a seated person
  is missed - docs/findings.md says how often a flame lands on one). Ground = below the horizon, none of those.

Pseudo depth on the ground: a camera ``camera_height`` above flat ground with vertical field of view ``yfov``
sees row ``v`` below the horizon at ``camera_height * fy / (v - horizon_px)`` metres (z along the view axis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml
from numpy.typing import NDArray

from ground.image.sky import sky_like, top_connected

SIDECAR_FOLDER = "_site.yaml"
CAMERA_HEIGHT_M = 1.6
YFOV_DEG = 60.0
MAX_GROUND_M = 40.0  # farther ground is not a place for a visible fire
_KEYS = {"horizon", "camera_height", "yfov", "ground"}
_WORK = 160  # long side, pixels, of the picture the estimate runs on
SKY_COLUMNS = 0.4  # the sky must span this share of the columns to place the horizon (else it is drawn)


@dataclass(frozen=True)
class Site:
    """A photo's site in its own pixels: ``horizon`` row (float px), ``ground`` (H, W) bool, ``people`` boxes
    [x, y, w, h] px, ``camera_height`` metres, ``yfov`` radians (of the whole photo), ``source`` sidecar|estimate."""

    horizon: float
    ground: NDArray[np.bool_]
    people: tuple[tuple[int, int, int, int], ...]
    camera_height: float
    yfov: float
    source: str

    def depth(self, height: int, fy: float, horizon: float, ground: NDArray[np.bool_]) -> NDArray[np.float32]:
        """(H, W) float32 z-depth in metres of ``ground`` pixels of a ``height``-row picture whose horizon is at
        row ``horizon`` and focal length ``fy`` px; 0 where no flame may stand (off the ground, too far)."""
        rows = np.arange(height, dtype=np.float64) + 0.5 - horizon
        d = np.where(rows > 0.5, self.camera_height * fy / np.maximum(rows, 0.5), 0.0)
        d = np.where(d > MAX_GROUND_M, 0.0, d).astype(np.float32)
        return np.where(ground, d[:, None], np.float32(0.0)).astype(np.float32)


def read_site_sidecar(photo: Path) -> dict[str, Any] | None:
    """The sidecar of ``photo`` (its own ``NAME.yaml``, else the folder's ``_site.yaml``), checked; None if none.
    Raises ValueError naming the file and key for unknown keys or bad values."""
    for path in (photo.with_suffix(".yaml"), photo.parent / SIDECAR_FOLDER):
        if path.is_file():
            return _check_sidecar(yaml.safe_load(path.read_text(encoding="utf-8")) or {}, path)
    return None


def sidecar_files(photo: Path) -> list[Path]:
    """The sidecar files that decide ``photo``'s site (for content identities)."""
    return [p for p in (photo.with_suffix(".yaml"), photo.parent / SIDECAR_FOLDER) if p.is_file()][:1]


def _check_sidecar(data: Any, path: Path) -> dict[str, Any]:
    if not isinstance(data, dict):
        raise ValueError(f"{path}: a site sidecar is a mapping of {', '.join(sorted(_KEYS))}")
    unknown = sorted(set(data) - _KEYS)
    if unknown:
        raise ValueError(f"{path}: unknown key {unknown[0]!r} (keys: {', '.join(sorted(_KEYS))})")
    out: dict[str, Any] = {}
    for key, lo, hi in (("horizon", -2.0, 1.0), ("camera_height", 0.1, 100.0), ("yfov", 5.0, 150.0)):
        if key in data:
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
                raise ValueError(f"{path}: {key} must be a number in {lo:g}..{hi:g}, got {value!r}")
            out[key] = float(value)
    if "ground" in data:
        poly = data["ground"]
        ok = (
            isinstance(poly, list)
            and len(poly) >= 3
            and all(isinstance(p, list) and len(p) == 2 and all(isinstance(c, (int, float)) for c in p) for p in poly)
        )
        if not ok:
            raise ValueError(f"{path}: ground must be a list of >= 3 [x, y] points (fractions of width and height)")
        out["ground"] = [[float(x), float(y)] for x, y in poly]
    return out


def estimate_site(image: NDArray[np.uint8], rng: np.random.Generator, sidecar: dict[str, Any] | None = None) -> Site:
    """The :class:`Site` of the (H, W, 3) uint8 RGB ``image``: from ``sidecar`` keys where given, estimated
    otherwise (module docstring). ``rng`` draws the horizon of a photo without sky."""
    h, w = image.shape[:2]
    sidecar = sidecar or {}
    scale = _WORK / max(h, w)
    small = cv2.resize(image, (max(int(w * scale), 8), max(int(h * scale), 8)), interpolation=cv2.INTER_AREA)
    skylike = sky_like(small)
    sky = top_connected(skylike)
    if "horizon" in sidecar:
        horizon = sidecar["horizon"] * h
    else:
        wide_sky = sky.any(axis=0).mean() >= SKY_COLUMNS and sky.mean() > 0.03
        drawn = float(rng.uniform(0.3, 0.5)) * h
        horizon = _horizon_from_sky(sky, h) if wide_sky else max(drawn, _lowest_sky(sky, h))
    below = (np.arange(h)[:, None] >= horizon) & np.ones((1, w), bool)
    if "ground" in sidecar:
        ground = polygon_mask(sidecar["ground"], w, h) & below
        people: tuple[tuple[int, int, int, int], ...] = ()
    else:
        wet = skylike | water_like(small)
        water = cv2.resize(wet.astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST).astype(bool)
        people = detect_people(image)
        ground = below & ~water
        for x, y, bw, bh in people:
            ground[max(y, 0) : y + bh, max(x, 0) : x + bw] = False
    return Site(
        float(horizon),
        ground,
        people,
        float(sidecar.get("camera_height", CAMERA_HEIGHT_M)),
        math.radians(sidecar.get("yfov", YFOV_DEG)),
        "sidecar" if sidecar else "estimate",
    )


def water_like(rgb: NDArray[np.uint8]) -> NDArray[np.bool_]:
    """(H, W) bool: fairly smooth, saturated blue or blue-green pixels (lakes, sea, pools), dilated by 2 px."""
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV).astype(np.float32)
    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32)
    texture = cv2.blur(np.abs(cv2.Laplacian(grey, cv2.CV_32F)), (5, 5))
    hue, sat, val = hsv[..., 0] * 2, hsv[..., 1] / 255, hsv[..., 2] / 255
    wet = (hue >= 170) & (hue <= 250) & (sat > 0.35) & (val > 0.15) & (texture < 14.0)
    return cv2.dilate(wet.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)


def _lowest_sky(sky: NDArray[np.bool_], height: int) -> float:
    """The row below the lowest sky pixel, in ``height``-row px (0 without sky)."""
    rows = np.flatnonzero(sky.any(axis=1))
    return float(rows[-1] + 1) * height / sky.shape[0] if len(rows) else 0.0


def _horizon_from_sky(sky: NDArray[np.bool_], height: int) -> float:
    """Median over the columns that show sky of the row below their lowest sky pixel, in ``height``-row px."""
    cols = sky.any(axis=0)
    lowest = sky.shape[0] - np.argmax(sky[::-1], axis=0)
    return float(np.median(lowest[cols])) * height / sky.shape[0]


def detect_people(image: NDArray[np.uint8]) -> tuple[tuple[int, int, int, int], ...]:
    """Boxes [x, y, w, h] (px of ``image``) of upright people by OpenCV's HOG pedestrian detector, enlarged by
    20 % (so a flame keeps off them); run at most 640 px wide."""
    h, w = image.shape[:2]
    scale = min(1.0, 640 / w)
    small = cv2.resize(image, (int(w * scale), int(h * scale))) if scale < 1 else image
    hog = cv2.HOGDescriptor()
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    if min(small.shape[:2]) < 128:
        return ()
    rects, weights = hog.detectMultiScale(cv2.cvtColor(small, cv2.COLOR_RGB2GRAY), winStride=(8, 8), scale=1.1)
    out = []
    for (x, y, bw, bh), score in zip(rects, np.ravel(weights)):
        if score < 0.5:
            continue
        x, y, bw, bh = (int(round(v / scale)) for v in (x, y, bw, bh))
        out.append((x - bw // 10, y - bh // 10, int(bw * 1.2), int(bh * 1.2)))
    return tuple(out)


def polygon_mask(points: list[list[float]], width: int, height: int) -> NDArray[np.bool_]:
    """(H, W) bool inside the polygon of (x, y) fractions of the image size."""
    mask = np.zeros((height, width), np.uint8)
    poly = np.round(np.asarray(points, np.float64) * [width, height]).astype(np.int32)
    cv2.fillPoly(mask, [poly], 1)
    return mask.astype(bool)

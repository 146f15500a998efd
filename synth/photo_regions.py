"""Fire-like regions of fire-free photos, cut out as RGBA sprites for the distractor kinds that paste them
(:mod:`synth.distractors`): your own hard negatives, pasted unboxed beside your own pasted flames. Two rules:

- ``photo`` (:func:`regions_of`): what the cut-out colour rule (:func:`synth.cutouts.fire_mask`) calls fire in
  photos known to hold none — orange lamp shades, lit windows, red sofas, sunlit wood — with the same kind of cut
  edge as a cut-out flame;
- ``lights`` (:func:`lights_of`): light sources — a white-hot lamp shade or bulb, a blown-out window, a street
  light — with their warm glow: the things a fire detector fires at most on fire-free photos, which the colour
  rule's saturation test leaves out (a near-white core is not "coloured").

A photo is searched at :data:`SEARCH_SIDE` px on its longer side; its fire-coloured mask is closed and filled
(:func:`synth.cutouts.filled`) and each connected component covering :data:`MIN_AREA`..:data:`MAX_AREA` of the
photo, filling at least :data:`MIN_FILL` of its bounding box and at least :data:`MIN_SIDE` px across (a thing,
not a ragged patch of warm texture, a sliver along an edge or a line) and of mean HSV saturation at least
:data:`MIN_SATURATION` (warm and coloured: a white wall or sky passes the rule's bright core test but looks like
nothing on fire) becomes a region: the component's bounding box of the (searched) photo, alpha = the component
softened (Gaussian, sigma 1 px).

A light is a connected component of near-white pixels (HSV value >= :data:`LIGHT_VALUE`, saturation <=
:data:`LIGHT_SATURATION`) covering :data:`LIGHT_MIN_AREA`..:data:`LIGHT_MAX_AREA` of the photo, filling at least
:data:`MIN_FILL` of its box and at least :data:`LIGHT_MIN_SIDE` px across, whose surround (its box grown by
:data:`LIGHT_MARGIN` x its longer side each way, the component excluded) is warm — mean red over mean blue by at
least :data:`LIGHT_WARMTH` of 255 (a lamp's glow, not a white sign on a blue wall or a patch of sky) and brighter
near it than farther out (the surround's part within half the margin brighter by :data:`LIGHT_GLOW` in HSV value
than the rest: a glow fading outwards, not white paper on a desk). Its region
is the grown box, alpha = the component grown by half the margin and blurred (sigma a third of the margin), so the
glow fades out before the cut's edge.

Frames: image pixels, row 0 at the top. Deterministic: the same photos in the same order give the same regions.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.core.imageio import ImageError, read_image
from synth.cutouts import filled, fire_mask

SEARCH_SIDE = 640  # a photo's longer side while it is searched, px
MIN_AREA = 0.002  # smallest region, share of the photo's area
MAX_AREA = 0.1  # largest region (a whole warm wall is a background, not a thing)
MIN_FILL = 0.35  # share of its bounding box a region fills at least
MIN_SIDE = 8  # shorter side of a region's bounding box at least, px of the searched photo
MIN_SATURATION = 0.4  # mean HSV saturation (0..1) of a region's pixels at least
LIGHT_VALUE = 0.97  # HSV value (0..1) of a light's core pixels at least (blown out: an emitter, not paper)
LIGHT_SATURATION = 0.45  # HSV saturation of a light's core pixels at most (near white)
LIGHT_MIN_AREA = 0.0003  # smallest light core, share of the photo's area
LIGHT_MAX_AREA = 0.03  # largest (a bright wall or sky is not a light source)
LIGHT_MIN_SIDE = 4  # shorter side of a light core's box at least, px of the searched photo
LIGHT_MARGIN = 0.5  # the glow kept around a light core: this x its box's longer side on every side
LIGHT_WARMTH = 20.0  # mean red minus mean blue (of 255) of a light's surround at least
LIGHT_GLOW = 0.05  # HSV value of the surround's inner half over its outer half at least (light fading outwards)
RULES: tuple[str, ...] = ("photo", "lights")  # the rules, named as the distractor kinds that paste them


@dataclass(frozen=True)
class Region:
    """A fire-like region: ``rgba`` (h, w, 4) uint8 (alpha: the region's pixels, soft edge), its height as a
    share of its photo's height, the photo's file name and the rule that found it (:data:`RULES`)."""

    rgba: NDArray[np.uint8]
    height_share: float
    photo: str
    kind: str = "photo"


def searched(rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """(H, W, 3) ``rgb`` scaled down so its longer side is at most :data:`SEARCH_SIDE` (never up)."""
    h, w = rgb.shape[:2]
    scale = SEARCH_SIDE / max(h, w)
    if scale >= 1.0:
        return rgb
    return cv2.resize(rgb, (max(round(w * scale), 1), max(round(h * scale), 1)), interpolation=cv2.INTER_AREA)


def regions_of(rgb: NDArray[np.uint8], name: str = "") -> list[Region]:
    """The fire-like regions of one (H, W, 3) uint8 RGB photo (module docstring), in OpenCV's component order."""
    image = searched(rgb)
    h, w = image.shape[:2]
    mask = filled(fire_mask(image)).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    saturation = cv2.cvtColor(image, cv2.COLOR_RGB2HSV)[..., 1].astype(np.float32) / 255.0
    out = []
    for k in range(1, count):
        x, y, bw, bh, area = (int(v) for v in stats[k])
        if not MIN_AREA * h * w <= area <= MAX_AREA * h * w or area < MIN_FILL * bw * bh or min(bw, bh) < MIN_SIDE:
            continue
        part = labels[y : y + bh, x : x + bw] == k
        if float(saturation[y : y + bh, x : x + bw][part].mean()) < MIN_SATURATION:
            continue
        part = part.astype(np.float32)
        alpha = np.clip(cv2.GaussianBlur(part, (0, 0), 1.0), 0.0, 1.0)
        rgba = np.dstack([image[y : y + bh, x : x + bw], np.round(alpha * 255.0).astype(np.uint8)])
        out.append(Region(np.ascontiguousarray(rgba), bh / h, name))
    return out


def lights_of(rgb: NDArray[np.uint8], name: str = "") -> list[Region]:
    """The light sources of one (H, W, 3) uint8 RGB photo with their glow (module docstring), in OpenCV's
    component order."""
    image = searched(rgb)
    h, w = image.shape[:2]
    hsv = cv2.cvtColor(image, cv2.COLOR_RGB2HSV).astype(np.float32) / 255.0
    core = ((hsv[..., 2] >= LIGHT_VALUE) & (hsv[..., 1] <= LIGHT_SATURATION)).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(core, connectivity=8)
    out = []
    for k in range(1, count):
        x, y, bw, bh, area = (int(v) for v in stats[k])
        if not LIGHT_MIN_AREA * h * w <= area <= LIGHT_MAX_AREA * h * w or area < MIN_FILL * bw * bh:
            continue
        if min(bw, bh) >= LIGHT_MIN_SIDE and (region := _lit(image, hsv, labels, k, (x, y, bw, bh), name)):
            out.append(region)
    return out


def _lit(
    image: NDArray[np.uint8], hsv: NDArray[np.float32], labels: NDArray[np.int32], k: int,
    box: tuple[int, int, int, int], name: str,
) -> Region | None:  # fmt: skip
    """The light of component ``k`` of the (H, W) ``labels`` (its box ``box``: x, y, w, h) in the searched (H, W, 3)
    RGB ``image`` (its HSV in 0..1: ``hsv``), cut with its glow; None when its surround is not warm or does not fade
    outwards (module docstring)."""
    x, y, bw, bh = box
    h, w = image.shape[:2]
    m = max(int(round(LIGHT_MARGIN * max(bw, bh))), 2)
    x0, y0, x1, y1 = max(x - m, 0), max(y - m, 0), min(x + bw + m, w), min(y + bh + m, h)
    part = labels[y0:y1, x0:x1] == k
    grown = cv2.dilate(part.astype(np.uint8), np.ones((m | 1, m | 1), np.uint8)).astype(np.float32)
    inner, outer = (grown > 0) & ~part, grown == 0
    if not inner.any() or not outer.any():
        return None
    surround = image[y0:y1, x0:x1][~part].astype(np.float32)
    value = hsv[y0:y1, x0:x1, 2]
    if (
        surround[:, 0].mean() - surround[:, 2].mean() < LIGHT_WARMTH
        or value[inner].mean() - value[outer].mean() < LIGHT_GLOW
    ):
        return None
    alpha = np.clip(cv2.GaussianBlur(grown, (0, 0), m / 3.0), 0.0, 1.0)
    rgba = np.dstack([image[y0:y1, x0:x1], np.round(alpha * 255.0).astype(np.uint8)])
    return Region(np.ascontiguousarray(rgba), (y1 - y0) / h, name, "lights")


FINDERS = {"photo": regions_of, "lights": lights_of}


def photo_regions(photos: Sequence[Path], rules: Sequence[str] = ("photo",)) -> tuple[Region, ...]:
    """Every region of ``photos`` that the ``rules`` (:data:`RULES`) find: photo by photo in their order, within
    a photo rule by rule in ``rules``' order (an unreadable photo is skipped: the pool that composites on it names
    it)."""
    if unknown := [r for r in rules if r not in FINDERS]:
        raise ValueError(f"unknown region rules {unknown}: choose from {', '.join(RULES)}")
    out: list[Region] = []
    for path in photos:
        try:
            rgb = read_image(path)
        except ImageError:
            continue
        for rule in rules:
            out += FINDERS[rule](rgb, Path(path).name)
    return tuple(out)

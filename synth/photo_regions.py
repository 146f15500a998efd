"""Fire-like regions of fire-free photos: what the cut-out colour rule (:func:`synth.cutouts.fire_mask`) calls fire
in photos known to hold none — lamps, lit windows, red sofas, sunlit wood, warm walls — cut out as RGBA sprites
for the ``photo`` distractor kind (:mod:`synth.distractors`): your own hard negatives, pasted unboxed beside (and
with the same kind of cut edge as) your own pasted flames.

A photo is searched at :data:`SEARCH_SIDE` px on its longer side; its fire-coloured mask is closed and filled
(:func:`synth.cutouts.filled`) and each connected component covering :data:`MIN_AREA`..:data:`MAX_AREA` of the
photo, filling at least :data:`MIN_FILL` of its bounding box and at least :data:`MIN_SIDE` px across (a thing,
not a ragged patch of warm texture, a sliver along an edge or a line) and of mean HSV saturation at least
:data:`MIN_SATURATION` (warm and coloured: a white wall or sky passes the rule's bright core test but looks like
nothing on fire) becomes a region: the component's bounding box of the (searched) photo, alpha = the component
softened (Gaussian, sigma 1 px). Frames: image pixels, row 0 at the top. Deterministic: the same photos in the
same order give the same regions.
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


@dataclass(frozen=True)
class Region:
    """A fire-like region: ``rgba`` (h, w, 4) uint8 (alpha: the region's pixels, soft edge), its height as a
    share of its photo's height and the photo's file name."""

    rgba: NDArray[np.uint8]
    height_share: float
    photo: str


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


def photo_regions(photos: Sequence[Path]) -> tuple[Region, ...]:
    """Every fire-like region of ``photos`` (in their order; an unreadable photo is skipped: the pool that
    composites on it names it)."""
    out: list[Region] = []
    for path in photos:
        try:
            out += regions_of(read_image(path), Path(path).name)
        except ImageError:
            continue
    return tuple(out)

"""Whether a composited flame can be seen: its contrast against what is behind it.

A flame pixel's contrast is the CIE76 colour difference ΔE*ab (CIE L*a*b*, D65, L* in 0..100) between the final
image and the *plate*: the same background through the same camera without any flame. A flame is **visible**
when at least :data:`MIN_PIXELS` of its mask pixels, and at least :data:`MIN_SHARE` of them, differ by
:data:`MIN_DELTA_E` or more. ΔE 10 is about four times the just-noticeable difference (~2.3): a difference a
person notices at a glance, not one found by flicking between two images. So a dim red flame on a sunlit wall,
or a flame of six pixels, is not a fire anyone would mark; a yellow flame on the same wall is.

:func:`measure` reports a flame's visibility; its box comes from its *visible part* (mask pixels at
:data:`MIN_DELTA_E` or more), so faint tips against a bright sky do not stretch a box beyond what shows.

Smoke is seen at a lower contrast: a smoke pixel counts from :data:`SMOKE_DELTA_E` (ΔE 5, about two just-noticeable
differences). Calibration (``python experiments/smoke_contrast.py``): over the 532 labelled smoke boxes of
fire-smoke-608, the median pixel of a box differs from the colour around the box by ΔE 4.9 at the 5th percentile
(9.0 at the 10th, 22.3 at the median): people label smoke that faint, so a plume whose pixels differ by less than
that from its plate is no smoke anyone would mark, and is erased. The pixel and share counts are the flames'.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

MIN_DELTA_E = 10.0  # CIE76 ΔE*ab a flame pixel needs to count as seen
MIN_PIXELS = 16  # seen pixels a visible flame has at least ...
MIN_SHARE = 0.3  # ... and at least this share of its mask
SMOKE_DELTA_E = 5.0  # CIE76 ΔE*ab a smoke pixel needs to count as seen (module docstring: its calibration)


def delta_e(image: NDArray[np.uint8], plate: NDArray[np.uint8]) -> NDArray[np.float32]:
    """(H, W) CIE76 ΔE*ab between two (H, W, 3) uint8 sRGB images."""
    lab = [cv2.cvtColor(x.astype(np.float32) / 255.0, cv2.COLOR_RGB2Lab) for x in (image, plate)]
    return np.sqrt(((lab[0] - lab[1]) ** 2).sum(axis=-1)).astype(np.float32)


@dataclass(frozen=True)
class Visibility:
    """One flame (or smoke): ``pixels`` in its mask, ``seen`` of them at ΔE >= its threshold, ``contrast`` the median
    ΔE over the mask (0 for an empty mask), ``part`` the (H, W) bool seen pixels."""

    pixels: int
    seen: int
    contrast: float
    part: NDArray[np.bool_]

    @property
    def visible(self) -> bool:
        return self.seen >= MIN_PIXELS and self.seen >= MIN_SHARE * self.pixels


def measure(delta: NDArray[np.float32], mask: NDArray[np.bool_], threshold: float = MIN_DELTA_E) -> Visibility:
    """Visibility of the flame (or, at ``threshold`` :data:`SMOKE_DELTA_E`, the smoke) with (H, W) bool ``mask``
    given the (H, W) ΔE map ``delta`` (:func:`delta_e`)."""
    values = delta[mask]
    part = mask & (delta >= threshold)
    contrast = float(np.median(values)) if values.size else 0.0
    return Visibility(int(values.size), int(part.sum()), contrast, part)

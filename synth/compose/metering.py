"""Auto exposure with the fire in view: a camera meters the whole frame, so a bright flame in it lowers the
exposure of everything else — the room around a fire is darker in footage than in a photo of the same room
without it. A flame composited on a photo exposed for that photo alone washes out over bright surfaces: its
light is added to a wall already near white, its warm cast clips the floor to pale yellow, and it reads as a
translucent film.

The meter keeps the frame's mean linear luminance. A scene of mean linear luminance ``m`` (Rec. 709 luma of its
display values linearised with gamma 2.2) with flames over a share ``a`` of its pixels, each ``radiance`` times
the sensor's white (a flame's core is far past it: :func:`synth.flames.colour.exposed_palette`), is exposed at

    gain = m / (m (1 - a) + a radiance),   clipped to [MIN_GAIN, 1],

applied to the scene in linear light before the flames are added (:func:`synth.compose.effects.scale_light`). A frame
without flames keeps its exposure, and so does one whose flames are too small to move the meter.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from synth.compose.composite import Placement, scaled_layers
from synth.compose.light import REC709, to_linear

#: A flame's radiance in units of the sensor's white, drawn log-uniform per image.
RADIANCE = (4.0, 16.0)
#: The lowest exposure the meter sets (a camera's metering range is not unbounded).
MIN_GAIN = 0.25
#: Darkest mean linear luminance the meter reads (a black frame is not metered to infinity).
MIN_MEAN = 0.02


def draw_radiance(rng: np.random.Generator) -> float:
    """A flame radiance (:data:`RADIANCE`, log-uniform) for one image."""
    lo, hi = np.log(RADIANCE[0]), np.log(RADIANCE[1])
    return float(np.exp(rng.uniform(lo, hi)))


def mean_linear_luma(img: NDArray[np.uint8]) -> float:
    """Mean linear luminance in 0..1 of the (H, W, 3) uint8 display ``img`` (gamma 2.2)."""
    return float((to_linear(img) @ REC709).mean())


def flame_share(placements: Sequence[Placement], width: int, height: int) -> float:
    """Share in 0..1 of a ``width`` x ``height`` image's pixels under the flame masks of ``placements`` (each
    clipped to the image, overlaps counted once)."""
    covered = np.zeros((height, width), bool)
    for p in placements:
        mask = scaled_layers(p.sprite, p.width, p.height)[2]
        x0, y0 = max(p.x, 0), max(p.y, 0)
        x1, y1 = min(p.x + p.width, width), min(p.y + p.height, height)
        if x0 < x1 and y0 < y1:
            covered[y0:y1, x0:x1] |= mask[y0 - p.y : y1 - p.y, x0 - p.x : x1 - p.x]
    return float(covered.mean())


def metered_gain(mean: float, share: float, radiance: float) -> float:
    """The exposure gain in [:data:`MIN_GAIN`, 1] that keeps the metered mean linear luminance of a scene of mean
    ``mean`` with flames of ``radiance`` over ``share`` of its pixels (module docstring); 1 without flames."""
    m = max(mean, MIN_MEAN)
    gain = m / (m * (1.0 - share) + share * max(radiance, m))
    return float(min(max(gain, MIN_GAIN), 1.0))

"""Display values and linear light: the gamma 2.2 encoding and the Rec. 709 luminance weights that exposure
(:func:`synth.compose.effects.scale_light`), the meter (:mod:`synth.compose.metering`), compositing (:mod:`synth.compose.composite`) and
the panoramas' tone mapping (:func:`synth.places.panorama.tone_map`, weights only) share. Display values are in 0..1 (or uint8 0..255), linear light in 0..1 relative to the sensor's white."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

GAMMA = 2.2
#: Rec. 709 luminance weights of (R, G, B).
REC709 = np.asarray([0.2126, 0.7152, 0.0722], np.float32)
#: Rec. 601 luma weights of (R, G, B): OpenCV's grey conversion, which the smoke's colour and light are read with.
REC601 = np.asarray([0.299, 0.587, 0.114], np.float32)


def to_linear(img: NDArray[np.uint8]) -> NDArray[np.float32]:
    """(H, W, 3) float32 linear light of the (H, W, 3) uint8 display ``img``."""
    return (img.astype(np.float32) / 255.0) ** GAMMA


def to_display(linear: NDArray[np.float32]) -> NDArray[np.uint8]:
    """(H, W, 3) uint8 display values of (H, W, 3) ``linear`` light in 0..1 (rounded)."""
    return np.round(255.0 * linear ** (1 / GAMMA)).astype(np.uint8)


def luma(rgb: NDArray[np.float32]) -> NDArray[np.float32]:
    """(..., 3) -> (..., 1) Rec. 709 weighted sum (luma of display values, luminance of linear ones)."""
    return rgb @ REC709[:, None]

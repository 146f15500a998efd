"""Sky in a photograph: the smooth, blue, overcast-grey or night-black region connected to the top edge. Read by
the photo-site estimate of Method 2 (:mod:`synth.places.sites`: fire stands below the horizon) and by the test-image
attributes of :mod:`eval.attributes` (is the fire outdoors, under a visible sky?)."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray


def sky_like(rgb: NDArray[np.uint8]) -> NDArray[np.bool_]:
    """(H, W) bool of the (H, W, 3) uint8 RGB image: smooth pixels that are blue, or bright and grey (overcast),
    or near black (night sky)."""
    lab = cv2.cvtColor(rgb, cv2.COLOR_RGB2LAB).astype(np.float32)
    light, b = lab[..., 0] * (100 / 255), lab[..., 2] - 128
    sat = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)[..., 1].astype(np.float32) / 255
    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32)
    texture = cv2.blur(np.abs(cv2.Laplacian(grey, cv2.CV_32F)), (5, 5))
    smooth = texture < 6.0
    blue = (b < -8) & (light > 35)
    overcast = (light > 70) & (sat < 0.18)
    night = light < 8
    return smooth & (blue | overcast | night)


def top_connected(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The parts of the (H, W) bool ``mask`` connected to the top row (8-connectivity)."""
    n, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    top = set(np.unique(labels[0][mask[0]]).tolist()) - {0}
    return np.isin(labels, list(top)) if top else np.zeros_like(mask)


def sky_mask(rgb: NDArray[np.uint8]) -> NDArray[np.bool_]:
    """(H, W) bool: the sky of the (H, W, 3) uint8 RGB image, :func:`sky_like` pixels connected to the top edge."""
    return top_connected(sky_like(rgb))

"""Per-flame appearance jitter: each flame of an image mirrored or not, its width stretched, its hue turned and its
saturation scaled, so that one cut-out (or simulated frame) pasted twice is two different flames. Copy-paste
augmentation gets its objects' variety from such draws (Ghiasi et al. 2021 jitter scale; here the size comes from
the scene's depth, so only the shape and colour are jittered).

Ranges (:data:`STRETCH`, :data:`HUE_DEG`, :data:`SATURATION`) keep a flame a flame: its hue stays in the red to
yellow of fire (at most 5 degrees towards pink, 10 towards yellow; fire's own hues span about 0-60 degrees), its aspect within what
fire-cctv-416's boxes show at the same height. Sprites are (h, w) layers in image orientation, row 0 at the top.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.sprites import Sprite

STRETCH = (0.75, 4 / 3)  # width factor, drawn log-uniform
HUE_DEG = (-5.0, 10.0)  # hue turned uniformly in this range, degrees (towards yellow; red turned far becomes pink)
SATURATION = (0.75, 1.25)  # saturation factor, uniform


@dataclass(frozen=True)
class Jitter:
    """One flame's draw: ``mirror`` left-right, ``stretch`` its width factor, ``hue`` degrees (positive towards
    yellow), ``saturation`` factor."""

    mirror: bool
    stretch: float
    hue: float
    saturation: float


def draw_jitter(rng: np.random.Generator) -> Jitter:
    """A :class:`Jitter` from four draws of ``rng`` (always four: the draws after it do not move)."""
    mirror = bool(rng.random() < 0.5)
    stretch = float(np.exp(rng.uniform(np.log(STRETCH[0]), np.log(STRETCH[1]))))
    hue = float(rng.uniform(*HUE_DEG))
    return Jitter(mirror, stretch, hue, float(rng.uniform(*SATURATION)))


def recoloured(rgb: NDArray[np.uint8], hue: float, saturation: float) -> NDArray[np.uint8]:
    """(h, w, 3) uint8 RGB with its hue turned by ``hue`` degrees and its saturation scaled by ``saturation``
    (HSV; value kept, so a flame's brightness and a black pixel's emptiness stay)."""
    if hue == 0.0 and saturation == 1.0:
        return rgb
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV_FULL).astype(np.float32)  # hue 0..255 for 0..360 degrees
    hsv[..., 0] = np.mod(hsv[..., 0] + hue * 256.0 / 360.0, 256.0)
    hsv[..., 1] = np.clip(hsv[..., 1] * saturation, 0.0, 255.0)
    return cv2.cvtColor(np.round(hsv).clip(0, 255).astype(np.uint8), cv2.COLOR_HSV2RGB_FULL)


def jittered(sprite: Sprite, j: Jitter) -> Sprite:
    """``sprite`` mirrored and recoloured by ``j`` (its size kept: the stretch is the placement's, see
    :func:`stretched_width`); the flame mask and every alpha are only mirrored."""
    cut = np.s_[:, ::-1] if j.mirror else np.s_[:, :]
    over = sprite.over[cut].copy()
    over[..., :3] = recoloured(np.ascontiguousarray(over[..., :3]), j.hue, j.saturation)
    emission = recoloured(np.ascontiguousarray(sprite.emission[cut]), j.hue, j.saturation)
    return Sprite(over, emission, np.ascontiguousarray(sprite.mask[cut]))


def stretched_width(width: int, j: Jitter) -> int:
    """A placement's ``width`` in pixels stretched by ``j`` (at least 2)."""
    return max(int(round(width * j.stretch)), 2)

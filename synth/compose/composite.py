"""Vectorised 2D compositing of flame sprites onto a background, tracking each flame's visible mask.

Per sprite, in order: the ``over`` layer (smoke) is alpha-blended and the background behind the flame dimmed by
its luminous coverage (``opacity`` x :func:`coverage` of the emission brightness: none below
:data:`CLEAR_BRIGHTNESS`, full from :data:`OPAQUE_BRIGHTNESS` up, so a flame's bright body hides what is behind it, as a camera exposed for the
fire sees it, while its dim edge lets the background through; over a bright background a half-covering dim edge
still darkens it into an outline, unless ``never_darken`` caps the coverage where covering and lighting keeps the luma
behind the flame: :func:`_keeping_cover`, up to clipping), then the emission
is added (``add``) or screened (``screen``), plus a soft glow
(blurred emission) and a warm cast: the surroundings lit in the flame's mean colour with a Gaussian falloff
around its base (light on the floor and walls; never part of the flame's mask or box). A flame pixel stays visible unless a later sprite is
opaque there (its smoke alpha >= 0.5 or its own flame mask); a smoke pixel (see ``synth.flames.sprites.SMOKE_ALPHA``)
likewise, and also where a later sprite has smoke (so smoke masks stay disjoint). Boxes come from these final
masks.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.compose.light import luma
from synth.compose.ramps import smoothstep
from synth.flames.sprites import Sprite

#: How a flame's light meets the background: added, or screened (1 - (1 - a)(1 - b)); drawn per flame.
BLEND_MODES: tuple[str, ...] = ("screen", "add")
#: Emission brightness (brightest channel, 0..1) from which a flame covers the background fully (x opacity) ...
OPAQUE_BRIGHTNESS = 0.6
#: ... and below which it covers nothing (only adds its light).
CLEAR_BRIGHTNESS = 0.15


def coverage(brightness: NDArray[np.float32]) -> NDArray[np.float32]:
    """Luminous coverage in [0, 1] of emission ``brightness`` (any shape, 0..1): a smoothstep from 0 at
    :data:`CLEAR_BRIGHTNESS` to 1 at :data:`OPAQUE_BRIGHTNESS`. The dim edge only adds light (a bright wall
    behind it is reddened, never outlined in a darker colour); the bright body is opaque."""
    return smoothstep(brightness, CLEAR_BRIGHTNESS, OPAQUE_BRIGHTNESS).astype(np.float32)


@dataclass(frozen=True)
class Placement:
    """A sprite scaled to ``width`` x ``height`` pixels with its top-left at (x, y) (may lie outside)."""

    sprite: Sprite
    x: int
    y: int
    width: int
    height: int
    blend: str = "screen"
    glow: float = 0.3
    opacity: float = 0.8  # luminous coverage: the background behind the flame dims by opacity x coverage()
    cast: bool = True  # light the surroundings warm (with ``glow`` > 0)
    never_darken: bool = False  # the flame's coverage is capped so it never darkens the luma behind it

    def __post_init__(self) -> None:
        if self.blend not in BLEND_MODES:
            raise ValueError(f"unknown blend mode {self.blend!r}; choose one of {', '.join(BLEND_MODES)}")
        if self.width < 1 or self.height < 1:
            raise ValueError("placement size must be at least 1 x 1")


def scaled_layers(
    sprite: Sprite, width: int, height: int
) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.bool_], NDArray[np.bool_]]:
    """Sprite layers resized to (height, width): over (h, w, 4) and emission (h, w, 3) float32 in [0, 1], flame
    mask and smoke mask (h, w) bool."""
    sw, sh = sprite.size
    interp = cv2.INTER_AREA if width < sw else cv2.INTER_LINEAR
    over = cv2.resize(sprite.over, (width, height), interpolation=interp).astype(np.float32) / 255.0
    emission = cv2.resize(sprite.emission, (width, height), interpolation=interp).astype(np.float32) / 255.0
    masks = np.stack([sprite.mask, sprite.smoke_mask()], axis=-1).astype(np.float32)
    masks = cv2.resize(masks, (width, height), interpolation=cv2.INTER_LINEAR).reshape(height, width, 2) >= 0.5
    return over.reshape(height, width, 4), emission.reshape(height, width, 3), masks[..., 0], masks[..., 1]


def _clip(p: Placement, w: int, h: int) -> tuple[slice, slice, slice, slice] | None:
    x0, y0, x1, y1 = max(p.x, 0), max(p.y, 0), min(p.x + p.width, w), min(p.y + p.height, h)
    if x0 >= x1 or y0 >= y1:
        return None
    return slice(y0, y1), slice(x0, x1), slice(y0 - p.y, y1 - p.y), slice(x0 - p.x, x1 - p.x)


def _keeping_cover(behind: NDArray[np.float32], light: NDArray[np.float32], blend: str) -> NDArray[np.float32]:
    """The largest coverage whose covered background plus ``light`` (added or screened by ``blend``) keeps the
    luma ``behind`` it (both (..., 1) in 0..1): ``L / B`` with ``add``, ``L (1 - B) / (B (1 - L))`` with ``screen``."""
    b = np.maximum(behind, 1e-3)
    if blend == "add":
        return light / b
    return light * (1.0 - b) / np.maximum(b * (1.0 - light), 1e-6)


def _add_light(img: NDArray[np.float32], light: NDArray[np.float32], blend: str) -> NDArray[np.float32]:
    return np.minimum(img + light, 1.0) if blend == "add" else 1.0 - (1.0 - img) * (1.0 - light)


def _glow(img: NDArray[np.float32], emission: NDArray[np.float32], p: Placement, cut) -> None:
    """Blurred emission added around the sprite (light spill), in place."""
    h, w = img.shape[:2]
    r = max(int(0.25 * max(p.width, p.height)), 2)
    big = replace(p, x=p.x - r, y=p.y - r, width=p.width + 2 * r, height=p.height + 2 * r)
    c = _clip(big, w, h)
    if c is None:
        return
    if emission.any():
        canvas = np.zeros((p.height + 2 * r, p.width + 2 * r, 3), np.float32)
        canvas[r : r + p.height, r : r + p.width] = emission
        light = (cv2.GaussianBlur(canvas, (0, 0), sigmaX=r / 2.5) * p.glow)[c[2], c[3]]
    else:  # nothing emits (an RGBA cut-out): the blur is zeros; skip it (a sprite drawn thousands of pixels
        # large made that blur take minutes) and add the same zeros, so the image keeps its bytes
        light = np.zeros((c[0].stop - c[0].start, c[1].stop - c[1].start, 3), np.float32)
    img[c[0], c[1]] = _add_light(img[c[0], c[1]], light, p.blend)


def _cast(img: NDArray[np.float32], emission: NDArray[np.float32], mask: NDArray[np.bool_], p: Placement) -> None:
    """Multiply the image by ``1 + strength * falloff * colour``, in place: ``colour`` the flame's mean emission
    (scaled to max 1 when its brightest channel is at least :data:`OPAQUE_BRIGHTNESS`, by 1 / that otherwise), ``falloff`` a Gaussian of 1.2 x the sprite's larger side around the base of the flame,
    ``strength`` 0.8 x ``glow``."""
    if not mask.any():
        return
    colour = emission[mask].mean(axis=0)
    colour = colour / max(float(colour.max()), OPAQUE_BRIGHTNESS)  # a dim flame lights its surroundings dimly
    h, w = img.shape[:2]
    sigma = 1.2 * max(p.width, p.height)
    cx, cy = p.x + p.width / 2, p.y + 0.85 * p.height
    x0, x1 = int(max(cx - 3 * sigma, 0)), int(min(cx + 3 * sigma + 1, w))
    y0, y1 = int(max(cy - 3 * sigma, 0)), int(min(cy + 3 * sigma + 1, h))
    if x0 >= x1 or y0 >= y1:
        return
    gx = np.exp(-0.5 * ((np.arange(x0, x1, dtype=np.float32) - cx) / sigma) ** 2)
    gy = np.exp(-0.5 * ((np.arange(y0, y1, dtype=np.float32) - cy) / sigma) ** 2)
    light = 1.0 + (0.8 * p.glow) * (gy[:, None, None] * gx[None, :, None]) * colour.astype(np.float32)
    img[y0:y1, x0:x1] = np.minimum(img[y0:y1, x0:x1] * light, 1.0)


@dataclass(frozen=True)
class Composited:
    """The composite: (H, W, 3) uint8 image and, per placement, its final visible (H, W) bool flame and smoke masks
    (after clipping to the image and occlusion by later sprites)."""

    image: NDArray[np.uint8]
    flames: list[NDArray[np.bool_]]
    smoke: list[NDArray[np.bool_]]


def composite(background: NDArray[np.uint8], placements: Sequence[Placement]) -> Composited:
    """Composite ``placements`` in order onto the (H, W, 3) uint8 ``background`` (see the module docstring)."""
    h, w = background.shape[:2]
    img = background.astype(np.float32) / 255.0
    flames: list[NDArray[np.bool_]] = []
    smoke: list[NDArray[np.bool_]] = []
    for p in placements:
        over, emission, mask, smoke_mask = scaled_layers(p.sprite, p.width, p.height)
        full, full_smoke = np.zeros((h, w), bool), np.zeros((h, w), bool)
        c = _clip(p, w, h)
        if c is not None:
            ys, xs, sy, sx = c
            a = over[sy, sx, 3:4]
            light = emission[sy, sx]
            flame = (1.0 - a) * p.opacity * coverage(light.max(axis=-1, keepdims=True))
            if p.never_darken:
                flame = np.minimum(flame, _keeping_cover(luma(img[ys, xs]), luma(light), p.blend))
            cover = a + flame
            img[ys, xs] = img[ys, xs] * (1.0 - cover) + over[sy, sx, :3] * a
            img[ys, xs] = _add_light(img[ys, xs], light, p.blend)
            if p.glow > 0:
                if p.cast:
                    _cast(img, emission, mask, p)
                _glow(img, emission, p, c)
            full[ys, xs], full_smoke[ys, xs] = mask[sy, sx], smoke_mask[sy, sx]
            opaque = (over[sy, sx, 3] >= 0.5) | mask[sy, sx]
            for earlier in flames:
                earlier[ys, xs] &= ~opaque
            for earlier in smoke:  # later smoke takes over overlapping smoke: smoke masks stay disjoint
                earlier[ys, xs] &= ~(opaque | smoke_mask[sy, sx])
        flames.append(full)
        smoke.append(full_smoke)
    return Composited(np.round(img * 255.0).astype(np.uint8), flames, smoke)

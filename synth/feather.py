"""Soft sides for real cut-outs where the box cut through the fire.

A cut-out (:mod:`synth.cutouts`) is the flame mask of an annotator's box, and that mask often runs into the box's
sides: the annotator's box ends where the fire goes on, or a fire-lit wall fills the box. Pasted as it is, the
cut-out shows each such side as a straight, hard edge — a rectangle no flame has, the paste cue a detector can
learn (the contact sheets' "filled rectangles"). :func:`feathered` fades the sprite's alpha to zero towards every
side of its canvas (the box it was cut from) that its flame mask touches, with a smoothstep over ``fraction`` of the
canvas across that side (its width for the left and right sides, its height for the top and bottom); sides the mask
does not reach, and so the flame's own edges, are kept. The flame mask then keeps only pixels at least
:data:`KEEP_ALPHA` opaque, so a flame's box never spans the faded margin where nothing of it is seen.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from synth.ramps import smoothstep
from synth.sprites import Sprite

#: A faded cut-out pixel stays in the flame mask (and its box) while at least this opaque.
KEEP_ALPHA = 0.25


def side_ramp(mask: NDArray[np.bool_], fraction: float) -> NDArray[np.float32]:
    """(h, w) float32 in [0, 1]: 1 inside, falling to 0 (smoothstep) over ``fraction`` x the canvas's width
    (height) towards each left/right (top/bottom) side of the (h, w) bool ``mask``'s canvas that the mask touches
    (a pixel centre at distance d from a side gets ``smoothstep(d / (fraction x size))``); all ones when
    ``fraction`` is 0 or the mask touches no side."""
    h, w = mask.shape
    rows, cols = np.ones(h, np.float32), np.ones(w, np.float32)
    if fraction > 0.0:
        y, x = np.arange(h, dtype=np.float32) + 0.5, np.arange(w, dtype=np.float32) + 0.5
        for touches, dist, size, ramp in (
            (mask[0].any(), y, h, rows),
            (mask[-1].any(), h - y, h, rows),
            (mask[:, 0].any(), x, w, cols),
            (mask[:, -1].any(), w - x, w, cols),
        ):
            if touches:
                np.minimum(ramp, smoothstep(dist, 0.0, fraction * size), out=ramp)
    return rows[:, None] * cols[None, :]


def feathered(sprite: Sprite, fraction: float) -> Sprite:
    """``sprite`` (a cut-out on the whole canvas it was cut from) with its ``over`` alpha faded towards the sides
    its flame mask touches (:func:`side_ramp`) and its mask kept where the faded alpha is at least
    :data:`KEEP_ALPHA`; the colours, emission and canvas size are unchanged. ``fraction`` in [0, 0.5]."""
    if not 0.0 <= fraction <= 0.5:
        raise ValueError(f"a cut-out's feather must be in [0, 0.5] of its box, got {fraction}")
    ramp = side_ramp(sprite.mask, fraction)
    over = sprite.over.copy()
    alpha = np.round(over[..., 3].astype(np.float32) * ramp)
    over[..., 3] = alpha.astype(np.uint8)
    mask = sprite.mask & (alpha >= KEEP_ALPHA * 255.0)
    return Sprite(over, sprite.emission, mask)

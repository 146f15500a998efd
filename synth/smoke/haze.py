"""Haze: smoke that fills much of the view, as smoke fills a room or hangs across a street on a CCTV frame.

A plume (:mod:`synth.smoke.plume`) is one column of smoke over its source; the smoke that CCTV data boxes is
mostly haze, a veil over half of the frame or more (fire-smoke-608's median smoke box spans 53 % of the image).
A haze layer is a soft-edged veil: fractal value noise (the same as a plume's billows,
:func:`synth.smoke.plume.value_noise`) at a grain of a third of the canvas, its opacity ``opacity`` times
``0.35 + 0.65 body`` (``body`` the noise through a smoothstep: thick and thin patches, never a hole), faded to 0
over the outer fifth of the canvas on each side (a haze has no edge). Its RGB is a white shading (thicker patches
brighter), which the placement tints with the drawn smoke colour and the scene's light, as a simulated plume's.

Each frame is a :class:`synth.flames.sprites.Sprite` with an empty flame mask, no emission and ``smoke`` set, so
Method 2 judges and boxes it as any plume (its seen part at the smoke threshold, or erased when too faint).
"""

from __future__ import annotations

import numpy as np

from ground.image.imageio import unit_to_u8
from synth.compose.ramps import smoothstep
from synth.flames.sprites import Sprite
from synth.smoke.plume import value_noise

#: Haze canvas, cells (rows, cols): the compositor scales it to the haze's rectangle.
CANVAS = (96, 128)
#: Share of the canvas on each side over which a haze fades to nothing.
FADE = 0.2


def haze_sprite(opacity: float, rng: np.random.Generator) -> Sprite:
    """One haze sprite of peak opacity ``opacity`` (0..1) on a :data:`CANVAS` grid, its noise drawn from ``rng``
    (module docstring)."""
    if not 0.0 < opacity <= 1.0:
        raise ValueError(f"a haze's opacity must be in (0, 1], got {opacity}")
    rows, cols = CANVAS
    noise = value_noise(CANVAS, max(rows, cols) / 3.0, rng)
    body = smoothstep(noise, 0.25, 0.75)
    y = np.linspace(0.0, 1.0, rows, dtype=np.float32)[:, None]
    x = np.linspace(0.0, 1.0, cols, dtype=np.float32)[None, :]
    edge = smoothstep(np.minimum(x, 1.0 - x), 0.0, FADE) * smoothstep(np.minimum(y, 1.0 - y), 0.0, FADE)
    alpha = opacity * (0.35 + 0.65 * body) * edge
    shade = 0.8 + 0.2 * body
    over = np.dstack([unit_to_u8(np.repeat(shade[..., None], 3, axis=-1)), unit_to_u8(alpha)])
    return Sprite(over, np.zeros((rows, cols, 3), np.uint8), np.zeros((rows, cols), bool))

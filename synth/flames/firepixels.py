"""Fire-coloured pixels of a photograph: the colour rule that starts a flame cut-out (:mod:`synth.flames.cutouts`),
keeps flames out of a smoke matte (:mod:`synth.smoke.matte`) and measures flame colour (``synth colour``).

A pixel (channels in [0, 1]) is fire when it is warm (R > 0.5, R >= G >= 0.9 B, R - B > 0.25) or a bright core
(R > 0.8, G > 0.65, R >= B). Warm or bright surfaces lit by the fire pass it too, and so does white: the rule is a
start, never a mask by itself.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def fire_mask(rgb: NDArray[np.uint8]) -> NDArray[np.bool_]:
    """(h, w) bool: fire-coloured pixels of an (h, w, 3) RGB image (the rule in the module docstring)."""
    f = rgb.astype(np.float32) / 255.0
    r, g, b = f[..., 0], f[..., 1], f[..., 2]
    warm = (r > 0.5) & (r >= g) & (g >= 0.9 * b) & (r - b > 0.25)
    core = (r > 0.8) & (g > 0.65) & (r >= b)
    return warm | core

"""The smooth ramp every soft edge of the synthesis uses: a flame's coverage and body, its smoke's windows, the
exposed palette's bloom to white; and the soft window that takes a cut-out's or a matte's alpha to 0 on its box's
sides (:func:`window`).

Arrays of any shape; the result keeps the input's float type (NumPy's promotion with Python floats).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def smoothstep(x: NDArray[np.floating], lo: float = 0.0, hi: float = 1.0) -> NDArray[np.floating]:
    """``x`` through a smoothstep: 0 at or below ``lo``, 1 at or above ``hi``, ``3 r^2 - 2 r^3`` of
    ``r = (x - lo) / (hi - lo)`` between (``hi`` > ``lo``)."""
    r = np.clip((x - lo) / (hi - lo), 0.0, 1.0)
    return r * r * (3.0 - 2.0 * r)


def window(height: int, width: int, inner: float, power: float = 2.0) -> NDArray[np.float32]:
    """(height, width) float32 in [0, 1]: 1 inside ``inner`` of the way from the centre to the edge of the
    super-ellipse ``|u|^power + |v|^power = 1`` inscribed in the box (u, v = -1 and 1 at the centres of its outer
    pixels), falling smoothly to 0 on it (0 outside it: the corners, and every outer pixel). ``power`` 2 is an
    ellipse; a larger power keeps more of the box's corners."""
    v = np.linspace(-1.0, 1.0, height, dtype=np.float32) if height > 1 else np.zeros(1, np.float32)
    u = np.linspace(-1.0, 1.0, width, dtype=np.float32) if width > 1 else np.zeros(1, np.float32)
    r = (np.abs(u[None, :]) ** power + np.abs(v[:, None]) ** power) ** (1.0 / power)
    return (1.0 - smoothstep(r, inner, 1.0)).astype(np.float32)

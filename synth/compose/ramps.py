"""The smooth ramp every soft edge of the synthesis uses: a flame's coverage and body, its smoke's windows, the
exposed palette's bloom to white.

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

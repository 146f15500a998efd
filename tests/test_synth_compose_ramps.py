"""The shared smoothstep: its ends, its shape, and the float type it keeps."""

import numpy as np

from synth.compose.ramps import smoothstep


def test_smoothstep_is_flat_outside_its_bounds_monotone_and_symmetric_between() -> None:
    x = np.linspace(-1.0, 3.0, 401)
    y = smoothstep(x, 0.5, 2.5)
    assert np.all(y[x <= 0.5] == 0.0) and np.all(y[x >= 2.5] == 1.0)
    assert np.all(np.diff(y) >= 0.0)
    assert smoothstep(np.array([1.5]), 0.5, 2.5)[0] == 0.5
    centred = smoothstep(x, 0.0, 2.0)  # the ramp's middle is x's middle
    assert np.allclose(centred + centred[::-1], 1.0)
    assert np.allclose(smoothstep(np.array([0.25])), [0.15625])  # 3 r^2 - 2 r^3


def test_smoothstep_keeps_the_float_type() -> None:
    assert smoothstep(np.zeros(3, np.float32)).dtype == np.float32
    assert smoothstep(np.zeros(3, np.float64), 0.1, 0.2).dtype == np.float64


def test_the_window_is_one_inside_and_zero_on_the_boxs_sides_and_corners() -> None:
    from synth.compose.ramps import window

    w = window(9, 9, 0.55)
    assert w[4, 4] == 1.0 and w[0].max() == w[:, 0].max() == w[-1].max() == 0.0 and w.min() >= 0.0
    assert window(9, 9, 0.55, power=4.0)[1, 1] >= w[1, 1]  # a larger power keeps more of the corners

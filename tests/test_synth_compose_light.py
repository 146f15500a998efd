"""Linear light: display <-> linear round trip, the gamma, and Rec. 709 weights summing to one."""

from __future__ import annotations

import numpy as np

from synth.compose.light import GAMMA, REC709, luma, to_display, to_linear


def test_display_and_linear_light_round_trip_every_uint8_value() -> None:
    img = np.arange(256, dtype=np.uint8).reshape(16, 16, 1).repeat(3, axis=2)
    assert np.array_equal(to_display(to_linear(img)), img)
    assert to_linear(img).dtype == np.float32 and float(to_linear(img).max()) == 1.0


def test_half_the_light_is_not_half_the_display_value() -> None:
    mid = to_display(np.full((1, 1, 3), 0.5, np.float32))
    assert int(mid[0, 0, 0]) == round(255 * 0.5 ** (1 / GAMMA))  # 186, not 128


def test_luma_weights_sum_to_one_and_green_counts_most() -> None:
    assert abs(float(REC709.sum()) - 1.0) < 1e-6 and int(np.argmax(REC709)) == 1
    rgb = np.asarray([[1.0, 1.0, 1.0], [0.0, 1.0, 0.0]], np.float32)
    assert luma(rgb).shape == (2, 1) and np.allclose(luma(rgb)[:, 0], [1.0, 0.7152])

"""The fire colour rule: flames and their white cores are fire-coloured, sky and grey are not."""

from __future__ import annotations

import numpy as np

from synth.flames.firepixels import fire_mask

ORANGE, CORE, BLUE, GREY = (240, 120, 20), (255, 240, 200), (30, 60, 200), (128, 128, 128)


def test_the_colour_rule_takes_flames_and_their_core_not_sky_or_grey() -> None:
    px = np.array([[ORANGE, CORE, BLUE, GREY, (255, 255, 255)]], np.uint8)
    assert fire_mask(px).tolist() == [[True, True, False, False, True]]  # white passes: a start, not a mask

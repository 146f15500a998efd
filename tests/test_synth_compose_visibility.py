"""Visibility of a composited flame: contrast against the flame-free plate, on constructed composites."""

from __future__ import annotations

import numpy as np

from synth.compose import visibility as V
from synth.compose.composite import Placement, composite
from synth.flames.sprites import Sprite


def _flame(colour: tuple[int, int, int], h: int = 12, w: int = 8) -> Sprite:
    emission = np.zeros((h, w, 3), np.uint8)
    emission[:] = colour
    return Sprite(np.zeros((h, w, 4), np.uint8), emission, np.ones((h, w), bool))


def _seen(background: np.ndarray, colour: tuple[int, int, int]) -> V.Visibility:
    out = composite(background, [Placement(_flame(colour), 10, 10, 8, 12, "screen", glow=0.0, opacity=1.0)])
    return V.measure(V.delta_e(out.image, background), out.flames[0])


def test_delta_e_is_zero_on_equal_images_and_large_on_black_vs_white():
    grey = np.full((4, 4, 3), 128, np.uint8)
    assert np.all(V.delta_e(grey, grey) == 0.0)
    assert np.allclose(V.delta_e(np.zeros_like(grey), np.full_like(grey, 255)), 100.0, atol=0.5)  # L* 0 vs 100


def test_a_faint_flame_on_a_bright_wall_is_not_seen_and_a_bright_one_is():
    wall = np.full((40, 40, 3), 235, np.uint8)
    faint = _seen(wall, (40, 12, 0))  # a dim red flame on a sunlit wall
    assert faint.pixels == 96 and faint.contrast < V.MIN_DELTA_E and not faint.visible
    bright = _seen(wall, (255, 200, 60))  # a yellow flame on the same wall
    assert bright.visible and bright.seen == 96 and bright.contrast > 3 * V.MIN_DELTA_E
    dark = np.full((40, 40, 3), 20, np.uint8)
    assert _seen(dark, (40, 12, 0)).visible  # the dim flame shows in the dark


def test_the_rule_needs_enough_seen_pixels_and_share():
    delta = np.zeros((20, 20), np.float32)
    mask = np.zeros((20, 20), bool)
    mask[:10, :10] = True  # 100 pixels
    delta[:3, :10] = 50.0  # 30 seen: 30 %
    v = V.measure(delta, mask)
    assert v.seen == 30 and v.visible and np.array_equal(v.part, mask & (delta > 0))
    delta[2, :] = 0.0  # 20 seen: 20 %
    assert not V.measure(delta, mask).visible
    tiny = np.zeros((20, 20), bool)
    tiny[:3, :5] = True  # 15 pixels, all seen: too small to notice
    assert not V.measure(np.full((20, 20), 80.0, np.float32), tiny).visible
    assert V.measure(delta, np.zeros((20, 20), bool)).contrast == 0.0

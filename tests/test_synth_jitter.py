"""Per-flame jitter: draws in their ranges and always four, mirror and recolour keep the flame's pixels and
brightness, the hue turns by the drawn angle."""

from __future__ import annotations

import cv2
import numpy as np

from synth.jitter import HUE_DEG, SATURATION, STRETCH, Jitter, draw_jitter, jittered, recoloured, stretched_width
from synth.sprites import Sprite


def _sprite() -> Sprite:
    rng = np.random.default_rng(0)
    mask = np.zeros((20, 12), bool)
    mask[4:18, 2:7] = True  # a flame on the left half
    emission = np.zeros((20, 12, 3), np.uint8)
    emission[mask] = (240, 120, 20)  # orange
    over = np.zeros((20, 12, 4), np.uint8)
    over[:5, :, :3], over[:5, :, 3] = 90, rng.integers(0, 200, (5, 12))  # grey smoke above
    return Sprite(over, emission, mask)


def test_draws_stay_in_their_ranges_and_take_four_draws() -> None:
    rng, twin = np.random.default_rng(1), np.random.default_rng(1)
    draws = [draw_jitter(rng) for _ in range(500)]
    twin.random(4 * 500)
    assert rng.random() == twin.random()
    assert all(STRETCH[0] <= j.stretch <= STRETCH[1] for j in draws)
    assert all(HUE_DEG[0] <= j.hue <= HUE_DEG[1] and SATURATION[0] <= j.saturation <= SATURATION[1] for j in draws)
    assert 150 < sum(j.mirror for j in draws) < 350
    assert stretched_width(100, Jitter(False, 0.75, 0.0, 1.0)) == 75 and stretched_width(1, draws[0]) == 2


def test_no_jitter_is_the_same_sprite_and_a_mirror_flips_every_layer() -> None:
    s = _sprite()
    same = jittered(s, Jitter(False, 1.0, 0.0, 1.0))
    assert np.array_equal(same.over, s.over) and np.array_equal(same.emission, s.emission)
    flipped = jittered(s, Jitter(True, 1.0, 0.0, 1.0))
    assert np.array_equal(flipped.mask, s.mask[:, ::-1]) and np.array_equal(flipped.over, s.over[:, ::-1])
    assert np.array_equal(flipped.emission, s.emission[:, ::-1])


def test_recolouring_turns_the_hue_keeps_the_brightness_and_the_mask() -> None:
    s = _sprite()
    turned = jittered(s, Jitter(False, 1.0, 10.0, 1.0))
    assert np.array_equal(turned.mask, s.mask) and np.array_equal(turned.over[..., 3], s.over[..., 3])
    hue = lambda rgb: int(cv2.cvtColor(rgb.reshape(1, 1, 3), cv2.COLOR_RGB2HSV_FULL)[0, 0, 0]) * 360 / 256  # noqa: E731
    before, after = hue(s.emission[10, 4]), hue(turned.emission[10, 4])
    assert abs((after - before) - 10.0) < 2.0  # towards yellow by the drawn angle (hue quantised to 1.4 degrees)
    assert abs(int(turned.emission[10, 4].max()) - 240) <= 1  # value kept
    assert not turned.emission[~s.mask].any()  # black stays black
    grey = recoloured(np.full((2, 2, 3), 90, np.uint8), 10.0, 1.2)
    assert np.array_equal(grey, np.full((2, 2, 3), 90, np.uint8))  # no saturation to turn

"""Auto exposure with the fire in view: no flame keeps the exposure, larger and brighter flames lower it within
its floor, the meter keeps the frame's mean linear luminance, and the flame share counts covered pixels once."""

from __future__ import annotations

import numpy as np
import pytest

from synth.compose.composite import Placement
from synth.compose.effects import scale_light
from synth.compose.metering import MIN_GAIN, RADIANCE, draw_radiance, flame_share, mean_linear_luma, metered_gain
from synth.flames.sprites import Sprite


def _flame(w: int, h: int) -> Sprite:
    over = np.zeros((h, w, 4), np.uint8)
    emission = np.full((h, w, 3), (255, 180, 40), np.uint8)
    return Sprite(over=over, emission=emission, mask=np.ones((h, w), bool))


def test_no_flame_keeps_the_exposure_and_more_light_lowers_it_to_its_floor() -> None:
    assert metered_gain(0.4, 0.0, 8.0) == 1.0
    by_share = [metered_gain(0.4, a, 8.0) for a in (0.01, 0.05, 0.2)]
    by_radiance = [metered_gain(0.4, 0.05, r) for r in (4.0, 8.0, 16.0)]
    assert by_share == sorted(by_share, reverse=True) and by_radiance == sorted(by_radiance, reverse=True)
    assert metered_gain(0.4, 0.9, 16.0) == MIN_GAIN and metered_gain(0.0, 0.5, 16.0) == MIN_GAIN
    assert metered_gain(0.9, 0.05, 4.0) > metered_gain(0.1, 0.05, 4.0)  # a bright scene: the flame moves it less


def test_the_meter_keeps_the_frames_mean_linear_luminance() -> None:
    m, a, r = 0.5, 0.1, 6.0
    g = metered_gain(m, a, r)
    assert MIN_GAIN < g < 1.0
    assert g * (m * (1 - a) + a * r) == pytest.approx(m)


def test_scale_light_scales_linear_light_and_keeps_the_image_at_gain_one() -> None:
    img = np.random.default_rng(0).integers(0, 256, (8, 8, 3), dtype=np.uint8)
    assert scale_light(img, 1.0) is img
    half = scale_light(img, 0.5)
    assert half.dtype == np.uint8 and (half <= img).all()
    assert mean_linear_luma(half) == pytest.approx(0.5 * mean_linear_luma(img), rel=0.02)


def test_flame_share_counts_each_covered_pixel_once_inside_the_image() -> None:
    sprite = _flame(10, 10)
    one = Placement(sprite, 0, 0, 10, 10)
    assert flame_share([one], 20, 10) == pytest.approx(0.5)
    assert flame_share([one, one], 20, 10) == pytest.approx(0.5)  # overlaps once
    assert flame_share([Placement(sprite, -5, 0, 10, 10)], 20, 10) == pytest.approx(0.25)  # clipped
    assert flame_share([Placement(sprite, 30, 0, 10, 10)], 20, 10) == 0.0  # outside
    assert flame_share([], 20, 10) == 0.0


def test_radiance_is_drawn_in_its_range_from_the_rng() -> None:
    draws = [draw_radiance(np.random.default_rng(s)) for s in range(200)]
    assert RADIANCE[0] <= min(draws) and max(draws) <= RADIANCE[1]
    assert draw_radiance(np.random.default_rng(7)) == draw_radiance(np.random.default_rng(7))

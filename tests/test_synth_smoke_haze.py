"""Haze sprites: a soft veil of the asked opacity with no edge, thick and thin patches but no hole, reproducible."""

from __future__ import annotations

import numpy as np
import pytest

from synth.smoke.haze import CANVAS, haze_sprite


def test_a_haze_is_a_veil_without_an_edge_or_a_hole() -> None:
    sprite = haze_sprite(0.6, np.random.default_rng(0))
    alpha = sprite.over[..., 3].astype(np.float32) / 255.0
    assert sprite.size == (CANVAS[1], CANVAS[0]) and not sprite.mask.any() and sprite.smoke
    assert alpha.max() <= 0.6 + 1 / 255 and alpha.max() > 0.45  # its peak is the opacity asked
    assert alpha[0].max() == alpha[-1].max() == alpha[:, 0].max() == alpha[:, -1].max() == 0.0  # faded to nothing
    core = alpha[CANVAS[0] // 4 : -CANVAS[0] // 4, CANVAS[1] // 4 : -CANVAS[1] // 4]
    assert core.min() >= 0.35 * 0.6 * 0.9 and core.std() > 0.02  # thick and thin patches, never a hole
    assert (sprite.over[..., :3][..., 0] == sprite.over[..., :3][..., 2]).all()  # a white shading, tinted later


def test_the_same_rng_makes_the_same_haze_and_a_bad_opacity_is_refused() -> None:
    a, b = (haze_sprite(0.4, np.random.default_rng(3)).over for _ in range(2))
    assert np.array_equal(a, b) and not np.array_equal(a, haze_sprite(0.4, np.random.default_rng(4)).over)
    for bad in (0.0, 1.5):
        with pytest.raises(ValueError, match="opacity"):
            haze_sprite(bad, np.random.default_rng(0))

"""synth.feather: cut-outs faded only towards the box sides their flame touches."""

from __future__ import annotations

import numpy as np
import pytest

from synth.feather import KEEP_ALPHA, feathered, side_ramp
from synth.sprites import Sprite


def _sprite(mask: np.ndarray) -> Sprite:
    over = np.zeros(mask.shape + (4,), np.uint8)
    over[mask] = (250, 160, 40, 255)
    return Sprite(over, np.zeros(mask.shape + (3,), np.uint8), mask.copy())


def test_the_ramp_falls_only_towards_the_sides_the_mask_touches() -> None:
    mask = np.zeros((40, 60), bool)
    mask[10:30, 0:30] = True  # touches the left side only
    ramp = side_ramp(mask, 0.2)
    assert np.allclose(ramp, ramp[:1])  # no fall along the rows: top and bottom untouched
    assert ramp[0, 0] < 0.01 and np.all(ramp[:, 12:] == 1.0)  # 0.2 x 60 px = 12 px from the left side
    assert np.all(np.diff(ramp[0, :12]) > 0)  # rising away from the side
    assert np.all(side_ramp(mask, 0.0) == 1.0)
    inner = np.zeros((40, 60), bool)
    inner[5:35, 5:55] = True
    assert np.all(side_ramp(inner, 0.3) == 1.0)  # a flame inside its box keeps its own edges


def test_a_filled_box_fades_on_all_four_sides_and_keeps_its_middle() -> None:
    full = _sprite(np.ones((50, 40), bool))
    soft = feathered(full, 0.2)
    alpha = soft.over[..., 3]
    assert alpha[25, 20] == 255 and alpha[0].max() < 8 and alpha[:, 0].max() < 8 and alpha[-1].max() < 8
    assert np.array_equal(soft.over[..., :3], full.over[..., :3]) and soft.size == full.size
    assert np.all(alpha <= full.over[..., 3])  # feathering only takes opacity away
    assert np.array_equal(soft.mask, full.mask & (alpha >= KEEP_ALPHA * 255))  # no box over the faded margin
    rows, cols = np.nonzero(soft.mask.any(axis=1))[0], np.nonzero(soft.mask.any(axis=0))[0]
    assert 0 < rows[0] < 5 and 0 < cols[0] < 4  # the box shrinks by part of the 10 / 8 px ramps, not all of them


def test_no_feather_and_a_free_flame_change_nothing() -> None:
    mask = np.zeros((30, 30), bool)
    mask[8:20, 10:22] = True
    sprite = _sprite(mask)
    for soft in (feathered(sprite, 0.0), feathered(sprite, 0.4)):
        assert np.array_equal(soft.over, sprite.over) and np.array_equal(soft.mask, sprite.mask)
    with pytest.raises(ValueError, match=r"\[0, 0.5\]"):
        feathered(sprite, 0.6)

"""Simulated plumes: soft smoke that rises, widens and thins with height, moves from frame to frame, never cut by its
canvas, and the same plume from the same seed."""

from __future__ import annotations

import numpy as np
import pytest

from synth.flames.sprites import is_smoke
from synth.smoke.plume import PlumeParams, plume_library, plume_sequence, sample_plume, value_noise

LIBRARY = plume_library(8, seed=0)


def test_a_plume_is_smoke_alone_with_soft_alpha_that_no_canvas_side_cuts() -> None:
    for seq in LIBRARY:
        assert is_smoke(seq) and len(seq.sprites) == 8 and seq.meta["generator"] == "plume"
        for sp in seq.sprites:
            assert not sp.mask.any() and not sp.emission.any() and sp.smoke  # no flame, no light
            alpha = sp.over[..., 3]
            assert alpha.max() >= 100 and sp.smoke_mask().any()  # dense enough to be seen somewhere
            assert max(alpha[0].max(), alpha[:, 0].max(), alpha[:, -1].max()) <= 2  # faded before any side


def _bands(alpha: np.ndarray, threshold: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Per quarter of the height, bottom first: (mean width of the rows above ``threshold``, mean opacity of the
    pixels above it)."""
    bands = np.array_split(alpha[::-1], 4)
    widths = np.array([(b > threshold).sum(axis=1).mean() for b in bands])
    return widths, np.array([b[b > threshold].mean() for b in bands])


def test_plumes_widen_and_thin_with_height() -> None:
    found = [_bands(np.stack([sp.over[..., 3] for sp in seq.sprites]).mean(axis=0) / 255.0) for seq in LIBRARY]
    widths, densities = np.mean([w for w, _ in found], axis=0), np.mean([d for _, d in found], axis=0)
    assert widths[2] > 1.3 * widths[0]  # wider two quarters up than at the source (Morton, Taylor & Turner)
    assert densities[3] < densities[0]  # and thinner at the top


def test_the_frames_of_a_plume_move_and_the_same_seed_draws_the_same_plume() -> None:
    seq = LIBRARY[0]
    assert all(not np.array_equal(a.over, b.over) for a, b in zip(seq.sprites, seq.sprites[1:]))
    again = plume_library(8, seed=0)[0]
    assert all(np.array_equal(a.over, b.over) for a, b in zip(seq.sprites, again.sprites))
    assert not np.array_equal(plume_library(1, seed=1)[0].sprites[0].over, seq.sprites[0].over)


def test_value_noise_spans_the_unit_range_and_plume_parameters_are_checked() -> None:
    rng = np.random.default_rng(0)
    n = value_noise((40, 30), 8.0, rng)
    assert n.shape == (40, 30) and n.min() == 0.0 and n.max() == pytest.approx(1.0)
    p = sample_plume(np.random.default_rng(3), frames=2)
    assert 0.18 <= p.spread <= 0.28 and len(plume_sequence("x", p, rng).sprites) == 2
    with pytest.raises(ValueError, match="at least 8 x 8 cells"):
        PlumeParams(rows=4)
    with pytest.raises(ValueError, match="density, thinning must be > 0"):
        PlumeParams(density=0.0)

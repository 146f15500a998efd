"""Camera rules: free-floor positions and the flat-view check."""

from __future__ import annotations

import numpy as np
import pytest

from synth.places import camera as C


def test_positions_place_the_eye_in_their_squares() -> None:
    rule = C.CameraRule((0, 10, 0, 10), (1.5, 1.6), positions=((1.0, 2.0), (8.0, 8.0)), cell=0.2)
    eyes = np.array([C.sample_view(rule, np.random.default_rng(k)).pose[:3, 3] for k in range(200)])
    near_a = (np.abs(eyes[:, 0] - 1.0) <= 0.1) & (np.abs(eyes[:, 2] - 2.0) <= 0.1)
    near_b = (np.abs(eyes[:, 0] - 8.0) <= 0.1) & (np.abs(eyes[:, 2] - 8.0) <= 0.1)
    assert (near_a | near_b).all() and near_a.any() and near_b.any()
    assert ((eyes[:, 1] >= 1.5) & (eyes[:, 1] <= 1.6)).all()


def test_area_rules_draw_as_before() -> None:
    """Procedural scenes keep their exact draws (datasets made before positions existed stay identical)."""
    rule = C.CameraRule((-1, 1, -2, 2))
    rng = np.random.default_rng(7)
    view = C.sample_view(rule, rng)
    rng = np.random.default_rng(7)
    x, h, z = rng.uniform(-1, 1), rng.uniform(1.2, 2.6), rng.uniform(-2, 2)
    assert np.allclose(view.pose[:3, 3], (x, h, z))


@pytest.mark.parametrize(
    ("depth", "blocked"),
    [
        (np.full((20, 20), 3.0, np.float32), True),  # one flat wall
        (np.tile(np.linspace(1, 8, 20, dtype=np.float32), (20, 1)), False),  # a room in depth
        (np.where(np.arange(20)[:, None] < 15, 0, 4.0).repeat(20, 1).astype(np.float32), True),  # mostly sky
    ],
)
def test_flat_or_empty_views_are_rejected_when_asked(depth: np.ndarray, blocked: bool) -> None:
    assert C.view_blocked(depth, C.CameraRule((0, 0, 0, 0), min_depth_spread=0.5, max_empty=0.5)) is blocked
    assert C.view_blocked(depth, C.CameraRule((0, 0, 0, 0))) is False  # procedural rules: no depth check


def test_find_view_also_asks_accept_and_keeps_the_old_draws_without_it() -> None:
    from synth.places.camera import CameraRule, find_view

    rule = CameraRule((-1, 1, -1, 1))
    flat = np.linspace(1, 5, 48 * 64, dtype=np.float32).reshape(48, 64)
    seen: list = []

    def third(view, depth) -> bool:
        seen.append(view)
        return len(seen) == 3

    chosen = find_view(rule, np.random.default_rng(0), lambda v: flat, accept=third)
    assert chosen is seen[2]
    plain = find_view(rule, np.random.default_rng(0), lambda v: flat)
    assert np.array_equal(plain.pose, seen[0].pose)  # the same first draw: accept changes nothing else

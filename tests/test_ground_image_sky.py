"""Sky: a smooth blue, overcast or night-black region connected to the top edge, and nothing in a busy room."""

from __future__ import annotations

import numpy as np

from ground.image.sky import sky_like, sky_mask, top_connected


def test_a_clear_sky_over_busy_ground_is_found_and_a_room_has_none() -> None:
    rng = np.random.default_rng(0)
    ground = np.clip(100 + rng.normal(0, 40, (80, 100, 1)).repeat(3, axis=2), 0, 255).astype(np.uint8)
    photo = ground.copy()
    photo[:30] = (110, 160, 230)
    sky = sky_mask(photo)
    assert sky[:28].mean() > 0.95 and sky[40:].mean() < 0.02
    assert sky_mask(ground).mean() < 0.02


def test_only_the_parts_touching_the_top_count() -> None:
    mask = np.zeros((10, 10), dtype=bool)
    mask[0:3, 0:4] = True  # touches the top
    mask[6:9, 6:9] = True  # a smooth patch lower down: a wall, not sky
    kept = top_connected(mask)
    assert kept[0:3, 0:4].all() and not kept[6:9, 6:9].any()
    assert sky_like(np.zeros((20, 20, 3), np.uint8)).all()  # a black night sky is sky-like

"""Sites: sidecars checked, sky and water kept off the ground, the horizon where the sky ends, depth on the ground."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from synth.places.sites import (
    MAX_GROUND_M,
    detect_people,
    estimate_site,
    polygon_mask,
    read_site_sidecar,
    sky_like,
)


def _outdoor(h: int = 120, w: int = 160, horizon: int = 50, lake: bool = False) -> np.ndarray:
    """Smooth blue sky above ``horizon``, textured brown ground below (a smooth blue lake in the lower left)."""
    rng = np.random.default_rng(0)
    img = np.empty((h, w, 3), np.uint8)
    img[:horizon] = (90, 150, 230)
    img[horizon:] = np.clip(rng.normal((120, 90, 60), 40, (h - horizon, w, 3)), 0, 255).astype(np.uint8)
    if lake:
        img[h - 30 :, : w // 2] = (80, 140, 220)
    return img


def test_sky_ends_at_the_horizon_and_water_is_not_ground() -> None:
    site = estimate_site(_outdoor(lake=True), np.random.default_rng(0))
    assert site.source == "estimate" and abs(site.horizon - 50) <= 4  # the 5-px texture window blurs the edge
    assert not site.ground[:46].any() and site.ground[60:90].mean() > 0.9
    assert site.ground[-25:, : 80 - 5].mean() < 0.05  # the lake
    assert site.ground[-25:, 85:].mean() > 0.9


def test_a_room_without_sky_gets_a_drawn_horizon() -> None:
    rng = np.random.default_rng(1)
    room = np.clip(rng.normal(128, 50, (120, 160, 3)), 0, 255).astype(np.uint8)
    horizons = {estimate_site(room, np.random.default_rng(s)).horizon for s in range(3)}
    assert all(0.3 * 120 <= h <= 0.5 * 120 for h in horizons) and len(horizons) == 3
    assert not sky_like(room).any()


def test_depth_on_the_ground_follows_the_camera_height() -> None:
    site = estimate_site(_outdoor(), np.random.default_rng(0), {"horizon": 0.5, "camera_height": 2.0})
    fy = 100.0
    depth = site.depth(120, fy, 60.0, site.ground)
    assert (depth[:60] == 0).all()
    assert depth[100, 10] == pytest.approx(2.0 * fy / (100.5 - 60), rel=1e-5)
    assert depth.max() <= MAX_GROUND_M


def test_sidecars_are_checked_and_found(tmp_path: Path) -> None:
    photo = tmp_path / "cam1.jpg"
    assert read_site_sidecar(photo) is None
    (tmp_path / "_site.yaml").write_text("horizon: 0.3\nyfov: 70\n")
    assert read_site_sidecar(photo) == {"horizon": 0.3, "yfov": 70.0}
    (tmp_path / "cam1.yaml").write_text("camera_height: 3\nground: [[0, 0.5], [1, 0.5], [1, 1]]\n")
    assert read_site_sidecar(photo) == {"camera_height": 3.0, "ground": [[0.0, 0.5], [1.0, 0.5], [1.0, 1.0]]}
    for text, message in (
        ("horizn: 0.3\n", "unknown key 'horizn'"),
        ("camera_height: -1\n", "camera_height must be a number"),
        ("ground: [[0, 1]]\n", "ground must be a list of >= 3"),
        ("- 1\n", "a site sidecar is a mapping"),
    ):
        (tmp_path / "cam1.yaml").write_text(text)
        with pytest.raises(ValueError, match=message) as err:
            read_site_sidecar(photo)
        assert str(tmp_path / "cam1.yaml") in str(err.value)


def test_a_sidecar_ground_polygon_and_camera_win_over_the_estimate() -> None:
    poly = [[0.0, 0.7], [0.5, 0.7], [0.5, 1.0], [0.0, 1.0]]
    site = estimate_site(_outdoor(), np.random.default_rng(0), {"ground": poly, "yfov": 45})
    assert site.source == "sidecar" and site.yfov == pytest.approx(math.radians(45))
    assert np.array_equal(site.ground, polygon_mask(poly, 160, 120) & (np.arange(120)[:, None] >= site.horizon))
    assert site.ground[100, 20] and not site.ground[100, 120] and not site.ground[60, 20]


def test_no_people_on_a_plain_picture() -> None:
    assert detect_people(_outdoor(240, 320)) == ()
    assert detect_people(np.zeros((60, 80, 3), np.uint8)) == ()

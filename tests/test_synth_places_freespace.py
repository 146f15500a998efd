"""Free floor found by rendering: floor height, furniture kept clear, inside the walls, deterministic."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from factories import write_textured_room

from synth.places import render as R
from synth.places import scenes as S
from synth.places.envfile import environment_file, load_meshes, mesh_bounds
from synth.places.freespace import find_floor, free_space, height_map, linear_ortho_depth, spread_points


@pytest.fixture(scope="module")
def renderer():
    with R.Renderer(120, 100) as r:
        yield r


def _scene(renderer, path: Path):
    meshes = load_meshes(environment_file(path))
    env = S.Environment("t", "file", None)
    env.meshes = meshes
    return S.to_pyrender(env, renderer.pyrender), mesh_bounds(meshes)


def test_orthographic_depth_is_linear_again() -> None:
    znear, zfar = 1e-3, 7.0
    true = np.array([[0.0, 0.5], [3.2, 6.9]], np.float32)
    ndc = (2 * true - zfar - znear) / (zfar - znear)  # what an orthographic projection stores (linear)
    pyrender_like = np.where(true > 0, 2 * znear * zfar / (zfar + znear - ndc * (zfar - znear)), 0)
    assert np.allclose(linear_ortho_depth(pyrender_like.astype(np.float32), znear, zfar), true, atol=1e-4)


def test_height_map_sees_floor_and_table_from_above(renderer, tmp_path: Path) -> None:
    scene, bounds = _scene(renderer, write_textured_room(tmp_path / "room.glb"))
    hm = height_map(renderer, scene, bounds, 1.3)  # below the ceiling: it is behind the camera
    finite = hm.heights[np.isfinite(hm.heights)]
    assert set(np.round(finite, 2)) <= {0.01, 0.8}
    rows, cols = np.nonzero(np.isclose(hm.heights, 0.8, atol=0.01))
    xz = hm.world(rows, cols)
    assert (np.abs(xz - 1.5) <= 0.6 + hm.cell).all() and len(xz) * hm.cell**2 == pytest.approx(1.44, rel=0.2)
    assert find_floor([hm]) == pytest.approx(0.01, abs=0.011)


def test_free_floor_keeps_clear_of_table_and_walls(renderer, tmp_path: Path) -> None:
    scene, bounds = _scene(renderer, write_textured_room(tmp_path / "room.glb"))
    space = free_space(renderer, scene, bounds, eye_height=1.3, clearance=0.5)
    x, z = space.positions.T
    assert space.floor == pytest.approx(0.01, abs=0.011)
    assert (np.abs(x) < 3 - 0.5 + space.cell).all() and (np.abs(z) < 3 - 0.5 + space.cell).all()
    table_gap = np.maximum(np.abs(x - 1.5) - 0.6, np.abs(z - 1.5) - 0.6)
    assert table_gap.min() >= 0.5 - 2 * space.cell
    assert 20 < space.area_m2 < 25  # (6 - 1)^2 minus the table with its margin
    assert np.allclose(space.targets[:, 1], 0.8, atol=0.01)  # the camera looks at the furniture
    again = free_space(renderer, scene, bounds, eye_height=1.3, clearance=0.5)
    assert np.array_equal(again.positions, space.positions) and np.array_equal(again.targets, space.targets)


def test_without_walls_a_scene_is_outdoor_or_nothing(renderer, tmp_path: Path) -> None:
    scene, bounds = _scene(renderer, write_textured_room(tmp_path / "yard.glb", walls=False))
    with pytest.raises(ValueError, match="outdoor: true"):
        free_space(renderer, scene, bounds, eye_height=1.3, clearance=0.5)
    space = free_space(renderer, scene, bounds, eye_height=1.3, clearance=0.5, outdoor=True)
    assert len(space.positions) > 100


def test_spread_points_cover_the_extremes() -> None:
    grid = np.stack(np.meshgrid(np.arange(11.0), np.arange(11.0)), -1).reshape(-1, 2)
    chosen = spread_points(grid, 5)
    assert len({tuple(p) for p in chosen}) == 5
    assert {(0.0, 0.0), (10.0, 10.0), (0.0, 10.0), (10.0, 0.0)} <= {tuple(p) for p in chosen}
    assert len(spread_points(grid[:3], 5)) == 3

"""Standing surfaces: a floor seen from eye height carries flames, a wall and the sky do not; points round-trip."""

from __future__ import annotations

import numpy as np

from synth.places.camera import pose_from_angles
from synth.places.render import intrinsics, project
from synth.places.standing import standing_mask, world_points


def _room_depth(pose: np.ndarray, yfov: float, w: int, h: int, wall_z: float) -> np.ndarray:
    """Depth along the view axis of a floor (y = 0) and a wall (z = wall_z) in front of the camera; sky = 0."""
    k = intrinsics(yfov, w, h)
    u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    rays = np.stack([(u - k[0, 2]) / k[0, 0], -(v - k[1, 2]) / k[1, 1], -np.ones_like(u)], -1) @ pose[:3, :3].T
    eye = pose[:3, 3]
    t_floor = np.where(rays[..., 1] < 0, -eye[1] / np.minimum(rays[..., 1], -1e-12), np.inf)
    t_wall = np.where(rays[..., 2] < 0, (wall_z - eye[2]) / np.minimum(rays[..., 2], -1e-12), np.inf)
    t = np.minimum(t_floor, t_wall)
    t = np.where(np.isfinite(t) & (t < 50), t, 0.0)  # t is depth along the view axis: rays have z_cam = -1
    return t.astype(np.float32)


def test_the_floor_stands_and_the_wall_does_not() -> None:
    pose = pose_from_angles(np.array([0.0, 1.6, 0.0]), 0.0, np.deg2rad(-25))
    yfov, w, h = np.deg2rad(60), 96, 72
    depth = _room_depth(pose, yfov, w, h, wall_z=-4.0)
    mask = standing_mask(depth, pose, yfov)
    points = world_points(depth, pose, yfov)
    floor = (np.abs(points[..., 1]) < 1e-6) & (depth > 0)
    wall = (np.abs(points[..., 2] + 4.0) < 1e-6) & (points[..., 1] > 0.05) & (depth > 0)
    assert floor.sum() > 1000 and wall.sum() > 500
    assert mask[floor].mean() > 0.8 and not mask[wall].any() and not mask[depth == 0].any()


def test_world_points_project_back_to_their_pixels() -> None:
    pose = pose_from_angles(np.array([1.0, 2.0, 3.0]), 0.4, np.deg2rad(-10))
    yfov, w, h = np.deg2rad(55), 40, 30
    depth = np.random.default_rng(0).uniform(1, 9, (h, w)).astype(np.float32)
    points = world_points(depth, pose, yfov).reshape(-1, 3)
    uvd = project(points, pose, intrinsics(yfov, w, h))
    u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    assert np.allclose(uvd[:, 0], u.ravel(), atol=1e-6) and np.allclose(uvd[:, 1], v.ravel(), atol=1e-6)
    assert np.allclose(uvd[:, 2], depth.ravel(), rtol=1e-6)

"""Camera rules (after the paper's Method 2 set-up): the camera moves in an area of the floor plane, within a
height range, looks towards one of the scene's targets with limited pitch and no roll (the horizon stays
horizontal); views blocked by a nearby wall (too many pixels closer than ``min_clearance``), showing mostly
nothing (``max_empty``) or only a flat surface (depth spread below ``min_depth_spread``) are rejected.

World frame: +Y up, floor at y = 0; ``area`` is ``(x_min, x_max, z_min, z_max)`` in metres. A rule may instead
list free floor ``positions`` ((x, z) centres of ``cell``-metre squares, found by :mod:`synth.places.freespace`): the
camera then stands in one of those squares.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class CameraRule:
    area: tuple[float, float, float, float]
    height: tuple[float, float] = (1.2, 2.6)
    targets: tuple[tuple[float, float, float], ...] = ((0.0, 0.5, 0.0),)
    max_pitch_deg: float = 20.0
    yaw_jitter_deg: float = 15.0
    yfov_deg: tuple[float, float] = (50.0, 70.0)
    min_clearance: float = 0.7  # metres
    max_blocked: float = 0.3  # fraction of pixels allowed closer than min_clearance
    min_depth_spread: float = 0.0  # metres between the 10th and 90th depth percentile (0 = no check)
    max_empty: float = 1.0  # fraction of pixels allowed to show nothing (sky, void)
    positions: tuple[tuple[float, float], ...] = ()  # free (x, z) squares; empty = anywhere in ``area``
    cell: float = 0.0  # side of a position's square, metres

    def __post_init__(self) -> None:
        x0, x1, z0, z1 = self.area
        if x1 < x0 or z1 < z0 or self.height[1] < self.height[0] or not self.targets:
            raise ValueError(f"invalid camera rule: area {self.area}, height {self.height}, targets {self.targets}")


@dataclass(frozen=True)
class CameraView:
    pose: NDArray[np.float64]  # (4, 4) camera-to-world
    yfov: float  # radians

    def to_json(self) -> dict:
        return {"pose": np.round(self.pose, 6).tolist(), "yfov": round(float(self.yfov), 6)}


def pose_from_angles(eye: NDArray[np.float64], yaw: float, pitch: float) -> NDArray[np.float64]:
    """(4, 4) pose at ``eye`` looking along yaw (radians about +Y, 0 = towards -Z) and pitch (up > 0), roll 0."""
    forward = np.array([-np.sin(yaw) * np.cos(pitch), np.sin(pitch), -np.cos(yaw) * np.cos(pitch)])
    z = -forward
    x = np.array([np.cos(yaw), 0.0, -np.sin(yaw)])
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, eye
    return pose


def sample_view(rule: CameraRule, rng: np.random.Generator) -> CameraView:
    """A random view obeying ``rule`` (not yet checked for blocking)."""
    if rule.positions:
        x, z = rule.positions[int(rng.integers(len(rule.positions)))]
        jitter = rng.uniform(-0.5, 0.5, 2) * rule.cell
        eye = np.array([x + jitter[0], rng.uniform(*rule.height), z + jitter[1]])
    else:
        x0, x1, z0, z1 = rule.area
        eye = np.array([rng.uniform(x0, x1), rng.uniform(*rule.height), rng.uniform(z0, z1)])
    target = np.asarray(rule.targets[int(rng.integers(len(rule.targets)))], float)
    d = target - eye
    yaw = np.arctan2(-d[0], -d[2]) + np.deg2rad(rng.uniform(-rule.yaw_jitter_deg, rule.yaw_jitter_deg))
    limit = np.deg2rad(rule.max_pitch_deg)
    pitch = float(np.clip(np.arctan2(d[1], np.hypot(d[0], d[2])), -limit, limit))
    return CameraView(pose_from_angles(eye, float(yaw), pitch), float(np.deg2rad(rng.uniform(*rule.yfov_deg))))


def view_blocked(depth: NDArray[np.float32], rule: CameraRule) -> bool:
    """True when more than ``max_blocked`` of the (H, W) depth pixels lie closer than ``min_clearance``, more
    than ``max_empty`` show nothing, or the drawn pixels' depths spread less than ``min_depth_spread`` (a view of
    one wall)."""
    near = (depth > 0) & (depth < rule.min_clearance)
    if float(near.mean()) > rule.max_blocked:
        return True
    drawn = depth[depth > 0]
    if rule.max_empty < 1.0 and len(drawn) < (1.0 - rule.max_empty) * depth.size:
        return True
    if rule.min_depth_spread > 0:
        if not len(drawn):
            return True
        low, high = np.percentile(drawn, [10, 90])
        return float(high - low) < rule.min_depth_spread
    return False


def pitch_roll_deg(pose: NDArray[np.float64]) -> tuple[float, float]:
    """(pitch, roll) in degrees of a camera pose; roll is the tilt of the image x axis out of the horizontal."""
    forward = -pose[:3, 2]
    pitch = np.degrees(np.arcsin(np.clip(forward[1], -1, 1)))
    roll = np.degrees(np.arcsin(np.clip(pose[1, 0], -1, 1)))
    return float(pitch), float(roll)


class NoViewError(RuntimeError):
    """No unblocked view was found within the allowed tries."""


def find_view(
    rule: CameraRule,
    rng: np.random.Generator,
    depth_of: Callable[[CameraView], NDArray[np.float32]],
    tries: int = 20,
    accept: Callable[[CameraView, NDArray[np.float32]], bool] | None = None,
) -> CameraView:
    """The first sampled view whose depth (from ``depth_of``) is not blocked by a nearby wall and, with
    ``accept``, that ``accept(view, depth)`` takes (e.g. a street view showing some of its fire zones)."""
    for _ in range(tries):
        view = sample_view(rule, rng)
        depth = depth_of(view)
        if not view_blocked(depth, rule) and (accept is None or accept(view, depth)):
            return view
    raise NoViewError(f"no unblocked view in {tries} tries (area {rule.area})")

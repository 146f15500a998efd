"""Where a flame can stand in a rendered view: surfaces that face up (floors, table tops, beds), seen from above.

A fire burns on something: a flame's foot belongs on a horizontal surface, not on a wall, a window, a ceiling
or the sky. From a render's depth (metres along the view axis, 0 = sky) and its camera, every pixel is lifted to
its 3D point, the surface normal is the cross product of the point differences to the neighbours, turned
towards the camera, and the pixel can carry a flame when the normal is within ``max_tilt_deg`` of world up (+Y).
Pixels beside a depth edge (a jump of over ``edge`` x the depth to a neighbour) are excluded: their normals
mix two surfaces.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.places.render import intrinsics


def world_points(depth: NDArray[np.float32], pose: NDArray[np.float64], yfov: float) -> NDArray[np.float64]:
    """(H, W, 3) world points of the (H, W) ``depth`` seen by the camera-to-world ``pose`` (OpenGL: the camera
    looks along -Z, +Y up) with vertical field of view ``yfov`` radians."""
    h, w = depth.shape
    k = intrinsics(yfov, w, h)
    u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    z = depth.astype(np.float64)
    cam = np.stack([(u - k[0, 2]) / k[0, 0] * z, -(v - k[1, 2]) / k[1, 1] * z, -z], axis=-1)
    return cam @ pose[:3, :3].T + pose[:3, 3]


def standing_mask(
    depth: NDArray[np.float32], pose: NDArray[np.float64], yfov: float, max_tilt_deg: float = 20.0, edge: float = 0.05
) -> NDArray[np.bool_]:
    """(H, W) bool: pixels of an up-facing surface (module docstring); sky (depth 0) is never one."""
    points = world_points(depth, pose, yfov)
    du = np.zeros_like(points)
    dv = np.zeros_like(points)
    du[:, 1:-1] = points[:, 2:] - points[:, :-2]
    dv[1:-1] = points[2:] - points[:-2]
    normal = np.cross(du, dv)
    length = np.linalg.norm(normal, axis=-1)
    normal = normal / np.maximum(length, 1e-12)[..., None]
    to_camera = pose[:3, 3] - points
    normal = np.where((np.sum(normal * to_camera, axis=-1) < 0)[..., None], -normal, normal)
    up = normal[..., 1] > np.cos(np.deg2rad(max_tilt_deg))
    z = depth.astype(np.float64)
    jump = np.zeros(depth.shape, bool)
    for axis in (0, 1):
        step = np.abs(np.diff(z, axis=axis)) > edge * np.maximum(z[:-1] if axis == 0 else z[:, :-1], 1e-6)
        pad = [(0, 0), (0, 0)]
        pad[axis] = (1, 0)
        jump |= np.pad(step, pad)
        pad[axis] = (0, 1)
        jump |= np.pad(step, pad)
    mask = up & (depth > 0) & ~jump & (length > 0)
    return cv2.erode(mask.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)

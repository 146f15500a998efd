"""Where a camera may stand in a mesh scene: on the floor, clear of furniture, inside the walls.

Found by rendering, not by hand:

- vertical ray casts: orthographic depth maps looking straight down from a cut height (everything above the
  cut is behind the camera, so ceilings do not hide the floor). The floor is the lowest height covering a
  large share of the hits below a few cuts; a grid cell is free when its first surface below the lowest eye
  height is the floor (within ``STEP``) and nothing else is within ``clearance`` (distance transform);
- horizontal ray casts: from up to ``PROBES`` free cells spread over the floor, four 90-degree depth renders at
  eye height. A probe that sees open sky or void in more than ``MAX_OPEN`` of its pixels stands outside the
  walls (skipped for outdoor scenes); one with a wall closer than ``clearance / 2`` ahead is too close. Every free
  cell takes the verdict of its nearest probe.

Frame: +Y up, metres; grid cells are (x, z) squares of ``cell`` metres.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.places.camera import pose_from_angles
from synth.places.render import Renderer, render_view

STEP = 0.25  # metres: a rug, a threshold or a floor step is still floor
PROBES = 64  # horizontal probes per scene
MAX_OPEN = 0.2  # share of a probe's pixels that may see nothing (windows, doors)
_YAWS = (0.0, np.pi / 2, np.pi, 3 * np.pi / 2)


@dataclass(frozen=True)
class HeightMap:
    """Heights (H, W) float64 of the first surface below ``cut`` seen from above (NaN = nothing there); cell
    (r, c) is centred at ``x = x0 + (c + 0.5) * cell``, ``z = z0 + (r + 0.5) * cell``."""

    heights: NDArray[np.float64]
    x0: float
    z0: float
    cell: float
    cut: float

    def world(self, rows: NDArray[np.integer], cols: NDArray[np.integer]) -> NDArray[np.float64]:
        """(N, 2) world (x, z) of cell centres."""
        return np.stack([self.x0 + (cols + 0.5) * self.cell, self.z0 + (rows + 0.5) * self.cell], 1)


@dataclass(frozen=True)
class FreeSpace:
    """``floor``: floor height (m); ``positions``: (N, 2) free (x, z) cell centres where a camera may stand;
    ``targets``: (K, 3) spread points to look at (furniture tops, else 0.5 m over free floor); ``cell``: grid
    size (m); ``area_m2``: free floor area."""

    floor: float
    positions: NDArray[np.float64]
    targets: NDArray[np.float64]
    cell: float
    area_m2: float


def linear_ortho_depth(depth: NDArray[np.float32], znear: float, zfar: float) -> NDArray[np.float64]:
    """Undo pyrender's perspective depth linearisation for an orthographic camera: (H, W) distances along the
    view axis (0 stays 0 = nothing drawn)."""
    d = depth.astype(np.float64)
    hit = d > 0
    ndc = np.zeros_like(d)
    ndc[hit] = (zfar + znear - 2 * znear * zfar / d[hit]) / (zfar - znear)
    out = np.zeros_like(d)
    out[hit] = (ndc[hit] * (zfar - znear) + zfar + znear) / 2
    return out


def height_map(renderer: Renderer, scene: Any, bounds: NDArray[np.float64], cut: float) -> HeightMap:
    """Look straight down from height ``cut`` over the (x, z) footprint of ``bounds`` (2, 3)."""
    pr = renderer.pyrender
    (x0, y0, z0), (x1, _, z1) = bounds
    w, h = renderer.width, renderer.height
    cell = max((x1 - x0) / w, (z1 - z0) / h) * 1.001
    cx, cz = (x0 + x1) / 2, (z0 + z1) / 2
    znear, zfar = 1e-3, max(cut - y0, 0.0) + 1.0
    cam = pr.OrthographicCamera(xmag=cell * w / 2, ymag=cell * h / 2, znear=znear, zfar=zfar)
    pose = np.eye(4)
    pose[:3, :3] = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])  # columns: x -> +X, up -> -Z, back -> +Y
    pose[:3, 3] = (cx, cut, cz)
    node = scene.add(cam, pose=pose)
    try:
        depth = linear_ortho_depth(renderer.depth(scene), znear, zfar)
    finally:
        scene.remove_node(node)
    heights = np.where(depth > 0, cut - depth, np.nan)
    return HeightMap(heights, cx - cell * w / 2, cz - cell * h / 2, cell, cut)


def find_floor(maps: list[HeightMap], share: float = 0.25) -> float:
    """The lowest height (2 cm bins) holding at least ``share`` of the most common height's hits."""
    values = np.concatenate([m.heights[np.isfinite(m.heights)] for m in maps])
    if not len(values):
        raise ValueError("nothing below any cut height: the scene has no floor to stand on")
    bins = np.round(values / 0.02).astype(np.int64)
    keys, counts = np.unique(bins, return_counts=True)
    return float(keys[np.argmax(counts >= share * counts.max())] * 0.02)


def probe(renderer: Renderer, scene: Any, eye: NDArray[np.float64]) -> tuple[float, float]:
    """(share of pixels seeing nothing, nearest distance in the middle rows) over four horizontal 90-degree
    depth renders from ``eye`` (3,)."""
    depths = [render_view(renderer, scene, pose_from_angles(eye, yaw, 0.0), np.pi / 2, True)[1] for yaw in _YAWS]
    h = depths[0].shape[0]
    band = np.concatenate([d[h // 2 - h // 8 : h // 2 + h // 8].ravel() for d in depths])
    open_share = float(np.mean([(d == 0).mean() for d in depths]))
    near = float(band[band > 0].min()) if (band > 0).any() else np.inf
    return open_share, near


def _nearest(points: NDArray[np.float64], probes: NDArray[np.float64]) -> NDArray[np.int64]:
    """For each of ``points`` (N, 2), the index of its nearest row of ``probes`` (P, 2): the probe whose inside /
    outside verdict it takes."""
    return np.argmin(((points[:, None, :] - probes[None, :, :]) ** 2).sum(-1), axis=1)


def spread_points(points: NDArray[np.float64], k: int) -> NDArray[np.float64]:
    """Up to ``k`` rows of ``points`` (N, D) far from each other: greedy farthest-point sampling from the row
    farthest from their mean (deterministic)."""
    if len(points) <= k:
        return points
    chosen = [int(np.argmax(np.linalg.norm(points - points.mean(0), axis=1)))]
    dist = np.linalg.norm(points - points[chosen[0]], axis=1)
    while len(chosen) < k:
        chosen.append(int(np.argmax(dist)))
        dist = np.minimum(dist, np.linalg.norm(points - points[chosen[-1]], axis=1))
    return points[chosen]


def free_space(
    renderer: Renderer,
    scene: Any,
    bounds: NDArray[np.float64],
    eye_height: float,
    clearance: float,
    floor: float | None = None,
    outdoor: bool = False,
    max_positions: int = 2048,
) -> FreeSpace:
    """The free floor of ``scene`` (see the module docstring). ``bounds`` (2, 3): the scene's; ``eye_height``:
    the lowest camera height above the floor (m). Deterministic."""
    (_, y0, _), (_, y1, _) = bounds
    if floor is None:
        floor = find_floor([height_map(renderer, scene, bounds, y0 + f * (y1 - y0)) for f in (0.15, 0.3, 0.45, 0.6)])
    eye = height_map(renderer, scene, bounds, floor + eye_height)
    on_floor = np.isfinite(eye.heights) & (np.abs(np.nan_to_num(eye.heights, nan=1e9) - floor) <= STEP)
    padded = np.pad(on_floor, 1).astype(np.uint8)  # beyond the map is not floor
    distance = cv2.distanceTransform(padded, cv2.DIST_L2, 5)[1:-1, 1:-1] * eye.cell
    rows, cols = np.nonzero(distance >= clearance)
    rng = np.random.default_rng(0)
    clear_m2 = len(rows) * eye.cell**2
    if len(rows) > 2 * max_positions:
        pick = np.sort(rng.choice(len(rows), 2 * max_positions, replace=False))
        rows, cols = rows[pick], cols[pick]
    cells = eye.world(rows, cols)
    probes = spread_points(cells, PROBES)
    verdicts = []
    for x, z in probes:
        open_share, near = probe(renderer, scene, np.array([x, floor + eye_height, z]))
        verdicts.append((outdoor or open_share <= MAX_OPEN) and near >= clearance / 2)
    if len(cells):
        nearest = _nearest(cells, probes)
        keep = np.asarray(verdicts, bool)[nearest]
        rows, cols = rows[keep], cols[keep]
        clear_m2 *= float(keep.mean())
    if not len(rows):
        raise ValueError(
            f"no free floor at least {clearance} m from walls and furniture inside the walls (floor at y = "
            f"{floor:.2f} m, {len(probes)} probes); set floor, scale or up in a sidecar, or outdoor: true"
        )
    positions = eye.world(rows, cols)
    if len(positions) > max_positions:
        positions = positions[np.sort(rng.choice(len(positions), max_positions, replace=False))]
    targets = _furniture(eye, floor, probes, np.asarray(verdicts, bool), rng)
    if not len(targets):
        targets = np.column_stack([positions[:, 0], np.full(len(positions), floor + 0.5), positions[:, 1]])
    return FreeSpace(floor, positions, spread_points(targets, 16), eye.cell, clear_m2)


def _furniture(
    eye: HeightMap, floor: float, probes: NDArray[np.float64], inside: NDArray[np.bool_], rng: np.random.Generator
) -> NDArray[np.float64]:
    """(K, 3) points on furniture tops (surfaces between ``STEP`` above the floor and the eye cut) whose
    nearest probe stands inside: what a camera looks at."""
    rows, cols = np.nonzero(np.nan_to_num(eye.heights, nan=-np.inf) > floor + STEP)
    if len(rows) > 4096:
        pick = rng.choice(len(rows), 4096, replace=False)
        rows, cols = rows[pick], cols[pick]
    xz = eye.world(rows, cols)
    if not len(xz) or not inside.any():
        return np.zeros((0, 3))
    nearest = _nearest(xz, probes)
    keep = inside[nearest]
    return np.column_stack([xz[keep, 0], eye.heights[rows[keep], cols[keep]], xz[keep, 1]])

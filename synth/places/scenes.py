"""Procedural 3D environments from trimesh primitives, procedural textures and coloured lights.

An :class:`Environment` is plain data (parts, lights, camera rule); :func:`to_pyrender` turns it into a
``pyrender.Scene`` (without camera). Environment ``i`` of a run belongs to family ``FAMILIES[i % 7]`` and is
built from ``np.random.default_rng([seed, i])``, so any number of distinct, reproducible environments exist.
Mesh files (glTF/GLB, OBJ, PLY: anything trimesh loads) become environments via :func:`file_environment`.

World frame: metres, +Y up, floor at y = 0.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from synth.flames.colour import blackbody_rgb
from synth.places.camera import CameraRule
from synth.places.envfile import EnvironmentFile, footprint, load_meshes, mesh_bounds, size_warning
from synth.places.freespace import free_space, spread_points
from synth.places.render import Renderer, rgba_opaque, textured_quad
from synth.places.textures import make_texture

Pose = NDArray[np.float64]


#: Procedural environments of a run that brings no places of its own (the paper's 48).
DEFAULT_SCENES = 48


@dataclass(frozen=True)
class ScenesConfig:
    """``fuzzyfire synth scenes``: one preview per procedural environment, the first ``n`` of a seed's."""

    n: int = DEFAULT_SCENES  # procedural environments to preview, >= 1
    seed: int = 0  # the environments' seed (a Method 1 or 2 run of this seed builds the same rooms)
    width: int = 320  # preview width, pixels, >= 16
    height: int = 240  # preview height, pixels, >= 16

    def __post_init__(self) -> None:
        if self.n < 1 or self.width < 16 or self.height < 16:
            raise ValueError(f"n must be >= 1, width and height >= 16; got n {self.n}, size {self.width}x{self.height}")


@dataclass(frozen=True)
class Solid:
    mesh: trimesh.Trimesh
    color: tuple[float, float, float]  # linear base colour 0..1
    pose: Pose


@dataclass(frozen=True)
class Panel:
    """A textured quad: bottom edge centred at the pose origin, extending up local +Y, facing local +Z."""

    width: float
    height: float
    texture: str
    tile: float  # metres per texture repeat
    pose: Pose


@dataclass(frozen=True)
class Light:
    kind: str  # "point" | "directional"
    kelvin: float
    intensity: float
    pose: Pose


@dataclass
class Environment:
    name: str
    family: str
    camera: CameraRule
    solids: list[Solid] = field(default_factory=list)
    panels: list[Panel] = field(default_factory=list)
    lights: list[Light] = field(default_factory=list)
    meshes: list[tuple[trimesh.Trimesh, Pose]] = field(default_factory=list)  # file meshes, visuals as loaded
    ambient: float = 0.15
    sky: tuple[float, float, float] = (0.0, 0.0, 0.0)
    seed: int = 0


def translate(x: float, y: float, z: float, yaw_deg: float = 0.0, pitch_deg: float = 0.0) -> Pose:
    """(4, 4) pose: rotate about +X by ``pitch_deg``, then about +Y by ``yaw_deg``, then translate."""
    a, b = np.deg2rad(yaw_deg), np.deg2rad(pitch_deg)
    ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    pose = np.eye(4)
    pose[:3, :3] = ry @ rx
    pose[:3, 3] = (x, y, z)
    return pose


# -- building blocks ------------------------------------------------------------------------------------


def add_box(env: Environment, size, at, color, yaw: float = 0.0) -> None:
    """A box of ``size`` (x, y, z) standing on ``at`` = (x, y_bottom, z)."""
    mesh = trimesh.creation.box(extents=size)
    env.solids.append(Solid(mesh, tuple(color), translate(at[0], at[1] + size[1] / 2, at[2], yaw)))


def add_cylinder(env: Environment, radius: float, height: float, at, color, sections: int = 16) -> None:
    mesh = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
    mesh.apply_transform(translate(0, 0, 0, 0, -90))  # trimesh cylinders run along Z; stand them up
    env.solids.append(Solid(mesh, tuple(color), translate(at[0], at[1] + height / 2, at[2])))


def add_room(env: Environment, w: float, d: float, h: float, floor: str, wall: str, ceiling: str | None) -> None:
    """Floor, four inward-facing walls and an optional ceiling of a w x d x h room centred at the origin."""
    env.panels.append(Panel(w, d, floor, 1.0, translate(0, 0, d / 2, 0, -90)))
    if ceiling:
        env.panels.append(Panel(w, d, ceiling, 2.0, translate(0, h, -d / 2, 0, 90)))
    env.panels += [
        Panel(w, h, wall, 2.0, translate(0, 0, -d / 2)),
        Panel(w, h, wall, 2.0, translate(0, 0, d / 2, 180)),
        Panel(d, h, wall, 2.0, translate(-w / 2, 0, 0, 90)),
        Panel(d, h, wall, 2.0, translate(w / 2, 0, 0, -90)),
    ]


def _colour(rng: np.random.Generator, base, spread: float = 0.12) -> tuple[float, float, float]:
    return tuple(float(c) for c in np.clip(np.asarray(base) + rng.normal(0, spread, 3), 0.03, 0.95))


def _lamp(env: Environment, at, kelvin: float, intensity: float) -> None:
    env.lights.append(Light("point", kelvin, intensity, translate(*at)))


def _inside(w: float, d: float, margin: float) -> tuple[float, float, float, float]:
    return (-w / 2 + margin, w / 2 - margin, -d / 2 + margin, d / 2 - margin)


# -- families -------------------------------------------------------------------------------------------


def living_room(env: Environment, rng: np.random.Generator) -> None:
    w, d = rng.uniform(4, 7), rng.uniform(4, 6.5)
    add_room(env, w, d, 2.6, str(rng.choice(["planks", "carpet"])), "plaster", "plaster")
    sofa = _colour(rng, (0.4, 0.3, 0.25), 0.2)
    add_box(env, (2.0, 0.45, 0.9), (0, 0, -d / 2 + 0.6), sofa)
    add_box(env, (2.0, 0.5, 0.2), (0, 0.45, -d / 2 + 0.2), sofa)
    add_box(env, (1.0, 0.45, 0.6), (rng.uniform(-0.5, 0.5), 0, -d / 2 + 1.8), _colour(rng, (0.35, 0.22, 0.12)))
    add_box(env, (0.4, 1.9, 1.4), (w / 2 - 0.3, 0, rng.uniform(-1, 1)), _colour(rng, (0.45, 0.3, 0.18)), 90)
    add_box(env, (1.4, 0.6, 0.4), (-w / 2 + 0.3, 0, rng.uniform(-1, 1)), _colour(rng, (0.2, 0.2, 0.2)), 90)
    add_cylinder(env, 0.2, 0.9, (-w / 2 + 0.5, 0, -d / 2 + 0.5), _colour(rng, (0.8, 0.75, 0.6)))
    _lamp(env, (0, 2.4, 0), rng.uniform(2500, 3200), rng.uniform(6, 14))
    _lamp(env, (-w / 2 + 0.5, 1.2, -d / 2 + 0.5), 2400, rng.uniform(2, 5))
    env.camera = CameraRule(_inside(w, d, 0.5), (1.1, 2.3), ((0, 0.4, -d / 2 + 1), (0, 0.3, 0), (w / 4, 0.8, 0)))


def corridor(env: Environment, rng: np.random.Generator) -> None:
    w, d = rng.uniform(1.8, 3.0), rng.uniform(12, 20)
    add_room(env, w, d, 2.8, str(rng.choice(["tiles", "concrete"])), "plaster", "tiles")
    door = _colour(rng, (0.5, 0.35, 0.2), 0.15)
    for z in np.arange(-d / 2 + 2, d / 2 - 1, rng.uniform(2.5, 4)):
        side = 1 if rng.random() < 0.5 else -1
        add_box(env, (0.08, 2.1, 0.9), (side * (w / 2 - 0.04), 0, z), door)
    for z in np.arange(-d / 2 + 1.5, d / 2, 3.0):
        _lamp(env, (0, 2.7, z), rng.uniform(3500, 5000), rng.uniform(3, 7))
    env.camera = CameraRule((-w / 4, w / 4, d / 2 - 3, d / 2 - 1), (1.5, 2.4), ((0, 0.6, -d / 4), (0, 0.6, 0)), 15)


def warehouse(env: Environment, rng: np.random.Generator) -> None:
    w, d, h = rng.uniform(15, 25), rng.uniform(20, 30), rng.uniform(6, 9)
    add_room(env, w, d, h, "concrete", "metal", "metal")
    rack = _colour(rng, (0.15, 0.25, 0.6), 0.1)
    for x in np.arange(-w / 2 + 3, w / 2 - 2, 4.0):
        for z0 in (-d / 2 + 3, 2.0):
            add_box(env, (1.2, rng.uniform(3, 5), 8.0), (x, 0, z0 + 4), rack)
    for _ in range(int(rng.integers(4, 10))):
        add_box(
            env,
            (1.2, rng.uniform(0.5, 1.5), 1.0),
            (rng.uniform(-w / 2, w / 2) * 0.8, 0, rng.uniform(-2, 2)),
            _colour(rng, (0.6, 0.45, 0.25)),
        )
    for x in (-w / 4, w / 4):
        for z in (-d / 4, d / 4):
            _lamp(env, (x, h - 0.5, z), rng.uniform(4000, 6000), rng.uniform(40, 80))
    env.camera = CameraRule(_inside(w, d, 2), (2.0, 5.0), ((0, 0.5, 0), (0, 1.0, -d / 4), (w / 4, 0.5, 0)), 25)


def office(env: Environment, rng: np.random.Generator) -> None:
    w, d = rng.uniform(5, 9), rng.uniform(5, 8)
    add_room(env, w, d, 2.8, str(rng.choice(["carpet", "tiles"])), "plaster", "tiles")
    desk, chair = _colour(rng, (0.7, 0.65, 0.55)), _colour(rng, (0.15, 0.15, 0.2))
    for x in np.arange(-w / 2 + 1.2, w / 2 - 0.8, 1.8):
        for z in (-1.0, 1.2):
            add_box(env, (1.4, 0.75, 0.7), (x, 0, z), desk)
            add_box(env, (0.5, 0.5, 0.5), (x, 0, z + 0.7), chair)
            add_box(env, (0.5, 0.35, 0.05), (x, 0.75, z - 0.2), (0.05, 0.05, 0.05))
    add_box(env, (w * 0.6, 0.9, 0.6), (0, 0, -d / 2 + 0.3), _colour(rng, (0.8, 0.8, 0.8)))  # kitchen counter
    for x in (-w / 4, w / 4):
        _lamp(env, (x, 2.7, 0), rng.uniform(3800, 5500), rng.uniform(6, 12))
    env.camera = CameraRule(_inside(w, d, 0.6), (1.3, 2.5), ((0, 0.8, 0), (0, 0.9, -d / 2 + 0.5), (-w / 4, 0.5, 1)))


def industrial_hall(env: Environment, rng: np.random.Generator) -> None:
    w, d, h = rng.uniform(18, 30), rng.uniform(18, 30), rng.uniform(7, 11)
    add_room(env, w, d, h, "concrete", "bricks", None)
    for _ in range(int(rng.integers(5, 10))):
        at = (rng.uniform(-w / 3, w / 3), 0, rng.uniform(-d / 3, d / 3))
        if rng.random() < 0.5:
            add_box(env, tuple(rng.uniform([1.5, 1.0, 1.5], [4, 3, 3])), at, _colour(rng, (0.35, 0.4, 0.3)))
        else:
            add_cylinder(env, rng.uniform(0.6, 1.6), rng.uniform(2, 5), at, _colour(rng, (0.6, 0.6, 0.62)))
    for z in np.arange(-d / 2 + 2, d / 2, 5.0):
        add_cylinder(env, 0.15, h, (w / 2 - 0.5, 0, z), (0.5, 0.2, 0.1))
    _lamp(env, (0, h - 1, 0), rng.uniform(4500, 6500), rng.uniform(60, 120))
    env.lights.append(Light("directional", rng.uniform(5000, 6500), rng.uniform(1, 2.5), translate(0, 0, 0, 30, -50)))
    env.camera = CameraRule(_inside(w, d, 2), (1.6, 4.0), ((0, 0.5, 0), (w / 4, 1, -d / 4)), 20)
    env.sky = (0.55, 0.6, 0.65)


def forest(env: Environment, rng: np.random.Generator) -> None:
    size = 60.0
    env.panels.append(Panel(size, size, "grass", 2.0, translate(0, 0, size / 2, 0, -90)))
    for _ in range(int(rng.integers(40, 80))):
        x, z = rng.uniform(-size / 2.5, size / 2.5, 2)
        if abs(x) < 2 and abs(z) < 2:
            continue
        hgt = rng.uniform(4, 12)
        add_cylinder(env, rng.uniform(0.12, 0.35), hgt, (x, 0, z), _colour(rng, (0.3, 0.2, 0.12), 0.05), 8)
        crown = trimesh.creation.cone(radius=rng.uniform(1.0, 2.5), height=hgt * 0.7, sections=10)
        crown.apply_transform(translate(0, 0, 0, 0, -90))
        env.solids.append(Solid(crown, _colour(rng, (0.1, 0.3, 0.1), 0.06), translate(x, hgt * 0.35, z)))
    for _ in range(int(rng.integers(5, 15))):
        rock = trimesh.creation.icosphere(subdivisions=1, radius=rng.uniform(0.2, 0.7))
        env.solids.append(Solid(rock, _colour(rng, (0.4, 0.4, 0.38)), translate(*rng.uniform(-15, 15, 3) * (1, 0, 1))))
    env.lights.append(
        Light("directional", rng.uniform(4500, 6500), rng.uniform(2, 4), translate(0, 0, 0, rng.uniform(0, 360), -40))
    )
    env.ambient, env.sky = 0.3, _colour(rng, (0.55, 0.7, 0.9), 0.06)
    env.camera = CameraRule((-6, 6, -6, 6), (1.2, 3.0), ((0, 0.5, -8), (8, 0.5, 0), (-8, 0.5, 0), (0, 0.5, 8)), 15)


def street(env: Environment, rng: np.random.Generator) -> None:
    size = 50.0
    env.panels.append(Panel(size, size, "asphalt", 3.0, translate(0, 0, size / 2, 0, -90)))
    for side in (-1, 1):
        x0 = side * rng.uniform(7, 10)
        for z in np.arange(-20, 20, rng.uniform(8, 12)):
            hgt = rng.uniform(6, 15)
            env.panels.append(
                Panel(
                    8.0, hgt, str(rng.choice(["bricks", "plaster", "concrete"])), 3.0, translate(x0, 0, z, -90 * side)
                )
            )
    for _ in range(int(rng.integers(3, 8))):
        add_box(
            env, (1.8, 1.4, 4.2), (rng.uniform(-5, 5), 0, rng.uniform(-18, 18)), _colour(rng, (0.4, 0.4, 0.45), 0.25)
        )
    for z in np.arange(-18, 18, 9.0):
        add_cylinder(env, 0.08, 5.0, (5.5, 0, z), (0.3, 0.3, 0.3), 8)
    env.lights.append(
        Light("directional", rng.uniform(4000, 6500), rng.uniform(2, 4), translate(0, 0, 0, rng.uniform(0, 360), -35))
    )
    env.ambient, env.sky = 0.3, _colour(rng, (0.6, 0.7, 0.85), 0.08)
    env.camera = CameraRule((-4, 4, 5, 15), (1.5, 4.0), ((0, 0.5, -5), (3, 0.5, 0), (-3, 1, -10)), 20)


FAMILIES: dict[str, Callable[[Environment, np.random.Generator], None]] = {
    "living_room": living_room,
    "corridor": corridor,
    "warehouse": warehouse,
    "office": office,
    "industrial_hall": industrial_hall,
    "forest": forest,
    "street": street,
}


def build_environment(index: int, seed: int = 0) -> Environment:
    """Environment ``index`` of a run seeded by ``seed`` (family ``index % len(FAMILIES)``)."""
    family = list(FAMILIES)[index % len(FAMILIES)]
    env = Environment(f"{family}-{index:03d}", family, CameraRule((0, 0, 0, 0)), seed=seed)
    FAMILIES[family](env, np.random.default_rng([seed, index]))
    return env


def file_environment(spec: EnvironmentFile, renderer: Renderer) -> tuple[Environment, Any]:
    """An environment from a mesh file (see :mod:`synth.places.envfile`) and its pyrender scene: textures and
    materials as the file has them, moved so the floor is at y = 0, the camera rule derived from its free floor
    (:mod:`synth.places.freespace`) unless the sidecar gives ``camera.area``, and (``lights: auto``) a warm lamp over
    every ~20 m2 of free floor (at most 4) plus a sun."""
    meshes = load_meshes(spec)
    warning = size_warning(spec, mesh_bounds(meshes))
    if warning:
        print(f"warning: {warning}", file=sys.stderr)
    bounds = footprint(meshes)
    pr = renderer.pyrender
    env = Environment(spec.name, "file", CameraRule((0, 0, 0, 0)), ambient=0.25, sky=(0.75, 0.8, 0.85))
    env.meshes = meshes
    scene = to_pyrender(env, pr)
    cam = spec.camera
    space = free_space(renderer, scene, bounds, cam.height[0], cam.min_clearance, spec.floor, spec.outdoor)
    shift = translate(0.0, -space.floor, 0.0)
    for node in list(scene.mesh_nodes):
        node.matrix = shift @ node.matrix
    env.meshes = [(mesh, shift @ pose) for mesh, pose in meshes]
    targets = cam.targets or tuple((float(x), float(y - space.floor), float(z)) for x, y, z in space.targets)
    rule = dict(height=cam.height, targets=targets, max_pitch_deg=cam.max_pitch_deg, yfov_deg=cam.yfov_deg)
    rule |= dict(min_clearance=cam.min_clearance, min_depth_spread=0.5, max_empty=0.8 if spec.outdoor else 0.5)
    if cam.area is not None:
        env.camera = CameraRule(cam.area, **rule)
    else:
        positions = tuple((float(x), float(z)) for x, z in space.positions)
        (x0, z0), (x1, z1) = space.positions.min(0), space.positions.max(0)
        env.camera = CameraRule((x0, x1, z0, z1), **rule, positions=positions, cell=space.cell)
    if spec.lights == "auto":
        lamps = max(1, min(4, int(space.area_m2 // 20)))
        for x, z in spread_points(space.positions, lamps):  # over free floor
            _lamp(env, (float(x), 2.3, float(z)), spec.kelvin, 20.0 / lamps**0.5)
        env.lights.append(Light("directional", 6000.0, 2.0, translate(0, 0, 0, 30, -50)))
        for light in env.lights:
            scene.add(_pyrender_light(light, pr), pose=light.pose)
    return env, scene


#: How much of a light's colour cast the camera's auto white balance removes (0: none, 1: all lights white).
CAMERA_WHITE_BALANCE = 0.7


def white_balanced(kelvin: float) -> NDArray[np.float64]:
    """(3,) linear RGB of a black-body light of ``kelvin`` as a white-balanced camera sees it: the chromaticity
    raised to ``1 - CAMERA_WHITE_BALANCE`` (warm lamps stay warm, not orange)."""
    c = blackbody_rgb(kelvin) ** (1.0 - CAMERA_WHITE_BALANCE)
    return c / c.max()


def to_pyrender(env: Environment, pr: Any, texture_size: int = 128) -> Any:
    """A ``pyrender.Scene`` of ``env`` (no camera). Textures are drawn from the environment's own rng."""
    scene = pr.Scene(bg_color=(*env.sky, 1.0), ambient_light=(env.ambient,) * 3)
    rng = np.random.default_rng([env.seed, 7919, len(env.panels)])
    cache: dict[str, Any] = {}
    for panel in env.panels:
        if panel.texture not in cache:
            img = make_texture(panel.texture, rng, texture_size)
            cache[panel.texture] = pr.MetallicRoughnessMaterial(
                baseColorTexture=pr.Texture(source=rgba_opaque(np.dstack([img, img[..., :1]])), source_channels="RGBA"),
                metallicFactor=0.0,
                roughnessFactor=0.9,
                doubleSided=True,
            )
        uv = (panel.width / panel.tile, panel.height / panel.tile)
        scene.add(textured_quad(pr, panel.width, panel.height, cache[panel.texture], uv), pose=panel.pose)
    for solid in env.solids:
        mat = pr.MetallicRoughnessMaterial(baseColorFactor=(*solid.color, 1.0), metallicFactor=0.0, roughnessFactor=0.8)
        scene.add(pr.Mesh.from_trimesh(solid.mesh, material=mat, smooth=False), pose=solid.pose)
    drawn: dict[int, Any] = {}  # one pyrender mesh per trimesh placed several times (a kit part, an instance)
    for mesh, pose in env.meshes:
        if id(mesh) not in drawn:
            drawn[id(mesh)] = _pyrender_mesh(mesh, pr)
        scene.add(drawn[id(mesh)], pose=pose)
    for light in env.lights:
        scene.add(_pyrender_light(light, pr), pose=light.pose)
    return scene


def _pyrender_mesh(mesh: trimesh.Trimesh, pr: Any) -> Any:
    """A file mesh as pyrender draws it (its own material and textures). Without scipy, trimesh logs a
    traceback each time it computes vertex normals the slow way; that is not a problem worth showing."""
    log = logging.getLogger("trimesh")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        return pr.Mesh.from_trimesh(mesh)
    finally:
        log.setLevel(level)


def _pyrender_light(light: Light, pr: Any) -> Any:
    cls = pr.PointLight if light.kind == "point" else pr.DirectionalLight
    return cls(color=white_balanced(light.kelvin), intensity=light.intensity)

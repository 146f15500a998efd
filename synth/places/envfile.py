"""Environments from 3D files: glTF/GLB, OBJ+MTL, PLY (anything ``trimesh.load`` reads), with their textures
and per-mesh materials, normalised to the frame of the procedural environments (metres, +Y up, floor at y = 0).

Each file may have a sidecar YAML that overrides what is otherwise derived: ``<file stem>.yaml`` beside it, or
a YAML passed in its place whose ``file:`` names the mesh (relative to the YAML), so scenes in a read-only
folder can still get one. Keys (all optional)::

    file: scene.glb            # only in a YAML passed instead of the mesh
    scale: 1.0                 # metres per file unit (glTF is metres; many OBJ exports are centimetres: 0.01)
    up: +y                     # the file's up axis: +y | -y | +z | -z | +x | -x
    floor: null                # floor height in metres after scale and up (null = found by probing)
    outdoor: false             # true: camera positions need no walls around them
    lights: auto               # auto: add a ceiling lamp and a sun (the file's own lights are not read); none
    kelvin: 4500               # colour temperature of the added lamp
    camera:                    # overrides of the derived camera rule (see synth.places.camera.CameraRule)
      height: [1.3, 2.2]       # eye height above the floor, metres
      area: null               # [x0, x1, z0, z1] metres: the camera moves in this rectangle (default: free floor)
      targets: null            # [[x, y, z], ...] look-at points (default: points of the free floor)
      max_pitch_deg: 20
      yfov_deg: [50, 70]
      min_clearance: 0.6       # metres from walls and furniture

Sizes are in metres after ``scale``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
import yaml
from numpy.typing import NDArray

MESH_SUFFIXES = (".glb", ".gltf", ".obj", ".ply", ".stl", ".off", ".dae")
_UP = {"+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1), "+x": (1, 0, 0), "-x": (-1, 0, 0)}


@dataclass(frozen=True)
class CameraOverrides:
    height: tuple[float, float] = (1.3, 2.2)
    area: tuple[float, float, float, float] | None = None
    targets: tuple[tuple[float, float, float], ...] | None = None
    max_pitch_deg: float = 20.0
    yfov_deg: tuple[float, float] = (50.0, 70.0)
    min_clearance: float = 0.6


@dataclass(frozen=True)
class EnvironmentFile:
    """A mesh file and its sidecar settings (see the module docstring)."""

    file: Path
    scale: float = 1.0
    up: str = "+y"
    floor: float | None = None
    outdoor: bool = False
    lights: str = "auto"
    kelvin: float = 4500.0
    camera: CameraOverrides = field(default_factory=CameraOverrides)
    sidecar: Path | None = None

    def __post_init__(self) -> None:
        where = self.sidecar or self.file
        if self.scale <= 0:
            raise ValueError(f"{where}: scale must be > 0, got {self.scale}")
        if self.up not in _UP:
            raise ValueError(f"{where}: up must be one of {', '.join(_UP)}, got {self.up!r}")
        if self.lights not in ("auto", "none"):
            raise ValueError(f"{where}: lights must be auto or none, got {self.lights!r}")

    @property
    def name(self) -> str:
        """The file's stem, or its folder's name when the stem is generic (``scene.glb``)."""
        stem = self.file.stem
        return self.file.parent.name if stem.lower() in ("scene", "model", "mesh") else stem


def _tuple(value: Any) -> Any:
    return tuple(_tuple(v) for v in value) if isinstance(value, list) else value


def _parse(data: dict, cls: type, where: Path) -> dict:
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}")
    return {k: _tuple(v) for k, v in data.items()}


def read_sidecar(path: Path, mesh: Path | None = None) -> EnvironmentFile:
    """The settings in sidecar ``path`` for ``mesh`` (default: the YAML's own ``file:`` key)."""
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML ({exc})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: a sidecar must be a mapping of keys")
    data = dict(data)
    named = data.pop("file", None)
    if mesh is None:
        if named is None:
            raise ValueError(f"{path}: a sidecar passed as an environment needs a file: key naming the mesh")
        mesh = (path.parent / named).resolve()
    camera = CameraOverrides(**_parse(data.pop("camera", None) or {}, CameraOverrides, path))
    settings = _parse(data, EnvironmentFile, path)
    settings.pop("sidecar", None)
    return EnvironmentFile(Path(mesh), camera=camera, sidecar=path, **settings)


def environment_file(path: Path) -> EnvironmentFile:
    """A mesh file (with ``<stem>.yaml`` beside it when present) or a sidecar YAML naming its mesh."""
    path = Path(path)
    if path.suffix.lower() in (".yaml", ".yml"):
        spec = read_sidecar(path)
    else:
        sidecar = next((s for s in (path.with_suffix(".yaml"), path.with_suffix(".yml")) if s.is_file()), None)
        spec = read_sidecar(sidecar, path) if sidecar else EnvironmentFile(path)
    if not spec.file.is_file():
        raise FileNotFoundError(f"{spec.sidecar or spec.file}: mesh file {spec.file} not found")
    return spec


def is_environment_sidecar(path: Path) -> bool:
    """Whether ``path`` is a YAML naming a mesh (a ``file:`` key): other YAMLs in a folder (a panorama's or a
    photo's sidecar) are not environments."""
    if path.suffix.lower() not in (".yaml", ".yml"):
        return False
    data = yaml.safe_load(path.read_text())
    return isinstance(data, dict) and "file" in data


def find_environment_files(paths: Iterable[Path | str]) -> list[EnvironmentFile]:
    """Every environment under ``paths`` (files, or folders searched recursively), sorted by path. In a folder a
    mesh with a sidecar beside it counts once, and a YAML counts only when it has a ``file:`` key."""
    found: dict[Path, EnvironmentFile] = {}
    for item in paths:
        path = Path(item)
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such environment file or folder")
        if path.is_file():
            spec = environment_file(path)
            found[spec.file.resolve()] = spec
            continue
        for mesh in sorted(p for p in path.rglob("*") if p.suffix.lower() in MESH_SUFFIXES):
            spec = environment_file(mesh)
            found.setdefault(spec.file.resolve(), spec)
        for side in sorted(p for p in path.rglob("*") if is_environment_sidecar(p)):
            spec = read_sidecar(side)
            found[spec.file.resolve()] = spec
    if not found:
        raise ValueError(f"no mesh files ({', '.join(MESH_SUFFIXES)}) in {', '.join(map(str, paths))}")
    return [found[k] for k in sorted(found)]


#: Files beside a mesh that a non-GLB mesh may load (materials, buffers, textures): part of its fingerprint.
RESOURCE_SUFFIXES = (".mtl", ".bin", ".png", ".jpg", ".jpeg", ".tga", ".bmp", ".ktx2", ".webp")


def fingerprint(spec: EnvironmentFile) -> dict[str, Any]:
    """What makes the environment ``spec``, wherever it lies: its mesh file's name and the sha256 of its bytes
    (a mesh that is not a ``.glb`` also brings the materials, buffers and textures beside it) and its sidecar
    settings. Two copies of a scene in different folders have one fingerprint; an edited file or setting
    changes it."""
    from ground.data.manifest import file_sha256

    beside = [] if spec.file.suffix.lower() == ".glb" else sorted(
        p for p in spec.file.parent.iterdir() if p.is_file() and p.suffix.lower() in RESOURCE_SUFFIXES
    )  # fmt: skip
    settings = {k: v for k, v in asdict(spec).items() if k not in ("file", "sidecar")}
    return {"file": spec.file.name, "sha256": {p.name: file_sha256(p) for p in [spec.file, *beside]}, **settings}


def _up_rotation(up: str) -> NDArray[np.float64]:
    """(4, 4) rotation taking the file's ``up`` axis to +Y."""
    a = np.asarray(_UP[up], float)
    b = np.array([0.0, 1.0, 0.0])
    r = np.eye(4)
    if np.allclose(a, b):
        return r
    if np.allclose(a, -b):
        r[:3, :3] = np.diag([1.0, -1.0, -1.0])  # half turn about +X
        return r
    return trimesh.geometry.align_vectors(a, b)


def load_meshes(spec: EnvironmentFile) -> list[tuple[trimesh.Trimesh, NDArray[np.float64]]]:
    """The file's meshes (visuals kept: textures, materials, vertex colours) with (4, 4) poses in the normalised
    frame (scaled to metres, up axis +Y; the floor is placed at y = 0 later, see :mod:`synth.places.freespace`)."""
    try:
        loaded = trimesh.load(str(spec.file))
    except Exception as exc:  # trimesh raises many types for bad files
        raise ValueError(f"{spec.file}: cannot be loaded as a 3D scene ({type(exc).__name__}: {exc})") from None
    scene = loaded if isinstance(loaded, trimesh.Scene) else trimesh.Scene(loaded)
    _shrink_textures(scene.geometry.values())
    frame = _up_rotation(spec.up)
    frame[:3, :3] *= spec.scale
    meshes = []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        mesh = scene.geometry.get(name)
        if isinstance(mesh, trimesh.Trimesh) and len(mesh.faces):
            meshes.append((mesh, frame @ np.asarray(transform, float)))
    if not meshes:
        raise ValueError(f"{spec.file}: no triangles")
    return meshes


MAX_TEXTURE = 1024  # pixels: renders are 640x480-ish; pyrender copies a material's textures for every mesh using it
_TEXTURES = ("baseColorTexture", "emissiveTexture", "normalTexture", "metallicRoughnessTexture", "occlusionTexture")


def _shrink_textures(meshes: Iterable[Any]) -> None:
    """Textures larger than :data:`MAX_TEXTURE` on a side scaled down in place (each image once). The Tokyo
    diorama shares one 4096 px texture among 54 meshes: 8.6 GB of RSS as pyrender holds it, ~0.3 GB at 1024."""
    done: dict[int, Any] = {}
    for mesh in meshes:
        material = getattr(getattr(mesh, "visual", None), "material", None)
        for name in _TEXTURES:
            image = getattr(material, name, None)
            if image is None or not hasattr(image, "size") or max(image.size) <= MAX_TEXTURE:
                continue
            if id(image) not in done:
                scale = MAX_TEXTURE / max(image.size)
                size = (max(1, round(image.size[0] * scale)), max(1, round(image.size[1] * scale)))
                done[id(image)] = image.resize(size)
            setattr(material, name, done[id(image)])


def mesh_bounds(meshes: Sequence[tuple[trimesh.Trimesh, NDArray[np.float64]]]) -> NDArray[np.float64]:
    """(2, 3) min/max corner of the posed meshes."""
    corners = [trimesh.transform_points(trimesh.bounds.corners(m.bounds), pose) for m, pose in meshes]
    points = np.concatenate(corners)
    return np.stack([points.min(0), points.max(0)])


#: Sizes (largest extent after ``scale``, metres) outside which a scene is neither a room nor a street.
PLAUSIBLE_SIZE_M = (1.5, 500.0)


def size_warning(spec: EnvironmentFile, bounds: NDArray[np.float64]) -> str | None:
    """One line when the scene's (2, 3) ``bounds`` (metres after ``scale``) are implausible for a room or a
    street - a model in millimetres or centimetres without a sidecar ``scale`` - else None."""
    extent = float(np.max(bounds[1] - bounds[0]))
    lo, hi = PLAUSIBLE_SIZE_M
    if lo <= extent <= hi:
        return None
    hint = "millimetres need scale: 0.001, centimetres 0.01" if extent > hi else "a model in km would need scale: 1000"
    return (
        f"{spec.sidecar or spec.file}: {extent:.4g} m across at scale {spec.scale:g}, not a room or a street "
        f"({lo:g}..{hi:g} m): give it a sidecar with the right scale ({hint})"
    )


def footprint(meshes: Sequence[tuple[trimesh.Trimesh, NDArray[np.float64]]]) -> NDArray[np.float64]:
    """(2, 3) bounds of where the camera may go: :func:`mesh_bounds` without ground planes, i.e. flat meshes
    (height under 1 % of their width) covering over 4x the (x, z) area of everything else; a classroom modelled on
    a 200 m lawn is searched in the classroom."""
    boxes = [mesh_bounds([m]) for m in meshes]
    size = [b[1] - b[0] for b in boxes]
    flat = [s[1] < 0.01 * max(s[0], s[2]) for s in size]
    rest = [b for b, f in zip(boxes, flat) if not f]
    if not rest:
        return mesh_bounds(meshes)
    lo, hi = np.min([b[0] for b in rest], 0), np.max([b[1] for b in rest], 0)
    rest_area = max((hi[0] - lo[0]) * (hi[2] - lo[2]), 1e-9)
    ground = [f and s[0] * s[2] > 4 * rest_area for s, f in zip(size, flat)]
    kept = [b for b, g in zip(boxes, ground) if not g]
    out = np.stack([np.min([b[0] for b in kept], 0), np.max([b[1] for b in kept], 0)])
    out[0, 1], out[1, 1] = min(b[0, 1] for b in boxes), max(b[1, 1] for b in boxes)  # heights of everything
    return out

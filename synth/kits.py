"""Modular building kits (glTF/GLB parts: road tiles, houses, wall blocks, bins, trees) as parts in metres.

A kit is a folder of GLB parts (in ``glb/`` when that subfolder exists) that one of the :data:`PROFILES`
recognises by file names: every ``required`` role must match at least one file. A profile names, per role,
the file patterns (``fnmatch`` on the path relative to the parts folder) and how each is scaled to metres:

- grid parts (roads, houses, wall blocks, trees) by the kit's ``unit_m`` (metres per kit unit), chosen from the
  parts' bounding boxes: Kenney City Kit Suburban: a house door is ~0.27 units, a storey ~0.35, a road tile
  (two lanes and kerbs) 1.0: 8 m per unit (door 2.2 m, storey 2.8 m, road 8 m); Kenney Retro Urban: a wall block
  is 1 unit high with a door of ~0.45 and a garage door of ~0.55: 4.5 m per unit (a 4.5 m shop storey, a 2 m
  door, a 2.5 m garage door, a 2.25 m pavement);
- props (bins, barriers, cones, fences, street lights) to a real height in metres, because the kits draw
  them oversized (a Retro Urban dumpster at 4.5 m per unit would be 2.4 m high; scaled to 1.5 m).

Parts are turned on load so that every facade faces +Z (City Kit Suburban's do; Retro Urban's face -Z and are
turned by 180 degrees). World frame of a part: metres, +Y up, standing on y = 0, centred in x and z as the kit
models it.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from synth.envfile import EnvironmentFile, load_meshes, mesh_bounds

Pose = NDArray[np.float64]


@dataclass(frozen=True)
class KitProfile:
    """How to read one kit: ``roles`` maps a role to ((file pattern, height in metres or None = ``unit_m``), ...)."""

    name: str
    title: str  # the kit's name as its author gives it (for credits)
    credit: str  # who made it and its licence
    unit_m: float  # metres per kit unit for grid parts
    front: int  # +1: facades face +Z in the kit's files, -1: they face -Z
    roles: dict[str, tuple[tuple[str, float | None], ...]]
    required: tuple[str, ...]  # roles a folder must have to be this kit


CC0_KENNEY = "Kenney (www.kenney.nl), CC0 1.0 (credit optional)"

SUBURBAN = KitProfile(
    name="suburban",
    title="Kenney City Kit Suburban + City Kit Roads",
    credit=CC0_KENNEY,
    unit_m=8.0,
    front=+1,
    roles={
        "road": (("roads/road-straight.glb", None),),
        "house": (("building-type-*.glb", None),),
        "driveway": (("driveway-long.glb", None),),
        "fence": (("fence.glb", 1.1),),
        "tree": (("tree-large.glb", None), ("tree-small.glb", None)),
        "barrier": (("roads/construction-barrier.glb", 1.0), ("roads/construction-cone.glb", 0.7)),
        "light": (("roads/light-square.glb", 6.5), ("roads/light-curved.glb", 6.5)),
    },
    required=("road", "house"),
)

RETRO_URBAN = KitProfile(
    name="retro_urban",
    title="Kenney Retro Urban Kit",
    credit=CC0_KENNEY,
    unit_m=4.5,
    front=-1,
    roles={
        "road": (("road-asphalt-center.glb", None),),
        "road_side": (("road-asphalt-side.glb", None),),
        "wall": (("wall-[ab].glb", None), ("wall-a-painted.glb", None)),
        "door": (("wall-[ab]-door.glb", None),),
        "window": (("wall-[ab]-window.glb", None),),
        "garage": (("wall-[ab]-garage.glb", None),),
        "roof": (("wall-[ab]-roof.glb", None),),
        "awning": (("detail-awning-*.glb", None),),
        "balcony": (("balcony-type-a.glb", None),),
        "bin": (("detail-dumpster-*.glb", 1.5),),
        "barrier": (("detail-barrier-*.glb", 1.0),),
        "tree": (("tree-large.glb", None), ("tree-park-large.glb", None), ("tree-pine-large.glb", None)),
        "light": (("detail-light-single.glb", 5.0), ("detail-light-double.glb", 5.0)),
    },
    required=("road", "road_side", "wall", "door"),
)

PROFILES: tuple[KitProfile, ...] = (SUBURBAN, RETRO_URBAN)


@dataclass(frozen=True, eq=False)
class Part:
    """One kit file in metres, facade towards +Z: ``meshes`` (visuals as loaded) with (4, 4) poses, ``bounds``
    (2, 3) their min/max corner."""

    name: str  # path relative to the kit's parts folder, e.g. "roads/road-straight.glb"
    kit: str
    meshes: tuple[tuple[trimesh.Trimesh, Pose], ...]
    bounds: NDArray[np.float64]

    @property
    def size(self) -> NDArray[np.float64]:
        """(3,) extent in metres (x: along the facade, y: up, z: depth)."""
        return self.bounds[1] - self.bounds[0]


@dataclass(frozen=True, eq=False)
class Kit:
    """A loaded kit: its folder, profile and parts by role (each role's parts sorted by name)."""

    folder: Path
    profile: KitProfile
    parts: dict[str, tuple[Part, ...]]

    @property
    def name(self) -> str:
        return self.folder.name


def parts_folder(folder: Path) -> Path:
    """Where a kit keeps its GLB parts: ``glb/`` when the folder has it, else the folder itself."""
    return folder / "glb" if (folder / "glb").is_dir() else folder


def _files(folder: Path) -> list[str]:
    root = parts_folder(folder)
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*.glb"))


def _matches(files: Sequence[str], patterns: Iterable[tuple[str, float | None]]) -> list[tuple[str, float | None]]:
    return [(f, h) for pattern, h in patterns for f in files if fnmatch.fnmatchcase(f, pattern)]


def profile_of(folder: Path) -> KitProfile | None:
    """The first profile whose required roles all match a file of ``folder`` (None: no profile does)."""
    files = _files(folder)
    for profile in PROFILES:
        if all(_matches(files, profile.roles[role]) for role in profile.required):
            return profile
    return None


def _known() -> str:
    return "; ".join(
        f"{p.title}: {' + '.join(p.roles[r][0][0] for r in p.required)}" for p in PROFILES
    )  # fmt: skip


def find_kits(paths: Iterable[Path | str]) -> list[Path]:
    """Kit folders in ``paths``: each path is a kit, or a folder whose subfolders holding GLB files are kits.
    A missing path is a FileNotFoundError; a folder of GLB parts no profile knows is a ValueError (one line)."""
    found: list[Path] = []
    for item in paths:
        path = Path(item)
        if not path.is_dir():
            raise FileNotFoundError(f"{path}: no such kit folder")
        if profile_of(path) is not None:
            found.append(path)
            continue
        subs = [p for p in sorted(path.iterdir()) if p.is_dir() and p.name != "glb" and _files(p)]
        for sub in subs or [path]:
            if profile_of(sub) is None:
                raise ValueError(
                    f"{sub}: not a building kit this street layout knows (it needs the files of {_known()})"
                )
            found.append(sub)
    if not found:
        raise ValueError("no kit folders given")
    return list(dict.fromkeys(found))


def load_part(path: Path, name: str, kit: str, profile: KitProfile, height_m: float | None) -> Part:
    """The part in ``path`` scaled to metres (``height_m`` tall, or ``profile.unit_m`` per unit) and turned so
    its facade faces +Z."""
    meshes = load_meshes(EnvironmentFile(path))
    raw = mesh_bounds(meshes)
    tall = float(raw[1, 1] - raw[0, 1])
    scale = profile.unit_m if height_m is None or tall <= 0 else height_m / tall
    frame = np.diag([1.0, 1.0, 1.0, 1.0]) if profile.front > 0 else np.diag([-1.0, 1.0, -1.0, 1.0])
    frame[:3, :3] *= scale
    posed = tuple((m, frame @ p) for m, p in meshes)
    return Part(name, kit, posed, mesh_bounds(posed))


def load_kit(folder: Path) -> Kit:
    """Every part of the kit in ``folder`` that a role of its profile names (ValueError: no profile knows it)."""
    profile = profile_of(folder)
    if profile is None:
        raise ValueError(f"{folder}: not a building kit this street layout knows (it needs the files of {_known()})")
    root, files = parts_folder(folder), _files(folder)
    parts = {
        role: tuple(load_part(root / f, f, folder.name, profile, h) for f, h in _matches(files, patterns))
        for role, patterns in profile.roles.items()
    }
    return Kit(folder, profile, {role: found for role, found in parts.items() if found})


def tinted(part: Part, rgb: tuple[float, float, float]) -> Part:
    """A copy of ``part`` whose textured meshes' base colour is multiplied by ``rgb`` (linear factors around 1:
    a colour cast over the kit's texture); meshes without a PBR material are kept as they are."""
    meshes = []
    for mesh, pose in part.meshes:
        material = getattr(mesh.visual, "material", None)
        if not hasattr(material, "baseColorFactor"):
            meshes.append((mesh, pose))
            continue
        copy = mesh.copy()
        base = copy.visual.material.baseColorFactor
        base = np.full(4, 255.0) if base is None else np.asarray(base, float)
        copy.visual.material.baseColorFactor = np.clip(base * np.array([*rgb, 1.0]), 0, 255).astype(np.uint8)
        meshes.append((copy, pose))
    return Part(part.name, part.kit, tuple(meshes), part.bounds)


def licence_files(folder: Path) -> list[Path]:
    """The kit's licence and readme files (``LICENSE*``, ``README*``): the sources a manifest records."""
    return sorted(p for p in folder.iterdir() if p.is_file() and p.name.upper().startswith(("LICENSE", "README")))


def credits(folders: Sequence[Path]) -> list[dict[str, str]]:
    """Per kit folder: its name, title and credit line (for the manifest; CC0 asks none, we credit anyway)."""
    out = []
    for folder in folders:
        profile = profile_of(folder)
        if profile is not None:
            out.append({"kit": folder.name, "title": profile.title, "credit": profile.credit})
    return out


def kit_fingerprint(folder: Path) -> dict[str, Any]:
    """What makes a kit, wherever it lies: its folder name and the sha256 of every file under it (by relative
    path). Two copies of a kit have one fingerprint; an edited part changes it."""
    from curate.core.manifest import file_sha256

    files = sorted(p for p in folder.rglob("*") if p.is_file())
    return {"kit": folder.name, "sha256": {p.relative_to(folder).as_posix(): file_sha256(p) for p in files}}

"""The places a pool is made in, by kind: rendered 3D environments (mesh files), 360-degree panoramas and
photographs. ``environments`` may hold meshes (or their sidecars) and equirectangular panoramas (a 2:1 image is
a place: :mod:`synth.panorama`); ``backgrounds`` holds photos, where a 2:1 panorama is also used as a place, not
cropped flat. Which kind a view shows is drawn per view with the kinds' weights (:func:`kind_of_view`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curate.core.imageio import ImageError
from curate.core.problems import Problem
from curate.core.walk import walk_files
from curate.scan import list_image_files
from synth.envfile import MESH_SUFFIXES, is_environment_sidecar
from synth.panorama import FLOAT_SUFFIXES, PANORAMA_SUFFIXES, is_panorama, named_panorama, readable_panorama

KINDS = ("photo", "panorama", "render")  # the order of the cumulative draw in :func:`kind_of_view`


@dataclass(frozen=True)
class Places:
    """``meshes``: paths for :func:`synth.envfile.find_environment_files`; ``panoramas`` and ``photos``: files;
    ``problems``: the files skipped because their header cannot be read (path and reason)."""

    meshes: tuple[Path, ...]
    panoramas: tuple[Path, ...]
    photos: tuple[Path, ...]
    problems: tuple[Problem, ...] = ()


def _has_meshes(folder: Path) -> bool:
    """Whether ``folder`` holds what :func:`synth.envfile.find_environment_files` finds (a mesh, or a sidecar
    naming one); a panorama folder's ``panoramas.yaml`` does not count."""
    return any(p.suffix.lower() in MESH_SUFFIXES or is_environment_sidecar(p) for p in folder.rglob("*"))


def split_places(environments: Iterable[Path | str], backgrounds: Iterable[Path | str] = ()) -> Places:
    """Sort ``environments`` into mesh paths and panorama files, and ``backgrounds`` into photos and panoramas.

    A folder of environments is searched for panoramas when it holds no mesh or sidecar file; a missing path is
    a FileNotFoundError, an environment file named that cannot be read a ValueError. An image in a folder of
    environments or among the backgrounds whose header cannot be read is skipped and named in ``problems``;
    backgrounds of which none can be read are a ValueError."""
    meshes: list[Path] = []
    panoramas: list[Path] = []
    problems: list[Problem] = []
    for item in environments:
        path = Path(item)
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such environment file or folder")
        if path.is_file():
            (panoramas if path.suffix.lower() in PANORAMA_SUFFIXES and named_panorama(path) else meshes).append(path)
        elif _has_meshes(path):
            meshes.append(path)
        else:
            panoramas += _panoramas_in(path, problems)
    photos: list[Path] = []
    backgrounds = list(backgrounds)
    if backgrounds:
        images, unreadable = list_image_files(backgrounds), []
        for image in images:
            try:
                (panoramas if is_panorama(image) else photos).append(image)
            except ImageError as exc:
                unreadable.append(Problem(str(image), exc.reason))
        for item in backgrounds:  # .hdr/.exr panoramas are not photos list_image_files knows
            if Path(item).is_dir():
                panoramas += _panoramas_in(Path(item), unreadable, FLOAT_SUFFIXES)
        if unreadable and not photos and not panoramas:
            raise ValueError(f"none of the {len(unreadable)} background images can be read: {unreadable[0]}")
        problems += unreadable
    return Places(tuple(meshes), tuple(dict.fromkeys(panoramas)), tuple(photos), tuple(dict.fromkeys(problems)))


def _panoramas_in(folder: Path, problems: list[Problem], suffixes: tuple[str, ...] = PANORAMA_SUFFIXES) -> list[Path]:
    """The panoramas in ``folder`` (recursive) with one of ``suffixes``; unreadable ones appended to
    ``problems``."""
    files = walk_files(folder, lambda n: n.lower().endswith(suffixes))
    return [p.absolute() for p in files if readable_panorama(p, problems)]


def kind_weights(available: Sequence[str], weights: Mapping[str, float]) -> dict[str, float]:
    """The normalised weights of the ``available`` kinds (a kind missing from ``weights`` weighs 0; when all
    available kinds weigh 0 they share equally)."""
    raw = {k: max(float(weights.get(k, 0.0)), 0.0) for k in KINDS if k in available}
    total = sum(raw.values())
    return {k: (v / total if total > 0 else 1.0 / len(raw)) for k, v in raw.items()}


def kind_of_view(seed: int, view_index: int, weights: Mapping[str, float]) -> str:
    """The kind view ``view_index`` shows: one uniform draw from ``default_rng([seed, 6, view_index])`` against
    the cumulative normalised ``weights`` in :data:`KINDS` order (a single kind needs no draw)."""
    if len(weights) == 1:
        return next(iter(weights))
    u = np.random.default_rng([seed, 6, view_index]).random()
    total = 0.0
    for kind, w in weights.items():
        total += w
        if u < total:
            return kind
    return list(weights)[-1]

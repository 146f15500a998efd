"""The places a pool is made in, by kind: rendered 3D environments (mesh files), 360-degree panoramas and
photographs. ``environments`` may hold meshes (or their sidecars) and equirectangular panoramas (a 2:1 image is
a place: :mod:`synth.places.panorama`); ``backgrounds`` holds photos, where a 2:1 image at least
:data:`PHOTO_PANORAMA_WIDTH` pixels wide is taken for a panorama and used as a place, not cropped flat. Which kind a view shows is drawn per view with the kinds' weights (:func:`kind_of_view`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curate.scan import list_image_files
from ground.data.problems import Problem
from ground.data.walk import walk_files
from ground.image.imageio import ImageError
from synth.places.envfile import MESH_SUFFIXES, is_environment_sidecar
from synth.places.panorama import FLOAT_SUFFIXES, PANORAMA_SUFFIXES, is_panorama, named_panorama, readable_panorama

KINDS = ("photo", "panorama", "render")  # the order of the cumulative draw in :func:`kind_of_view`
#: Least width (px) of a 2:1 background taken as a 360-degree panorama: a smaller 2:1 image is an ordinary wide
#: photo (a 450 x 223 conference room), while panoramas are 1024 x 512 and up (../shared/data/panoramas).
PHOTO_PANORAMA_WIDTH = 1024


@dataclass(frozen=True)
class Places:
    """``meshes``: paths for :func:`synth.places.envfile.find_environment_files`; ``panoramas`` and ``photos``: files;
    ``problems``: the files skipped because their header cannot be read (path and reason); ``taken``: the
    backgrounds taken as panoramas (:data:`PHOTO_PANORAMA_WIDTH`), of ``backgrounds`` background images."""

    meshes: tuple[Path, ...]
    panoramas: tuple[Path, ...]
    photos: tuple[Path, ...]
    problems: tuple[Problem, ...] = ()
    taken: tuple[Path, ...] = ()
    backgrounds: int = 0

    def panorama_note(self, shown: int = 10) -> str | None:
        """One line naming the backgrounds taken as 360-degree panoramas and why (None when none was)."""
        if not self.taken:
            return None
        names = ", ".join(p.name for p in self.taken[:shown])
        more = f" and {len(self.taken) - shown} more" if len(self.taken) > shown else ""
        return (
            f"took {len(self.taken)} of {self.backgrounds} backgrounds as 360° panoramas (2:1, >= "
            f"{PHOTO_PANORAMA_WIDTH} px wide): {names}{more}"
        )


def _has_meshes(folder: Path) -> bool:
    """Whether ``folder`` holds what :func:`synth.places.envfile.find_environment_files` finds (a mesh, or a sidecar
    naming one); a panorama folder's ``panoramas.yaml`` does not count."""
    return any(p.suffix.lower() in MESH_SUFFIXES or is_environment_sidecar(p) for p in folder.rglob("*"))


def split_places(environments: Iterable[Path | str], backgrounds: Iterable[Path | str] = ()) -> Places:
    """Sort ``environments`` into mesh paths and panorama files, and ``backgrounds`` into photos and panoramas.

    A folder of environments is searched for panoramas when it holds no mesh or sidecar file; a missing path is
    a FileNotFoundError, an environment file named that cannot be read a ValueError. Among environments a 2:1
    image is a panorama; among backgrounds only when it is also :data:`PHOTO_PANORAMA_WIDTH` pixels wide or more
    (a smaller 2:1 image is an ordinary wide photo). An image in a folder of environments or among the
    backgrounds whose header cannot be read is skipped and named in ``problems``; backgrounds of which none can
    be read are a ValueError."""
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
    photos, taken, skipped, count = _split_backgrounds(list(backgrounds))
    return Places(
        tuple(meshes),
        tuple(dict.fromkeys([*panoramas, *taken])),
        tuple(photos),
        tuple(dict.fromkeys([*problems, *skipped])),
        tuple(taken),
        count,
    )


def _split_backgrounds(backgrounds: list[Path | str]) -> tuple[list[Path], list[Path], list[Problem], int]:
    """(photos, panoramas, skipped files, how many images there were) of ``backgrounds``: the images
    (:func:`curate.scan.list_image_files`, and the .hdr/.exr files in its folders) sorted by
    :func:`is_panorama` with :data:`PHOTO_PANORAMA_WIDTH`; a .hdr/.exr that is no such panorama, or a file whose
    header cannot be read, is skipped. ValueError when there were images and none can be used."""
    if not backgrounds:
        return [], [], [], 0
    floats = [f.absolute() for b in backgrounds if Path(b).is_dir() for f in walk_files(b, _is_float)]
    images = list(dict.fromkeys([*list_image_files(backgrounds), *floats]))
    photos: list[Path] = []
    panoramas: list[Path] = []
    skipped: list[Problem] = []
    for image in images:
        try:
            wide = is_panorama(image, PHOTO_PANORAMA_WIDTH)
        except ImageError as exc:
            skipped.append(Problem(str(image), exc.reason))
            continue
        if wide:
            panoramas.append(image)
        elif image.suffix.lower() in FLOAT_SUFFIXES:  # a float image is no photo
            why = f"not a 2:1 panorama of >= {PHOTO_PANORAMA_WIDTH} px, and a {image.suffix} file is no photo"
            skipped.append(Problem(str(image), why))
        else:
            photos.append(image)
    if skipped and not photos and not panoramas:
        raise ValueError(f"none of the {len(skipped)} background images can be used: {skipped[0]}")
    return photos, panoramas, skipped, len(images)


def _is_float(name: str) -> bool:
    return name.lower().endswith(FLOAT_SUFFIXES)


def _panoramas_in(folder: Path, problems: list[Problem]) -> list[Path]:
    """The panoramas in ``folder`` (recursive); unreadable ones appended to ``problems``."""
    files = walk_files(folder, lambda n: n.lower().endswith(PANORAMA_SUFFIXES))
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

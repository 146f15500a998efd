"""Helpers shared by the readers: folder scans, header probing, box sanitising, class-name resolution."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from ground.data import boxes
from ground.data.classes import canonical_class, is_known, normalise_name
from ground.data.dataset import Dataset
from ground.data.names import check_names, split_names
from ground.data.problems import Problem
from ground.data.walk import walk_files
from ground.image.imageio import ImageError, image_size, is_image_file
from ground.run.progress import progress


@dataclass
class ReadResult:
    """What a reader found: the dataset it could build and every problem on the way. ``unlabelled``: ids of the
    images that have no label/annotation file at all (negatives by absence, as opposed to an empty label file)."""

    dataset: Dataset
    problems: list[Problem] = field(default_factory=list)
    unlabelled: frozenset[int] = frozenset()
    source_classes: tuple[str, ...] = ()  # the class names as the source spells them, before any alias

    def check_aliases(self, aliases: Mapping[str, str] | None, option: str = "--alias") -> ReadResult:
        """This result, after checking that every ``NAME`` of ``aliases`` (``{NAME: CLASS}``, any spelling) names a
        class of the source: one that names none raises :class:`~ground.data.names.UnknownNameError` listing
        the source's classes and naming the ``option`` that gave it, like :meth:`drop_classes` (a typo must not
        leave the boxes under their old name silently)."""
        spelt = {normalise_name(n) for n in self.source_classes}
        unknown = [name for name in aliases or {} if normalise_name(name) not in spelt]
        ds = self.dataset
        where = str(ds.info.get("source_root") or ds.info.get("source_file") or ds.root)
        check_names("class", unknown, list(self.source_classes), where, "classes", option)
        return self

    def drop_classes(self, names: Iterable[str], missing_ok: bool = False, option: str = "--drop-class") -> ReadResult:
        """Without the boxes of the classes ``names`` (any spelling; their images stay, maybe as negatives).

        A name may be a comma-separated list (``"default,smoke"``). The user chose to drop them, so their "unknown
        class" warnings go and an info line per class says how many boxes were dropped. A name the dataset has
        no class for raises :class:`~ground.data.names.UnknownNameError` listing its classes and naming the
        ``option`` that gave it (a typo must not keep the boxes silently), unless ``missing_ok`` (the caller
        checked the names against other datasets).
        """
        asked = [canonical_class(n) for n in split_names(names)]
        ds = self.dataset
        where = str(ds.info.get("source_root") or ds.info.get("source_file") or ds.root)
        if not missing_ok:
            check_names("class", asked, ds.category_names, where, "classes", option)
        drop = set(asked) & set(ds.category_names)
        if not drop:
            return self
        counts = Counter(ds.categories[a.category_id - 1].name for a in ds.annotations)
        problems = [p for p in self.problems if p.code not in {f"unknown-class:{n}" for n in drop}]
        problems += [Problem(where, f"dropped {counts[n]} boxes of class {n!r} as asked", "info") for n in sorted(drop)]
        left = ds.drop_categories(drop)
        emptied = len({a.image_id for a in ds.annotations}) - len({a.image_id for a in left.annotations})
        if emptied:
            problems.append(Problem(where, f"{emptied} images had only boxes of {', '.join(sorted(drop))} and are "
                                           "now images without boxes (negatives)", "info"))  # fmt: skip
        return ReadResult(left, problems, self.unlabelled, self.source_classes)


def list_images(folder: Path) -> list[Path]:
    """Image files below ``folder`` (recursive, linked folders followed, hidden entries skipped), sorted by POSIX
    path (see :mod:`ground.data.walk`)."""
    return walk_files(folder, is_image_file)


def probe_sizes(
    paths: Sequence[Path], desc: str = "reading image headers", workers: int = 8
) -> list[tuple[int, int] | ImageError]:
    """``(width, height)`` after EXIF orientation for each path, or the :class:`ImageError` it raised."""

    def one(path: Path) -> tuple[int, int] | ImageError:
        try:
            return image_size(path)
        except ImageError as exc:
            return exc

    with ThreadPoolExecutor(max_workers=workers) as pool:
        it = pool.map(one, paths)
        return list(progress(it, total=len(paths), desc=desc))


#: The code of the warning on a box that reached outside its image and was clipped to it.
CLIPPED = "clipped-box"


def sanitize_box(
    xywh: Sequence[float], width: int, height: int, where: str, problems: list[Problem]
) -> tuple[float, float, float, float] | None:
    """The box clipped to the image, or ``None`` (with an error) when it is NaN/inf or has no area.

    A box reaching outside the image is clipped and reported as a warning (code :data:`CLIPPED`).
    """
    if not all(math.isfinite(float(v)) for v in xywh):
        problems.append(Problem(where, f"box {_fmt(xywh)} has NaN or infinite values (dropped)"))
        return None
    x, y, w, h = (float(v) for v in xywh)
    if w <= 0 or h <= 0:
        problems.append(Problem(where, f"box {_fmt(xywh)} has zero or negative area (dropped)"))
        return None
    clipped = boxes.clip_xywh([x, y, w, h], width, height)
    if not bool(boxes.inside_xywh([x, y, w, h], width, height, tol=1e-3)):
        if clipped[2] <= 0 or clipped[3] <= 0:
            problems.append(Problem(where, f"box {_fmt(xywh)} lies outside the {width}x{height} image (dropped)"))
            return None
        problems.append(
            Problem(where, f"box {_fmt(xywh)} reaches outside the {width}x{height} image (clipped)", "warning", CLIPPED)
        )
        return (float(clipped[0]), float(clipped[1]), float(clipped[2]), float(clipped[3]))
    return (x, y, w, h)


def _fmt(xywh: Iterable[float]) -> str:
    return "[" + ", ".join(f"{float(v):.6g}" for v in xywh) + "] (x, y, w, h px)"


class ClassResolver:
    """Maps a source's class names to canonical names; reports each class outside the known vocabulary once.

    ``aliases`` adds user synonyms (source name -> canonical name). Unknown classes are kept under their
    normalised name (never silently dropped) and reported as a warning naming the source file (``where``) and,
    when the names come from one key of it, that key (``key``, e.g. ``names``).
    """

    def __init__(self, where: str, aliases: Mapping[str, str] | None = None, key: str = "") -> None:
        self.where = where
        self.key = key
        self.aliases = dict(aliases or {})
        self._reported: set[str] = set()
        self.seen: dict[str, None] = {}  # the source's class names, as spelt, in the order met

    def resolve(self, name: str, problems: list[Problem], where: str = "") -> str:
        """The canonical name of the source's class ``name`` (found in ``where``, default the source file)."""
        self.seen.setdefault(str(name), None)
        canonical = canonical_class(name, self.aliases)
        if not is_known(canonical) and canonical not in self._reported:
            self._reported.add(canonical)
            problems.append(
                Problem(
                    where or self.where,
                    f"{self.key + ': ' if self.key else ''}class {name!r} is not a known class (fire, smoke): kept as {canonical!r}; "
                    "map it with --alias NAME=fire or drop it with --drop-class",
                    "warning",
                    code=f"unknown-class:{canonical}",
                )
            )
        return canonical


def source_tag(root: Path, source: str | None) -> str:
    """The ``source`` tag of a real dataset: ``source`` as given, else ``real:<folder name>``."""
    return source if source else f"real:{root.resolve().name}"

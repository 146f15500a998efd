"""One split of a dataset with the classes a task wants: the one way every command and the experiment pick a
split, drop classes and fix the category list (read, :func:`pick_split`, :func:`with_classes`; both:
:func:`prepare`; read and prepare: :func:`load_split`). The class rules: an image whose every box was removed is
not a negative unless asked (``emptied``), and :func:`class_changes` counts what the rules touched."""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from curate.core.classes import KNOWN_CLASSES, canonical_class
from curate.core.dataset import Dataset
from curate.core.formats.registry import read_dataset
from curate.core.names import check_names


class SplitError(ValueError):
    """A split that is missing or has no images; the message names the dataset and the splits it has."""


def pick_split(ds: Dataset, split: str | None, where: Path | str = "", defaults: Sequence[str] = ()) -> Dataset:
    """The images of split ``split`` of ``ds`` (``val``, ``valid`` and ``validation`` name one split); None: the
    first of ``defaults`` that ``ds`` has, else every image. Raises :class:`SplitError` when the named split
    is missing or empty (``where`` names the dataset in the message)."""
    if split is None:
        found = next((s for s in (ds.resolve_split(d) for d in defaults) if s is not None), None)
        return ds if found is None else ds.select_split(found)
    if ds.resolve_split(split) is None:
        raise SplitError(f"{where or ds.root}: no split {split!r} ({splits_found(ds)})")
    chosen = ds.select_split(split)
    if not chosen.images:
        raise SplitError(f"{where or ds.root}: no images in split {split!r}")
    return chosen


def splits_found(ds: Dataset) -> str:
    """What a dataset has for splits, for a message: ``splits: 'train', 'valid'``, or ``no splits: its 16
    images are one set``."""
    named = [s for s in ds.splits if s]
    if not named:
        return f"no splits: its {len(ds.images)} images are one set"
    unsplit = " and images outside them" if "" in ds.splits else ""
    return "splits: " + ", ".join(repr(s) for s in named) + unsplit


#: What becomes of an image whose every box was removed (a dropped class, or a class not studied): ``leave`` =
#: it leaves the set (counted, :class:`ClassChanges`); ``negatives`` = it stays as an image without the classes.
Emptied = Literal["leave", "negatives"]
EMPTIED: tuple[str, ...] = ("leave", "negatives")


@dataclass(frozen=True)
class ClassChanges:
    """What the class rules did to one set: boxes removed per source class (``dropped``: named in drop_classes;
    ``unstudied``: not among the studied classes), the images left with no box (``emptied``) and whether they left
    the set (``emptied_rule`` ``leave``) or stayed as negatives (``negatives``)."""

    dropped: Mapping[str, int] = field(default_factory=dict)
    unstudied: Mapping[str, int] = field(default_factory=dict)
    emptied: int = 0
    emptied_rule: str = "leave"

    def __bool__(self) -> bool:
        return bool(self.dropped or self.unstudied)

    def to_dict(self) -> dict:
        return {"dropped": dict(self.dropped), "unstudied": dict(self.unstudied), "emptied": self.emptied,
                "emptied_rule": self.emptied_rule}  # fmt: skip

    def text(self) -> str:
        """One clause: ``smoke 2,194 boxes not studied; 97 images had only those boxes and left the set``."""
        parts = [f"{n} {c:,} boxes dropped (drop_classes)" for n, c in self.dropped.items()]
        parts += [f"{n} {c:,} boxes not studied" for n, c in self.unstudied.items()]
        if not parts:
            return "no class removed"
        fate = "left the set" if self.emptied_rule == "leave" else "stayed as images without them (emptied: negatives)"
        return "; ".join(parts) + f"; {self.emptied:,} images had only those boxes and {fate}"


def class_changes(ds: Dataset, classes: Sequence[str], drop: Sequence[str] = (), emptied: Emptied = "leave") -> ClassChanges:
    """What :func:`with_classes` (same arguments) removes from ``ds``: boxes per class and the emptied images."""
    drop = [canonical_class(n) for n in drop]
    counts = Counter(ds.categories[a.category_id - 1].name for a in ds.annotations)
    gone = _removed(ds, classes, drop)
    kept = {a.image_id for a in ds.annotations if ds.categories[a.category_id - 1].name not in gone}
    boxed = {a.image_id for a in ds.annotations}
    return ClassChanges(
        {n: counts[n] for n in ds.category_names if n in drop and counts[n]},
        {n: counts[n] for n in ds.category_names if n in gone and n not in drop and counts[n]},
        len(boxed - kept),
        emptied,
    )


def _removed(ds: Dataset, classes: Sequence[str], drop: Sequence[str]) -> list[str]:
    return [*drop, *(n for n in ds.category_names if n not in classes and n not in drop)]


def with_classes(ds: Dataset, classes: Sequence[str], drop: Sequence[str] = (), emptied: Emptied = "leave") -> Dataset:
    """``ds`` with exactly the categories ``classes``, in that order: boxes of ``drop`` and of every class not in
    ``classes`` removed. An image left with no box by that leaves the set (``emptied`` ``leave``; count them with
    :func:`class_changes`) or stays as a negative (``negatives``); images that had no box stay negatives."""
    if emptied not in EMPTIED:
        raise ValueError(f"emptied must be one of {', '.join(EMPTIED)}, got {emptied!r}")
    gone = _removed(ds, classes, drop)
    out = ds.drop_categories(gone)
    if emptied == "leave" and len(out.annotations) != len(ds.annotations):
        boxed = {a.image_id for a in ds.annotations}
        kept = {a.image_id for a in out.annotations}
        out = out.filter_images(lambda img: img.id not in boxed or img.id in kept)
    return out.with_categories(list(classes))


def data_classes(*datasets: Dataset, drop: Sequence[str] = ()) -> tuple[str, ...]:
    """The classes a study of ``datasets`` studies when its config names none: every class that has a box in
    one of them, less ``drop``; the known ones (:data:`~curate.core.classes.KNOWN_CLASSES`) first, then the
    others by name."""
    gone = {canonical_class(n) for n in drop}
    boxed = {ds.categories[a.category_id - 1].name for ds in datasets for a in ds.annotations} - gone
    return tuple(n for n in KNOWN_CLASSES if n in boxed) + tuple(sorted(boxed - set(KNOWN_CLASSES)))


def prepare(
    ds: Dataset,
    split: str | None,
    classes: Sequence[str] | None = None,
    drop: Sequence[str] = (),
    where: Path | str = "",
    emptied: Emptied = "leave",
) -> Dataset:
    """Split ``split`` of ``ds`` (None = every image; :func:`pick_split`), then :func:`with_classes` (``classes``
    None: only ``drop`` removed, images kept; ``emptied``: what becomes of an image left with no box). Raises :class:`SplitError` for a missing or empty split or no images and
    :class:`~curate.core.names.UnknownNameError` for a class of ``drop`` the dataset does not have."""
    drop = [canonical_class(n) for n in drop]
    check_names("class", drop, ds.category_names, str(where or ds.root), "classes", "drop_classes")
    chosen = pick_split(ds, split, where)
    if not chosen.images:
        raise SplitError(f"{where or ds.root}: no images")
    return chosen.drop_categories(drop) if classes is None else with_classes(chosen, classes, drop, emptied)


def load_split(
    path: Path | str,
    fmt: str = "auto",
    split: str | None = None,
    classes: Sequence[str] | None = None,
    aliases: Mapping[str, str] | None = None,
    drop: Sequence[str] = (),
    emptied: Emptied = "leave",
) -> Dataset:
    """Read the dataset at ``path`` (:func:`curate.core.formats.registry.read_dataset`, class ``aliases``
    applied; an alias of a class the dataset does not have is an :class:`~curate.core.names.UnknownNameError`)
    and :func:`prepare` split ``split`` with ``classes``."""
    return prepare(read_dataset(path, fmt, aliases=aliases or None).dataset, split, classes, drop, path, emptied)

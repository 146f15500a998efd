"""One split of a dataset with the classes a task wants: the one way every command and the experiment pick a
split, drop classes and fix the category list (read, :func:`pick_split`, :func:`with_classes`; both:
:func:`prepare`; read and prepare: :func:`load_split`). The class rules: an image whose every box was removed is
not a negative unless its class says so (``negatives``), and :func:`class_changes` counts what the rules touched."""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ground.data.classes import KNOWN_CLASSES, canonical_class
from ground.data.dataset import Dataset
from ground.data.formats.registry import read_dataset
from ground.data.names import check_names


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
    images are one set``; then the split entries of its dataset YAML that name nothing (file, key and value)."""
    named = [s for s in ds.splits if s]
    notes = "".join(f"; {note}" for note in ds.info.get("split_notes") or ())  # a dataset YAML's unmet entries
    if not named:
        return f"no splits: its {len(ds.images)} images are one set{notes}"
    unsplit = " and images outside them" if "" in ds.splits else ""
    return "splits: " + ", ".join(repr(s) for s in named) + unsplit + notes


@dataclass(frozen=True)
class ClassChanges:
    """What the class rules did to one set: boxes removed per class (``dropped``: named in drop_classes;
    ``unstudied``: not among the studied classes; ``negative``: named in negative_classes, boxes that mark an image
    without the studied classes), the images left with no box that left the set (``emptied``: every image that
    lost a dropped or unstudied box and has none left) and those kept as negatives (``negatives``: every box it
    lost was of a negative class)."""

    dropped: Mapping[str, int] = field(default_factory=dict)
    unstudied: Mapping[str, int] = field(default_factory=dict)
    negative: Mapping[str, int] = field(default_factory=dict)
    emptied: int = 0
    negatives: int = 0

    def __bool__(self) -> bool:
        return bool(self.dropped or self.unstudied or self.negative)

    def text(self) -> str:
        """One clause: ``smoke: 2,194 boxes not studied; 97 images had only such boxes and left the set``."""
        parts = [f"{n}: {c:,} boxes dropped (drop_classes)" for n, c in self.dropped.items()]
        parts += [f"{n}: {c:,} boxes not studied" for n, c in self.unstudied.items()]
        parts += [f"{n}: {c:,} boxes removed as marks of images without fire (negative_classes)"
                  for n, c in self.negative.items()]  # fmt: skip
        if not parts:
            return "no class removed"
        fates = (
            [f"{self.emptied:,} images had only such boxes and left the set"] if self.dropped or self.unstudied else []
        )
        fates += [f"{self.negatives:,} images stay as negatives"] if self.negative else []
        return "; ".join(parts + fates)


def class_changes(
    ds: Dataset, classes: Sequence[str], drop: Sequence[str] = (), negatives: Sequence[str] = ()
) -> ClassChanges:
    """What :func:`with_classes` (same arguments) removes from ``ds``: boxes per class and the emptied images."""
    drop, negatives = [canonical_class(n) for n in drop], [canonical_class(n) for n in negatives]
    counts = Counter(name for _, name in _holdings(ds))
    gone = _removed(ds, classes, drop, negatives)
    left, kept = _emptied(ds, gone, negatives)
    return ClassChanges(
        {n: counts[n] for n in ds.category_names if n in drop and counts[n]},
        {n: counts[n] for n in ds.category_names if n in gone and n not in drop and n not in negatives and counts[n]},
        {n: counts[n] for n in ds.category_names if n in negatives and counts[n]},
        len(left),
        len(kept),
    )


def _removed(ds: Dataset, classes: Sequence[str], drop: Sequence[str], negatives: Sequence[str]) -> list[str]:
    named = [*drop, *negatives]
    return [*named, *(n for n in ds.category_names if n not in classes and n not in named)]


def _emptied(ds: Dataset, gone: Sequence[str], negatives: Sequence[str]) -> tuple[set[int], set[int]]:
    """The ids of the images that lose every box to ``gone``: (those that leave, those kept as negatives because
    every box they lose is of a class in ``negatives``)."""
    keeps, losses = set(), Counter()
    marks = Counter()
    for image_id, name in _holdings(ds):
        if name not in gone:
            keeps.add(image_id)
        else:
            losses[image_id] += 1
            marks[image_id] += name in negatives
    emptied = set(losses) - keeps
    kept = {i for i in emptied if marks[i] == losses[i]}
    return emptied - kept, kept


def _holdings(ds: Dataset) -> list[tuple[int, str]]:
    """(image id, class name) of every box and every image-level label of ``ds``."""
    boxes = [(a.image_id, ds.categories[a.category_id - 1].name) for a in ds.annotations]
    return boxes + [(img.id, name) for img in ds.images for name in img.labels]


def with_classes(
    ds: Dataset, classes: Sequence[str], drop: Sequence[str] = (), negatives: Sequence[str] = ()
) -> Dataset:
    """``ds`` with exactly the categories ``classes``, in that order: boxes of ``drop``, of ``negatives`` and of
    every class not in ``classes`` removed. An image left with no box leaves the set (count them with
    :func:`class_changes`) unless every box it lost was of a class in ``negatives`` (boxes that mark an image
    without the studied classes, such as a 'default' box): then it stays as a negative, as do images that had no
    box."""
    drop, negatives = [canonical_class(n) for n in drop], [canonical_class(n) for n in negatives]
    gone = _removed(ds, classes, drop, negatives)
    out = ds.drop_categories(gone)
    if len(out.annotations) != len(ds.annotations) or out.images != ds.images:
        left, _ = _emptied(ds, gone, negatives)
        out = out.filter_images(lambda img: img.id not in left)
    return out.with_categories(list(classes))


def data_classes(*datasets: Dataset, drop: Sequence[str] = ()) -> tuple[str, ...]:
    """The classes a study of ``datasets`` studies when its config names none: every class that has a box (or an
    image-level label) in one of them, less ``drop``; the known ones (:data:`~ground.data.classes.KNOWN_CLASSES`) first, then the
    others by name."""
    gone = {canonical_class(n) for n in drop}
    boxed = {name for ds in datasets for _, name in _holdings(ds)} - gone
    return tuple(n for n in KNOWN_CLASSES if n in boxed) + tuple(sorted(boxed - set(KNOWN_CLASSES)))


def prepare(
    ds: Dataset,
    split: str | None,
    classes: Sequence[str] | None = None,
    drop: Sequence[str] = (),
    where: Path | str = "",
    negatives: Sequence[str] = (),
) -> Dataset:
    """Split ``split`` of ``ds`` (None = every image; :func:`pick_split`), then :func:`with_classes` (``classes``
    None: only ``drop`` removed, images kept; ``negatives``: classes whose images stay as negatives). Raises :class:`SplitError` for a missing or empty split or no images and
    :class:`~ground.data.names.UnknownNameError` for a class of ``drop`` the dataset does not have."""
    drop, negatives = [canonical_class(n) for n in drop], [canonical_class(n) for n in negatives]
    check_names("class", drop, ds.category_names, str(where or ds.root), "classes", "drop_classes")
    check_names("class", negatives, ds.category_names, str(where or ds.root), "classes", "negative_classes")
    chosen = pick_split(ds, split, where)
    if not chosen.images:
        raise SplitError(f"{where or ds.root}: no images")
    return chosen.drop_categories(drop) if classes is None else with_classes(chosen, classes, drop, negatives)


def load_split(
    path: Path | str,
    fmt: str = "auto",
    split: str | None = None,
    classes: Sequence[str] | None = None,
    aliases: Mapping[str, str] | None = None,
    drop: Sequence[str] = (),
    negatives: Sequence[str] = (),
) -> Dataset:
    """Read the dataset at ``path`` (:func:`ground.data.formats.registry.read_dataset`, class ``aliases``
    applied; an alias of a class the dataset does not have is an :class:`~ground.data.names.UnknownNameError`)
    and :func:`prepare` split ``split`` with ``classes``."""
    return prepare(read_dataset(path, fmt, aliases=aliases or None).dataset, split, classes, drop, path, negatives)

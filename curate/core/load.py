"""One split of a dataset with the classes a task wants: the one way every command and the experiment pick a
split, drop classes and fix the category list (read, :func:`pick_split`, :func:`with_classes`; both:
:func:`prepare`; read and prepare: :func:`load_split`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from curate.core.classes import canonical_class
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
    images are one set``; then the split entries of its dataset YAML that name nothing (file, key and value)."""
    named = [s for s in ds.splits if s]
    notes = "".join(f"; {note}" for note in ds.info.get("split_notes") or ())  # a dataset YAML's unmet entries
    if not named:
        return f"no splits: its {len(ds.images)} images are one set{notes}"
    unsplit = " and images outside them" if "" in ds.splits else ""
    return "splits: " + ", ".join(repr(s) for s in named) + unsplit + notes


def with_classes(ds: Dataset, classes: Sequence[str], drop: Sequence[str] = ()) -> Dataset:
    """``ds`` with exactly the categories ``classes``, in that order: boxes of ``drop`` and of every class not in
    ``classes`` removed (their images stay, maybe as negatives)."""
    gone = [*drop, *(n for n in ds.category_names if n not in classes and n not in drop)]
    return ds.drop_categories(gone).with_categories(list(classes))


def prepare(
    ds: Dataset,
    split: str | None,
    classes: Sequence[str] | None = None,
    drop: Sequence[str] = (),
    where: Path | str = "",
) -> Dataset:
    """Split ``split`` of ``ds`` (None = every image; :func:`pick_split`), then :func:`with_classes` (``classes``
    None: only ``drop`` removed). Raises :class:`SplitError` for a missing or empty split or no images and
    :class:`~curate.core.names.UnknownNameError` for a class of ``drop`` the dataset does not have."""
    drop = [canonical_class(n) for n in drop]
    check_names("class", drop, ds.category_names, str(where or ds.root), "classes", "drop_classes")
    chosen = pick_split(ds, split, where)
    if not chosen.images:
        raise SplitError(f"{where or ds.root}: no images")
    return chosen.drop_categories(drop) if classes is None else with_classes(chosen, classes, drop)


def load_split(
    path: Path | str,
    fmt: str = "auto",
    split: str | None = None,
    classes: Sequence[str] | None = None,
    aliases: Mapping[str, str] | None = None,
    drop: Sequence[str] = (),
) -> Dataset:
    """Read the dataset at ``path`` (:func:`curate.core.formats.registry.read_dataset`, class ``aliases``
    applied; an alias of a class the dataset does not have is an :class:`~curate.core.names.UnknownNameError`)
    and :func:`prepare` split ``split`` with ``classes``."""
    return prepare(read_dataset(path, fmt, aliases=aliases or None).dataset, split, classes, drop, path)

"""The datasets of an experiment: references to them (:class:`DataRef`) and :class:`Datasets`, which reads each
from disk once and keeps every split the experiment asks for in its prepared state (one split, the
experiment's classes)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ground.data.classes import canonical_class
from ground.data.dataset import Dataset
from ground.data.formats.images import IMAGE_LABELLED, NEGATIVES_ONLY
from ground.data.formats.registry import read_dataset
from ground.data.holdout import held_out_images
from ground.data.load import ClassChanges, class_changes, pick_split, prepare


@dataclass(frozen=True)
class DataRef:
    """A labelled dataset a run reads: ``path`` (folder or COCO .json) in ``format``, one ``split`` of it (None =
    every image), classes renamed by ``aliases`` and ``drop`` removed (an image left with no box by the class
    rules leaves the set unless every box it lost was of a class of ``negatives``:
    :func:`ground.data.load.with_classes`), with ``holdout`` > 0 only the images
    :func:`ground.data.holdout.held_out` picks at that share, and without the images ``exclude`` names (their
    ``file_name``: test images that leak from the training data, :mod:`fuzzyfire.leakage`). ``label``: the class
    every image of a folder without label files holds (an image-labelled set; on a stand-in, its image-level
    view: :meth:`ground.data.dataset.Dataset.at_image_level`). ``identity``: what made it
    (hashable JSON; no absolute output paths, so two experiment folders give the same run identities)."""

    path: Path
    identity: Mapping[str, Any]
    format: str = "auto"
    split: str | None = None
    aliases: Mapping[str, str] = field(default_factory=dict)
    drop: tuple[str, ...] = ()
    standin: bool = False
    holdout: float = 0.0
    exclude: tuple[str, ...] = ()
    negatives: tuple[str, ...] = ()
    label: str | None = None

    def with_split(self, split: str | None) -> DataRef:
        return replace(self, split=split)

    def key(self) -> dict[str, Any]:
        """The identity of this split of the data (and of the images it leaves out, when it leaves any)."""
        left_out = {"exclude": sorted(self.exclude)} if self.exclude else {}
        return {"data": dict(self.identity), "split": self.split, **left_out}

    def source(self) -> tuple[str, str, tuple[tuple[str, str], ...], str | None]:
        """What is read from disk: the same for every split of one dataset."""
        return (Path(self.path).as_posix(), self.format, tuple(sorted(self.aliases.items())), self.label)


class Datasets:
    """Each dataset read once, each (split, classes) prepared once; ``classes`` are the experiment's.

    :meth:`read` gives a dataset as read (every split, its own classes), :meth:`get` one split of it with
    exactly ``classes`` (:func:`ground.data.load.prepare`). Both return shared immutable objects."""

    def __init__(
        self, classes: Sequence[str], read: dict[tuple, Dataset] | None = None, notes: dict[tuple, str] | None = None
    ) -> None:
        self.classes = tuple(classes)
        self._read: dict[tuple, Dataset] = {} if read is None else read
        self._notes: dict[tuple, str] = {} if notes is None else notes
        self._prepared: dict[tuple, Dataset] = {}

    def for_classes(self, classes: Sequence[str]) -> Datasets:
        """Datasets prepared with ``classes`` instead, sharing what this one has read (nothing is read again)."""
        return Datasets(classes, self._read, self._notes)

    def read(self, ref: DataRef) -> Dataset:
        """``ref``'s dataset as read, every split (read on first use)."""
        key = ref.source()
        if key not in self._read:
            self._read[key], self._notes[key] = read_ref(ref)
        return self._read[key]

    def reading(self, ref: DataRef) -> str:
        """What ``ref``'s folder was read as when it holds no boxes ("a negatives-only set", "an image-labelled
        set"), in the reader's words; "" for a set with boxes."""
        self.read(ref)
        return self._notes[ref.source()]

    def get(self, ref: DataRef) -> Dataset:
        """Split ``ref.split`` (None = every image) with exactly the experiment's classes, in their order.
        Raises ValueError when the split is missing or has no images."""
        key = (ref.source(), ref.split, ref.drop, ref.holdout, ref.exclude, ref.negatives)
        if key not in self._prepared:
            ds = prepare(self.read(ref), ref.split, self.classes, ref.drop, ref.path, ref.negatives)
            self._prepared[key] = _narrowed(ds, ref)
        return self._prepared[key]

    def changes(self, ref: DataRef) -> ClassChanges:
        """What the class rules remove from split ``ref.split`` (None = every image) of ``ref``'s dataset
        (:func:`ground.data.load.class_changes`), before its hold-out and leaked images are taken out."""
        chosen = pick_split(self.read(ref), ref.split, ref.path)
        return class_changes(chosen, self.classes, ref.drop, ref.negatives)


def read_ref(ref: DataRef) -> tuple[Dataset, str]:
    """``ref``'s dataset as read (every split; a stand-in with a ``label`` at the image level) and what its folder
    was read as when it holds no boxes (the reader's info line: :data:`ground.data.formats.images.NEGATIVES_ONLY`,
    :data:`ground.data.formats.images.IMAGE_LABELLED`; "" otherwise)."""
    label = None if ref.standin else ref.label
    result = read_dataset(ref.path, ref.format, aliases=dict(ref.aliases) or None, label=label)
    ds = result.dataset
    if ref.standin and ref.label:
        ds = ds.at_image_level(canonical_class(ref.label))
        return (
            ds,
            f"a stand-in read at the image level: {len(ds.labelled_ids())} of {len(ds.images)} images hold {ref.label}",
        )
    said = [p.reason for p in result.problems if p.code in (NEGATIVES_ONLY, IMAGE_LABELLED)]
    return ds, said[0] if said else ""


def _narrowed(ds: Dataset, ref: DataRef) -> Dataset:
    """``ds`` (``ref``'s split, prepared) with only its held-out share and without the images ``ref`` excludes."""
    ds = held_out_images(ds, ref.holdout, ref.path) if ref.holdout else ds
    if ref.exclude:
        left_out = set(ref.exclude)
        ds = ds.filter_images(lambda img: img.file_name not in left_out)
    return ds


def load_data(ref: DataRef, classes: Sequence[str]) -> Dataset:
    """``ref``'s split with exactly ``classes``, read from disk now (a run outside an experiment)."""
    ds = prepare(read_ref(ref)[0], ref.split, classes, ref.drop, ref.path, ref.negatives)
    return _narrowed(ds, ref)

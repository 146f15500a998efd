"""A dataset's contents in one hash: which image files (by content), in which split, with which boxes.

Two folders with the same fingerprint hold the same pictures in the same splits with the same labels, wherever
they are and whatever their image files are called (symbolic links are followed). Used by the experiment's
stages (``stage.json`` records the fingerprint of what a stage produced) and by docs/findings.md's statement of the
shared-data curated set.
"""

from __future__ import annotations

import hashlib
from collections import Counter
from dataclasses import dataclass

from ground.data.dataset import Dataset
from ground.data.manifest import hash_files


@dataclass(frozen=True)
class Fingerprint:
    """``digest``: 16 hex digits; ``images``: count; ``splits``: images per split name (sorted by name)."""

    digest: str
    images: int
    splits: dict[str, int]

    def to_dict(self) -> dict[str, object]:
        return {"fingerprint": self.digest, "images": self.images, "splits": self.splits}

    def describe(self) -> str:
        """``629 images (test 126, train 440, valid 63), fingerprint 1a2b...``"""
        parts = ", ".join(f"{name or '(none)'} {n}" for name, n in self.splits.items())
        return f"{self.images} images ({parts}), fingerprint {self.digest}"


def image_lines(ds: Dataset) -> list[str]:
    """One line per image: ``split<TAB>sha256 of its bytes<TAB>its boxes`` (class name and x, y, w, h rounded
    to 0.01 px, sorted), the lines sorted. File names and ids do not enter: a renamed copy matches."""
    names = {c.id: c.name for c in ds.categories}
    boxes = ds.annotations_by_image()
    shas = [sha for sha, _ in hash_files([ds.image_path(img) for img in ds.images])]
    lines = []
    for img, sha in zip(ds.images, shas):
        labels = sorted(
            f"{names[a.category_id]}:{','.join(f'{v:.2f}' for v in a.bbox)}:{a.iscrowd}" for a in boxes[img.id]
        )
        lines.append(f"{img.split}\t{sha}\t{';'.join(labels)}")
    return sorted(lines)


def fingerprint(ds: Dataset) -> Fingerprint:
    """The :class:`Fingerprint` of ``ds`` (its image files are read and hashed)."""
    text = "\n".join(image_lines(ds)) + "\n"
    splits = dict(sorted(Counter(img.split for img in ds.images).items()))
    return Fingerprint(hashlib.sha256(text.encode("utf-8")).hexdigest()[:16], len(ds.images), splits)

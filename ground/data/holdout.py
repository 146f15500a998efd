"""A share of images held out by content: the photos no synthetic pool composites on, and so the images a
false-alarm test set may use. An image is held out at ``share`` when the first 8 hex digits of its file's sha256,
as a fraction of 16^8, are >= 1 - share — the same images on every machine, for every seed and under any name, and
the images held out at a share are among those held out at any larger share."""

from __future__ import annotations

from pathlib import Path

from ground.data.dataset import Dataset
from ground.data.manifest import file_sha256


def content_fraction(image: Path) -> float:
    """Where the image file ``image`` falls in [0, 1) by its content: the first 8 hex digits of its sha256 as a
    fraction of 16^8 (the images held out at ``share`` are those at or above ``1 - share``)."""
    return int(file_sha256(image)[:8], 16) / 16**8


def held_out(image: Path, share: float) -> bool:
    """Whether the image file ``image`` is among the ``share`` (0..1) of images held out by content."""
    return share > 0 and content_fraction(image) >= 1.0 - share


def held_out_images(ds: Dataset, share: float, where: Path | str = "") -> Dataset:
    """The images of ``ds`` :func:`held_out` at ``share`` (0..1), with their boxes: the test set of photos that a
    Method 2 pool with ``background_holdout: share`` never shows. Raises ValueError when ``share`` is outside 0..1
    or none is held out (``where`` names the set in the message)."""
    if not 0.0 <= share <= 1.0:
        raise ValueError(f"a held-out share is in 0..1, got {share:g}")
    kept = ds.filter_images(lambda img: held_out(ds.image_path(img), share))
    if not kept.images:
        raise ValueError(f"{where or ds.root}: none of its {len(ds.images)} images is held out at share {share:g}")
    return kept

"""A folder of images and nothing else (no label, annotation or data.yaml file). Undeclared, it is a negatives-only
set: every image kept as a negative (photographs without fire, for false alarms or as hard negatives). Declared
with a ``label`` (``label: fire``), every image holds that class at the image level: an image-labelled set, judged
by image recall (no boxes, no AP)."""

from __future__ import annotations

from pathlib import Path

from ground.data.classes import canonical_class
from ground.data.dataset import DatasetBuilder
from ground.data.formats.common import ReadResult, list_images, probe_sizes, source_tag
from ground.data.problems import Problem
from ground.image.imageio import ImageError

NEGATIVES_ONLY = "negatives-only"  # the code of the info line that says a folder was read as negatives only
IMAGE_LABELLED = "image-labelled"  # the code of the info line that says a folder was read at the image level


def negatives_only_note(count: int) -> str:
    """What such a folder is, in the words every command uses."""
    return f"{count} images, no label files: a negatives-only set"


def labelled_note(count: int, label: str) -> str:
    """What a folder declared with ``label`` is, in the words every command uses."""
    return f"{count} images, each declared {label!r} (label: {label}): an image-labelled set (image recall, no AP)"


def read_images(root: Path | str, source: str | None = None, label: str | None = None) -> ReadResult:
    """Every image below ``root`` (one split): a negative, or with ``label`` (any spelling of a class) labelled
    with that class at the image level. Unreadable images are skipped and named. The folder itself is named with
    what it was read as (an info line, code :data:`NEGATIVES_ONLY` or :data:`IMAGE_LABELLED`)."""
    root = Path(root)
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: not a folder")
    paths = list_images(root)
    if not paths:
        raise ValueError(f"{root}: no images, labels or annotations found")
    name = None if label is None else canonical_class(label)
    if name is not None and not name:
        raise ValueError(f"{root}: label must name a class, got {label!r}")
    note = negatives_only_note(len(paths)) if name is None else labelled_note(len(paths), name)
    problems = [Problem(str(root), note, "info", code=NEGATIVES_ONLY if name is None else IMAGE_LABELLED)]
    builder = DatasetBuilder(root, [name] if name else ())
    tag = source_tag(root, source)
    for path, size in zip(paths, probe_sizes(paths)):
        if isinstance(size, ImageError):
            problems.append(Problem(str(path), f"unreadable image: {size.reason} (skipped)"))
            continue
        builder.add_image(path.relative_to(root).as_posix(), size[0], size[1], tag, labels=(name,) if name else ())
    dataset = builder.build({"format": "images", "source_root": str(root.resolve())})
    return ReadResult(dataset, problems, frozenset(img.id for img in dataset.images))

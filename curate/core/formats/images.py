"""A folder of images and nothing else (no label, annotation or data.yaml file): a negatives-only set, every
image kept as a negative (photographs without fire, for false alarms or as hard negatives)."""

from __future__ import annotations

from pathlib import Path

from curate.core.dataset import DatasetBuilder
from curate.core.formats.common import ReadResult, list_images, probe_sizes, source_tag
from curate.core.imageio import ImageError
from curate.core.problems import Problem


def negatives_only_note(count: int) -> str:
    """What such a folder is, in the words every command uses."""
    return f"{count} images, no label files: a negatives-only set"


def read_images(root: Path | str, source: str | None = None) -> ReadResult:
    """Every image below ``root`` as a negative (one split, no classes); unreadable images are skipped and
    named. The folder itself is named with what it holds (an info line)."""
    root = Path(root)
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: not a folder")
    paths = list_images(root)
    if not paths:
        raise ValueError(f"{root}: no images, labels or annotations found")
    problems = [Problem(str(root), negatives_only_note(len(paths)), "info", code="negatives-only")]
    builder = DatasetBuilder(root)
    tag = source_tag(root, source)
    for path, size in zip(paths, probe_sizes(paths)):
        if isinstance(size, ImageError):
            problems.append(Problem(str(path), f"unreadable image: {size.reason} (skipped)"))
            continue
        builder.add_image(path.relative_to(root).as_posix(), size[0], size[1], tag)
    dataset = builder.build({"format": "images", "source_root": str(root.resolve())})
    return ReadResult(dataset, problems, frozenset(img.id for img in dataset.images))

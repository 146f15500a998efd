"""Dataset validation: everything a reader reports, plus a full decode of every image (a truncated file
can have a perfect header). Problems come back ordered errors -> warnings -> info."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ground.data.dataset import Dataset
from ground.data.formats.common import ReadResult
from ground.data.formats.registry import read_dataset
from ground.data.problems import LEVELS, Problem
from ground.image.imageio import ImageError, decode_image, jpeg_repaired, read_bytes
from ground.run.progress import progress


def decode_problems(ds: Dataset, workers: int = 4) -> list[Problem]:
    """An error for every image of ``ds`` that does not fully decode; a warning for each thing in a JPEG that
    libjpeg skips with a warning of its own (:func:`~ground.image.imageio.jpeg_repaired`: the image decodes)."""

    def check(path: Path) -> list[Problem]:
        try:
            data, notes = jpeg_repaired(read_bytes(path))
            decode_image(data, path)
        except ImageError as exc:
            return [Problem(str(path), f"unreadable image: {exc.reason}")]
        return [Problem(str(path), f"{note}: skipped, the image decodes", "warning") for note in notes]

    paths = [ds.image_path(img) for img in ds.images]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        found = list(progress(pool.map(check, paths), total=len(paths), desc="decoding images"))
    return [p for problems in found for p in problems]


def validate(
    path: Path | str,
    fmt: str = "auto",
    names: Sequence[str] | None = None,
    aliases: Mapping[str, str] | None = None,
    decode: bool = True,
    alias_option: str = "aliases",
) -> ReadResult:
    """Read ``path`` and check it; returns what could be read with every problem, sorted by level (``aliases``
    of classes the source lacks: :func:`~ground.data.formats.registry.read_dataset`)."""
    result = read_dataset(path, fmt, names=names, aliases=aliases, alias_option=alias_option)
    problems = list(result.problems)
    if decode:
        problems += decode_problems(result.dataset)
    order = {level: i for i, level in enumerate(LEVELS)}
    problems.sort(key=lambda p: order[p.level])
    return ReadResult(result.dataset, problems, result.unlabelled, result.source_classes)

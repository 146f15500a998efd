"""The realism gap of a synthetic image set: the Fréchet distance between its CNN embeddings and a real set's.

Images are embedded as curation embeds them (the built-in ImageNet EfficientNet-Lite0 or a user ONNX model,
L2-normalised whole-image embeddings, cached by content hash), so a rerun costs only hashing. The distance is
measured at equal set sizes against half of the real set, next to the real set's distance to its own other
half (the floor a perfect generator reaches); see :mod:`curate.frechet`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from curate.core.problems import Problem
from curate.embed import OnnxEmbedder
from curate.embedcache import EmbeddingCache
from curate.frechet import Gap, gap_interval
from curate.scan import list_image_files, scan_images


@dataclass(frozen=True)
class ImageSet:
    """Readable images of one side: their L2-normalised embeddings (N, D) float32 and what could not be read."""

    label: str
    vectors: NDArray[np.float32]
    problems: tuple[Problem, ...]


@dataclass(frozen=True)
class GapReport:
    synthetic: ImageSet
    real: ImageSet
    gap: Gap
    model: str

    def to_json(self) -> dict[str, Any]:
        """``{"sets": {synthetic, real: {path, images}}, "model", "size", "draws", "frechet": {synthetic, floor,
        ratio: {median, low, high}}}``."""
        g = self.gap
        return {
            "sets": {
                "synthetic": {"path": self.synthetic.label, "images": len(self.synthetic.vectors)},
                "real": {"path": self.real.label, "images": len(self.real.vectors)},
            },
            "model": self.model,
            "size": g.size,
            "draws": g.draws,
            "frechet": {k: asdict(getattr(g, k)) for k in ("synthetic", "floor", "ratio")},
        }

    def lines(self) -> list[str]:
        g = self.gap
        return [
            f"synthetic {self.synthetic.label}: {len(self.synthetic.vectors)} images; "
            f"real {self.real.label}: {len(self.real.vectors)} images",
            f"Fréchet distance of embeddings, {g.size} images per side, median [2.5%, 97.5%] of {g.draws} draws:",
            f"  synthetic vs real  {g.synthetic}",
            f"  real vs real       {g.floor}   (the floor)",
            f"  ratio              {g.ratio.median:.2f} [{g.ratio.low:.2f}, {g.ratio.high:.2f}]"
            "   (1 = as close to the real set as the real set is to itself)",
        ]


def dataset_images(path: Path, split: str | None = None, fmt: str = "auto") -> list[Path]:
    """Image paths of the dataset at ``path`` (any format the toolkit reads), of ``split`` when given;
    ``fmt="images"``: every image file under the folder (no labels needed)."""
    from curate.core.formats.registry import read_dataset
    from curate.core.load import pick_split

    if fmt == "images":
        if split is not None:
            raise ValueError(f"{path}: a split needs a dataset format, not 'images'")
        paths = list_image_files([path])
        if not paths:
            raise ValueError(f"{path}: no image files")
        return paths
    try:
        ds = read_dataset(path, fmt).dataset
    except ValueError as exc:
        raise ValueError(f"{exc} (or 'images' for a plain folder of images)") from None
    ds = pick_split(ds, split, path)
    if not ds.images:
        raise ValueError(f"{path}: no images")
    return [ds.image_path(im) for im in ds.images]


def image_kinds(folder: Path) -> dict[str, str]:
    """Image file (resolved path) -> the kind of place it was made in (``photo``, ``panorama``, ``render``), for a
    mixed pool whose ``manifest.json`` records it per image; {} for anything else."""
    import json

    manifest = folder / "manifest.json"
    if not manifest.is_file():
        return {}
    doc = json.loads(manifest.read_text(encoding="utf-8"))
    per_image = doc.get("args", {}).get("per_image") or []
    files = [entry["file"] for entry in doc.get("images", [])]
    if len(files) != len(per_image):
        return {}
    return {
        (folder / name).resolve().as_posix(): meta["kind"]
        for name, meta in zip(files, per_image)
        if isinstance(meta, dict) and "kind" in meta
    }


def split_by_kind(images: ImageSet, paths: Sequence[Path], kinds: dict[str, str]) -> dict[str, ImageSet]:
    """``images`` (embedded from ``paths``, in order, all readable) divided by the kind of each path."""
    if not kinds or len(paths) != len(images.vectors):
        return {}
    labels = [kinds.get(Path(p).resolve().as_posix()) for p in paths]
    return {
        kind: ImageSet(f"{images.label} [{kind}]", images.vectors[[k for k, x in enumerate(labels) if x == kind]], ())
        for kind in sorted({x for x in labels if x})
    }


def embed_set(
    label: str, paths: Sequence[Path], embedder: OnnxEmbedder, cache: EmbeddingCache | None, workers: int = 0
) -> ImageSet:
    """Embeddings of the readable ``paths``; unreadable ones are kept as problems."""
    scan = scan_images(paths, embedder, cache, workers)
    return ImageSet(label, scan.vectors, tuple(scan.problems))


def measure_gap(
    synthetic: ImageSet,
    real: ImageSet,
    model: str,
    rng: np.random.Generator,
    draws: int = 200,
    size: int | None = None,
) -> GapReport:
    """The gap of ``synthetic`` to ``real`` with its floor (see :func:`curate.frechet.gap_interval`)."""
    return GapReport(synthetic, real, gap_interval(synthetic.vectors, real.vectors, rng, draws, size), model)

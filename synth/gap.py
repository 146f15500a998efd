"""The realism gap of a synthetic image set: the Fréchet distance between its CNN embeddings and a real set's.

Images are embedded as curation embeds them (the built-in ImageNet EfficientNet-Lite0 or a user ONNX model,
L2-normalised whole-image embeddings, cached by content hash), so a rerun costs only hashing. The distance is
measured at equal set sizes against half of the real set, next to the real set's distance to its own other
half (the floor a perfect generator reaches); see :mod:`curate.frechet`.

The *flame gap* (``--crops``) compares the objects instead of the whole images: every box of a class (``fire``)
is cut out with :data:`CROP_CONTEXT` of its size as context on each side (clipped to the image), resized by the
embedder's own preprocessing and embedded (no cache: crops are not files). The same Fréchet distance and floor
are then taken over crops rather than images. Of a pool composited on labelled frames only the flames it drew are
cut out (:func:`synthetic_boxes`): the frames' own fires are real.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal, Optional

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.embed import OnnxEmbedder, l2_normalize
from curate.embedcache import EmbeddingCache
from curate.frechet import DRAWS, Gap, gap_interval
from curate.scan import list_image_files, scan_images
from curate.settings import EmbedderConfig
from ground.data.problems import Problem
from ground.image.imageio import ImageError, read_image


@dataclass(frozen=True)
class ImageSet:
    """Readable images of one side: their L2-normalised embeddings (N, D) float32 and what could not be read."""

    label: str
    vectors: NDArray[np.float32]
    problems: tuple[Problem, ...]


#: Context around a box when it is cut out for the flame gap: this fraction of the box's width (height) on the
#: left and right (top and bottom).
CROP_CONTEXT = 0.1

#: The layout of a side: ``auto`` (detect), a labelled format, or ``images`` (a plain folder of images).
GapFormat = Literal["auto", "coco", "yolo", "voc", "dfire", "images"]


@dataclass(frozen=True)
class GapConfig:
    """``fuzzyfire synth gap SYNTHETIC REAL``: how far a synthetic set is from a real one (module docstring)."""

    format: GapFormat = "auto"  # layout of SYNTHETIC (auto: detect; images: a plain folder of images, no labels)
    real_format: GapFormat = "auto"  # layout of REAL, as format
    draws: int = DRAWS  # random equal-size draws, >= 1
    size: Optional[int] = None  # images (crops) per side, >= 2; null = min(synthetic, real / 2)
    seed: int = 0  # seed of the draws
    crops: bool = False  # the flame gap: compare box crops, not whole images
    class_name: str = "fire"  # crops: the boxes' class
    context: float = CROP_CONTEXT  # crops: context around a box, fraction of its width (height) on each side, >= 0
    all_boxes: bool = False  # crops: also the boxes a pool has no flame mask for (the own fires of the labelled
    # frames it composited on; left out by default: they are real flames)
    model: EmbedderConfig = EmbedderConfig()  # the embedding CNN (built-in ImageNet Lite0, or your ONNX), as dedup's

    def __post_init__(self) -> None:
        if self.draws < 1 or (self.size is not None and self.size < 2) or self.context < 0:
            raise ValueError(
                f"draws must be >= 1, size >= 2 (or null), context >= 0; got {self.draws}, {self.size}, {self.context}"
            )


@dataclass(frozen=True)
class GapReport:
    synthetic: ImageSet
    real: ImageSet
    gap: Gap
    model: str
    unit: str = "images"  # what a vector is: "images", or "crops" (boxes with context: the flame gap)

    def to_json(self) -> dict[str, Any]:
        """``{"sets": {synthetic, real: {path, images}}, "unit", "model", "size", "draws", "frechet": {synthetic,
        floor, ratio: {median, low, high}}}``; ``images`` counts vectors: crops when ``unit`` is ``crops``."""
        g = self.gap
        return {
            "sets": {
                "synthetic": {"path": self.synthetic.label, "images": len(self.synthetic.vectors)},
                "real": {"path": self.real.label, "images": len(self.real.vectors)},
            },
            "unit": self.unit,
            "model": self.model,
            "size": g.size,
            "draws": g.draws,
            "frechet": {k: asdict(getattr(g, k)) for k in ("synthetic", "floor", "ratio")},
        }

    def lines(self) -> list[str]:
        g, u = self.gap, self.unit
        return [
            f"synthetic {self.synthetic.label}: {len(self.synthetic.vectors)} {u}; "
            f"real {self.real.label}: {len(self.real.vectors)} {u}",
            f"Fréchet distance of embeddings, {g.size} {u} per side, median [2.5%, 97.5%] of {g.draws} draws:",
            f"  synthetic vs real  {g.synthetic}",
            f"  real vs real       {g.floor}   (the floor)",
            f"  ratio              {g.ratio.median:.2f} [{g.ratio.low:.2f}, {g.ratio.high:.2f}]"
            "   (1 = as close to the real set as the real set is to itself)",
        ] + self.size_note()

    def size_note(self) -> list[str]:
        """A warning line when fewer vectors per side were compared than half the real set holds: both distances
        grow as the sets shrink, the floor faster, so the ratio falls toward 1 (the same flame pool measured
        1.80x at 233 crops and 2.51x at 446): ratios compare only at equal ``size``."""
        half = len(self.real.vectors) // 2
        if self.gap.size >= half:
            return []
        return [
            f"  note: {self.gap.size} {self.unit} per side, below the real set's half ({half}); the ratio falls toward 1"
            " as sets shrink: compare ratios at equal --size"
        ]


def dataset_images(path: Path, split: str | None = None, fmt: str = "auto") -> list[Path]:
    """Image paths of the dataset at ``path`` (any format the toolkit reads), of ``split`` when given;
    ``fmt="images"``: every image file under the folder (no labels needed)."""
    from ground.data.formats.registry import read_dataset
    from ground.data.load import pick_split

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


def dataset_boxes(
    path: Path, split: str | None = None, fmt: str = "auto", category: str = "fire"
) -> list[tuple[Path, list[tuple[float, float, float, float]]]]:
    """(image path, its ``category`` boxes [x, y, w, h] in pixels) of every image of the dataset at ``path`` (of
    ``split`` when given) that has such a box; ValueError when there is none (or ``fmt`` is ``images``)."""
    from ground.data.classes import canonical_class
    from ground.data.formats.registry import read_dataset
    from ground.data.load import pick_split

    if fmt == "images":
        raise ValueError(f"{path}: crops need boxes, a plain folder of images has none")
    ds = pick_split(read_dataset(path, fmt).dataset, split, path)
    ids = {c.id for c in ds.categories if c.name == canonical_class(category)}
    by_image = ds.annotations_by_image()
    out = [
        (ds.image_path(im), [tuple(a.bbox) for a in by_image[im.id] if a.category_id in ids and not a.iscrowd])
        for im in ds.images
    ]
    out = [(p, boxes) for p, boxes in out if boxes]
    if not out:
        raise ValueError(f"{path}: no {category!r} boxes")
    return out


def synthetic_boxes(
    folder: Path, items: Sequence[tuple[Path, Sequence[Sequence[float]]]]
) -> tuple[list[tuple[Path, list[tuple[float, float, float, float]]]], int]:
    """``items`` (from :func:`dataset_boxes` of the pool at ``folder``) with only the boxes of flames the pool drew,
    and how many boxes were left out: a pool composited on labelled frames keeps each frame's own fire boxes, which
    have no mask (:mod:`synth.audit`: ``masks/<image stem>.png`` value k marks the k-th fire box; a frame's boxes
    follow the drawn flames'), and are real flames. ``items`` unchanged (0 left out) without ``folder/masks``."""
    masks = folder / "masks"
    if not masks.is_dir():
        return [(p, list(b)) for p, b in items], 0
    out, left = [], 0
    for path, boxes in items:
        mask = cv2.imread(str(masks / f"{Path(path).stem}.png"), cv2.IMREAD_UNCHANGED)
        drawn = set() if mask is None else {int(v) for v in np.unique(mask) if v > 0}
        kept = [tuple(box) for k, box in enumerate(boxes, start=1) if k in drawn]
        left += len(boxes) - len(kept)
        if kept:
            out.append((path, kept))
    return out, left


def crop_box(rgb: NDArray[np.uint8], box: Sequence[float], context: float = CROP_CONTEXT) -> NDArray[np.uint8] | None:
    """The (h, w, 3) part of ``rgb`` inside ``box`` [x, y, w, h] (pixels) grown by ``context`` x its size on each
    side, clipped to the image; None when nothing of it is inside."""
    x, y, w, h = (float(v) for v in box)
    height, width = rgb.shape[:2]
    x0, y0 = max(int(np.floor(x - context * w)), 0), max(int(np.floor(y - context * h)), 0)
    x1, y1 = min(int(np.ceil(x + w + context * w)), width), min(int(np.ceil(y + h + context * h)), height)
    return rgb[y0:y1, x0:x1] if x1 > x0 and y1 > y0 else None


def embed_crops(
    label: str,
    items: Sequence[tuple[Path, Sequence[Sequence[float]]]],
    embedder: OnnxEmbedder,
    context: float = CROP_CONTEXT,
    batch: int = 64,
) -> ImageSet:
    """L2-normalised embeddings (N, D) of every box of ``items`` (from :func:`dataset_boxes`) cut out by
    :func:`crop_box` and resized by ``embedder.preprocess``; unreadable images are kept as problems."""
    from ground.run.progress import progress

    pending: list[NDArray[np.uint8]] = []
    vectors: list[NDArray[np.float32]] = []
    problems: list[Problem] = []
    for path, boxes in progress(items, total=len(items), desc=f"crops of {label}", unit="img"):
        try:
            rgb = read_image(path)
        except ImageError as exc:
            problems.append(Problem(str(path), f"skipped: {exc.reason}"))
            continue
        crops = (crop_box(rgb, box, context) for box in boxes)
        pending += [embedder.preprocess.resize(c) for c in crops if c is not None]
        while len(pending) >= batch:
            vectors.append(embedder.embed(np.stack(pending[:batch])))
            pending = pending[batch:]
    if pending:
        vectors.append(embedder.embed(np.stack(pending)))
    if not vectors:
        raise ValueError(f"{label}: no readable crops")
    return ImageSet(label, l2_normalize(np.concatenate(vectors)), tuple(problems))


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
    draws: int = DRAWS,
    size: int | None = None,
    unit: str = "images",
) -> GapReport:
    """The gap of ``synthetic`` to ``real`` with its floor (see :func:`curate.frechet.gap_interval`); ``unit``
    names what the vectors are (``images`` or ``crops``)."""
    gap = gap_interval(synthetic.vectors, real.vectors, rng, draws, size)
    return GapReport(synthetic, real, gap, model, unit)

"""Dataset statistics: counts per split and class, negatives, box sizes (COCO small/medium/large), boxes by how
many share their image, and a box-size histogram PNG."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from ground.data.dataset import Dataset

#: Buckets of :func:`crowding`: boxes whose image holds 1, 2, 3-4 or 5+ boxes.
CROWDING: tuple[tuple[str, int, int], ...] = (("1", 1, 1), ("2", 2, 2), ("3-4", 3, 4), ("5+", 5, 2**31))

#: COCO's area thresholds (pixels squared) between small / medium / large.
SMALL_AREA = 32.0**2
LARGE_AREA = 96.0**2


def dataset_stats(ds: Dataset, unlabelled: frozenset[int] = frozenset()) -> dict[str, Any]:
    """Counts as a JSON-able dict: images, boxes, negatives, per split, per class, per COCO size bucket.

    ``unlabelled``: ids of images without any label file (:attr:`ReadResult.unlabelled`); negatives are counted
    by origin, ``no_label_file`` (absent) vs ``empty_labels`` (a label file or annotation list without boxes)."""
    names = {c.id: c.name for c in ds.categories}
    areas = np.array([a.area for a in ds.annotations], dtype=np.float64)
    per_split: dict[str, dict[str, int]] = {}
    by_image = ds.annotations_by_image()
    for img in ds.images:
        entry = per_split.setdefault(
            img.split or "(none)", {"images": 0, "boxes": 0, "negatives": 0, "no_label_file": 0, "empty_labels": 0}
        )
        entry["images"] += 1
        entry["boxes"] += len(by_image[img.id])
        negative = not by_image[img.id]
        entry["negatives"] += int(negative)
        entry["no_label_file"] += int(negative and img.id in unlabelled)
        entry["empty_labels"] += int(negative and img.id not in unlabelled)
    return {
        "images": len(ds.images),
        "boxes": len(ds.annotations),
        "negatives": ds.num_negatives(),
        "negatives_by_origin": {
            "no_label_file": sum(e["no_label_file"] for e in per_split.values()),
            "empty_labels": sum(e["empty_labels"] for e in per_split.values()),
        },
        "boxes_per_class": {n: Counter(names[a.category_id] for a in ds.annotations).get(n, 0) for n in names.values()},
        "per_split": per_split,
        "sources": dict(Counter(img.source for img in ds.images)),
        "box_sizes": {
            "small": int((areas < SMALL_AREA).sum()),
            "medium": int(((areas >= SMALL_AREA) & (areas < LARGE_AREA)).sum()),
            "large": int((areas >= LARGE_AREA).sum()),
        },
        "crowd_boxes": sum(a.iscrowd for a in ds.annotations),
        "boxes_by_crowding": crowding(ds),
    }


def crowding(ds: Dataset) -> dict[str, int]:
    """Boxes counted by how many boxes their image holds (:data:`CROWDING` buckets): a fire boxed patch by patch
    (a burning building, window by window) puts many boxes in one image, and detectors merge or miss them."""
    out = dict.fromkeys((name for name, _, _ in CROWDING), 0)
    for boxes in ds.annotations_by_image().values():
        if boxes:
            out[crowding_bucket(len(boxes))] += len(boxes)
    return out


def crowding_bucket(boxes: int) -> str:
    """The :data:`CROWDING` bucket of a box whose image holds ``boxes`` boxes (>= 1)."""
    return next(name for name, lo, hi in CROWDING if lo <= boxes <= hi)


def relative_box_sizes(ds: Dataset) -> dict[str, np.ndarray]:
    """Per class name: (N,) ``sqrt(box area / image area)`` in [0, 1]."""
    sizes = {img.id: float(img.width * img.height) for img in ds.images}
    names = {c.id: c.name for c in ds.categories}
    out: dict[str, list[float]] = {n: [] for n in names.values()}
    for a in ds.annotations:
        out[names[a.category_id]].append(float(np.sqrt(a.area / sizes[a.image_id])))
    return {k: np.asarray(v, dtype=np.float64) for k, v in out.items()}


def plot_box_sizes(ds: Dataset, path: Path, title: str = "") -> Path:
    """Write a PNG: histogram of relative box size per class, COCO small/large limits of a 640 px image."""
    from matplotlib.figure import Figure  # no pyplot: no global backend or figure state

    fig = Figure(figsize=(7, 4), dpi=110)
    ax = fig.add_subplot()
    bins = np.linspace(0.0, 1.0, 41)
    for name, values in relative_box_sizes(ds).items():
        ax.hist(values, bins=bins, alpha=0.6, label=f"{name} ({len(values)})")
    ax.set_xlabel("box size: sqrt(box area / image area)")
    ax.set_ylabel("boxes")
    ax.set_title(title or f"{len(ds.images)} images, {len(ds.annotations)} boxes, {ds.num_negatives()} negatives")
    if ds.annotations:
        ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path

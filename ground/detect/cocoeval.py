"""COCO box metrics: AP, AP50, AP75, small/medium/large, AP25 and per class. The one COCO evaluation of the
toolkit: training-time validation (best-epoch selection) and ``fuzzyfire score`` both call
:func:`evaluate_predictions`. The numbers are pycocotools' ``COCOeval``'s, computed by its vectorised numpy
equal :class:`ground.detect.fast_cocoeval.FastCOCOeval` (a ``COCOeval``; tested against pycocotools).

AP25 is AP at IoU 0.25, beside COCO's numbers: fire and smoke have no crisp edge, and test sets box them
differently (the flames, or the whole burning region), so a detector that finds the fire but draws its box
another way scores near 0 at IoU 0.5 and still well at 0.25.

Every image of the test set counts (negatives included: their detections are false positives); classes are
matched by *name* between the model and the test set; an empty detection list gives AP 0, not an error.
"""

from __future__ import annotations

import contextlib
import io
from collections import defaultdict
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pycocotools.cocoeval import COCOeval

from ground.data.boxes import xyxy_to_xywh
from ground.data.classes import canonical_class
from ground.data.dataset import Dataset
from ground.detect.detections import Predictions
from ground.detect.fast_cocoeval import (
    CocoBoxes,
    FastCOCOeval,
    boxes_to_records,
    detection_boxes,
    ground_truth_boxes,
    records_to_boxes,
)

#: ``COCOeval.stats`` entries we report, by index.
_STATS = {"AP": 0, "AP50": 1, "AP75": 2, "AP_small": 3, "AP_medium": 4, "AP_large": 5}
LOOSE_IOU = 0.25  # the IoU threshold of AP25


class ClassMatchError(ValueError):
    """The model and the test set share no class name."""


@dataclass(frozen=True)
class ClassMatch:
    """How model classes map onto test-set categories (by canonical name).

    ``label_to_cat``: model class index -> test category id; ``evaluated``: names scored, in test-set order;
    ``not_in_model``: test classes the model cannot predict (not scored); ``not_in_test``: model classes
    whose detections are dropped."""

    label_to_cat: dict[int, int]
    evaluated: tuple[str, ...]
    not_in_model: tuple[str, ...]
    not_in_test: tuple[str, ...]


def match_classes(model_names: Sequence[str], dataset: Dataset) -> ClassMatch:
    """Match class names case-insensitively through :func:`ground.data.classes.canonical_class`."""
    test = {canonical_class(c.name): c for c in dataset.categories}
    label_to_cat = {}
    not_in_test = []
    for i, name in enumerate(model_names):
        cat = test.get(canonical_class(name))
        if cat is None:
            not_in_test.append(name)
        else:
            label_to_cat[i] = cat.id
    shared = set(label_to_cat.values())
    if not shared:
        raise ClassMatchError(f"no class in common: model {list(model_names)}, test set {dataset.category_names}")
    evaluated = tuple(c.name for c in dataset.categories if c.id in shared)
    not_in_model = tuple(c.name for c in dataset.categories if c.id not in shared)
    return ClassMatch(label_to_cat, evaluated, not_in_model, tuple(not_in_test))


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """pycocotools prints progress on stdout; keep stdout clean for ``--json``."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


def _detection_arrays(preds: Predictions, match: ClassMatch) -> CocoBoxes:
    """The detections of the matched classes as :func:`detection_records` writes them (xywh rounded to 3
    decimals, scores to 5), image by image in id order."""
    items = sorted((i, d) for i, d in preds.by_image.items() if len(d))
    if not items:
        return detection_boxes(np.zeros(0), np.zeros(0), np.zeros((0, 4)), np.zeros(0))
    lookup = np.full(max(match.label_to_cat, default=0) + 1, -1, dtype=np.int64)
    for label, cat in match.label_to_cat.items():
        lookup[label] = cat
    labels = np.concatenate([d.labels for _, d in items]).astype(np.int64)
    cats = np.where((labels >= 0) & (labels < len(lookup)), lookup[labels.clip(0, len(lookup) - 1)], -1)
    keep = cats >= 0
    image_ids = np.repeat([i for i, _ in items], [len(d) for _, d in items])
    # Rounded image by image, in each image's dtype, as the records have always been written.
    boxes = np.concatenate([np.round(xyxy_to_xywh(d.boxes), 3).reshape(-1, 4) for _, d in items])
    scores = np.concatenate([np.round(d.scores, 5) for _, d in items])
    return detection_boxes(image_ids[keep], cats[keep], boxes[keep], scores[keep])


def detection_records(preds: Predictions, match: ClassMatch) -> list[dict[str, Any]]:
    """COCO result records ``{image_id, category_id, bbox: [x, y, w, h], score}`` of the matched classes."""
    return boxes_to_records(_detection_arrays(preds, match))


def top_records(records: Sequence[dict[str, Any]], max_det: int) -> list[dict[str, Any]]:
    """``records`` without those COCOeval never reads: beyond the ``max_det`` best of their (image, category).

    COCOeval sorts each (image, category)'s detections by score with a stable sort and keeps the first
    ``max_det`` before matching, for every area range; the same stable sort here keeps the same ones, in
    their original order (so ties still resolve the same way)."""
    groups: dict[tuple[int, int], list[int]] = defaultdict(list)
    for i, r in enumerate(records):
        groups[(r["image_id"], r["category_id"])].append(i)
    if all(len(idx) <= max_det for idx in groups.values()):
        return list(records)
    keep: list[int] = []
    for idx in groups.values():
        keep += sorted(idx, key=lambda i: -records[i]["score"])[:max_det] if len(idx) > max_det else idx
    return [records[i] for i in sorted(keep)]


def run_cocoeval(
    dataset: Dataset,
    records: Sequence[dict[str, Any]] | CocoBoxes,
    cat_ids: Sequence[int],
    iou_thresholds: Sequence[float] | None = None,
) -> COCOeval:
    """pycocotools' ``COCOeval`` over every image of ``dataset`` and categories ``cat_ids``, evaluated and
    accumulated (:class:`ground.detect.fast_cocoeval.FastCOCOeval`: the same numbers, vectorised).

    ``records`` are COCO results (or the same as :class:`CocoBoxes`); an empty list is a valid input (AP 0).
    ``iou_thresholds`` (default COCO's 0.5:0.95) limits the work when only some are needed (e.g. ``[0.5]``:
    ``stats[1]`` is AP50, the stats of other thresholds are -1)."""
    dt = records if isinstance(records, CocoBoxes) else records_to_boxes(records)
    ev = FastCOCOeval(ground_truth_boxes(dataset), dt)
    ev.params.imgIds = sorted(img.id for img in dataset.images)
    ev.params.catIds = sorted(cat_ids)
    if iou_thresholds is not None:
        ev.params.iouThrs = np.asarray(iou_thresholds, dtype=np.float64)
    ev.evaluate()
    ev.accumulate()
    with _quiet():
        ev.summarize()
    return ev


def _stat(value: float) -> float | None:
    """A ``COCOeval.stats`` entry, None where pycocotools says -1 (undefined)."""
    return float(value) if value > -1 else None


def _mean_valid(values: np.ndarray) -> float | None:
    valid = values[values > -1]
    return float(valid.mean()) if valid.size else None


@dataclass
class CocoMetrics:
    """Headline numbers (None where undefined, e.g. no ground truth of that size), per class and counts.
    ``negatives``: scored images without a box of a scored class (they can only collect false positives)."""

    summary: dict[str, float | None]
    per_class: dict[str, dict[str, Any]]
    images: int
    boxes: int
    detections: int
    negatives: int = 0
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            **self.summary,
            "images": self.images,
            "boxes": self.boxes,
            "negatives": self.negatives,
            "detections": self.detections,
            "per_class": self.per_class,
            **self.extra,
        }


def metrics_from_eval(ev: COCOeval, dataset: Dataset, detections: int, loose: COCOeval | None = None) -> CocoMetrics:
    """Read AP numbers from an accumulated ``COCOeval`` (area ``all``, 100 detections per image); ``loose``,
    the same evaluation at :data:`LOOSE_IOU` alone, adds AP25 to the summary and to each class."""
    summary = {k: _stat(ev.stats[i]) for k, i in _STATS.items()}
    precision = ev.eval["precision"]  # (T, R, K, A, M)
    names = {c.id: c.name for c in dataset.categories}
    counts: dict[int, int] = {}
    for a in dataset.annotations:
        if not a.iscrowd:
            counts[a.category_id] = counts.get(a.category_id, 0) + 1
    per_class = {}
    for k, cat_id in enumerate(ev.params.catIds):
        per_class[names[cat_id]] = {
            "AP": _mean_valid(precision[:, :, k, 0, -1]),
            "AP50": _mean_valid(precision[0, :, k, 0, -1]),
            "boxes": counts.get(cat_id, 0),
            **({"AP25": _mean_valid(loose.eval["precision"][0, :, k, 0, -1])} if loose is not None else {}),
        }
    if loose is not None:
        summary["AP25"] = _stat(loose.stats[0])
    boxes = sum(counts.get(c, 0) for c in ev.params.catIds)
    scored = set(ev.params.catIds)
    with_boxes = {a.image_id for a in dataset.annotations if a.category_id in scored} | dataset.labelled_ids(scored)
    negatives = sum(1 for i in ev.params.imgIds if i not in with_boxes)
    return CocoMetrics(summary, per_class, len(ev.params.imgIds), boxes, detections, negatives)


def loose_ap(dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int]) -> float | None:
    """AP25 of COCO result ``records`` over every image of ``dataset`` and categories ``cat_ids`` (None when no
    category has ground truth)."""
    return _stat(run_cocoeval(dataset, records, cat_ids, [LOOSE_IOU]).stats[0])


def evaluate_detections(dataset: Dataset, preds: Predictions) -> tuple[CocoMetrics, COCOeval, CocoBoxes]:
    """Score ``preds`` against ``dataset`` over the images that were scored (unreadable ones are left out
    and listed in ``preds.problems``). Returns metrics, the accumulated ``COCOeval`` and the detections of the
    matched classes as evaluated (:func:`ground.detect.fast_cocoeval.boxes_to_records` makes them COCO records)."""
    match = match_classes(preds.class_names, dataset)
    scored = dataset.filter_images(lambda img: img.id in preds.by_image)
    dt = _detection_arrays(preds, match)
    cat_ids = sorted(set(match.label_to_cat.values()))
    ev = run_cocoeval(scored, dt, cat_ids)
    metrics = metrics_from_eval(ev, scored, len(dt), run_cocoeval(scored, dt, cat_ids, [LOOSE_IOU]))
    metrics.extra["classes"] = {
        "evaluated": list(match.evaluated),
        "not_in_model": list(match.not_in_model),
        "not_in_test": list(match.not_in_test),
    }
    return metrics, ev, dt


def evaluate_predictions(dataset: Dataset, preds: Predictions) -> tuple[CocoMetrics, COCOeval, list[dict[str, Any]]]:
    """:func:`evaluate_detections` with the detections as COCO result records."""
    metrics, ev, dt = evaluate_detections(dataset, preds)
    return metrics, ev, boxes_to_records(dt)

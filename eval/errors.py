"""Where a detector's AP50 goes: a TIDE-style error breakdown (Bolya et al., "TIDE: A General Toolbox for
Identifying Object Detection Errors", ECCV 2020), written from the paper's definitions, plus the false alarms on
images without fire that a fire-alarm user asks about first.

Detections are matched to ground truth per (image, class) in descending score order at IoU >= ``T_FG`` (0.5),
each ground-truth box once, as COCO does (crowd boxes absorb the detections they match, which are then no
error). Every unmatched detection gets the first error type it fits, with ``iou_same`` / ``iou_other`` its
best IoU with a ground-truth box of its own / of another class:

- ``duplicate``: iou_same >= T_FG (its box was already taken by a higher-scoring detection);
- ``classification``: iou_other >= T_FG;
- ``localisation``: T_BG <= iou_same < T_FG (T_BG = 0.1);
- ``both``: T_BG <= iou_other < T_FG;
- ``background``: every IoU < T_BG.

A ground-truth box no detection matched and no classification or localisation error points at is ``missed``.
Each type's weight is dAP50 = AP50 with that type fixed - AP50, every type fixed alone, AP50 by pycocotools
(:func:`ground.detect.cocoeval.run_cocoeval`): a classification error takes the class of its box and a localisation
error the box itself (dropped if that box is already detected), duplicates, "both" and background errors are
dropped, missed boxes are removed from the ground truth.
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pycocotools.cocoeval import Params

from ground.data.boxes import box_iou_xyxy, xywh_to_xyxy
from ground.data.dataset import Dataset
from ground.detect.cocoeval import run_cocoeval, top_records

T_FG = 0.5  # foreground IoU: a detection at or above it is on its object
T_BG = 0.1  # background IoU: a detection below it with every box is on nothing
ALARM_CONF = 0.25  # confidence at which a detection would raise an alarm (ultralytics' predict default)
ALARMS = "alarms_per_100"  # result key of the alarm rate of a set without fire: false alarms per 100 images
ERROR_TYPES = ("classification", "localisation", "both", "duplicate", "background", "missed")
ERRORS_FILE = "errors.json"  # where a breakdown is kept beside a scoring's other outputs


@dataclass(frozen=True)
class ErrorBreakdown:
    """AP50 (0..1), each error type's count and dAP50 when fixed (0..1 points of AP50), and false alarms at
    ``alarm_conf`` on the ``negatives`` images without ground truth: detections per 100 such images and the
    share (0..1) of them with at least one. ``boxes``: the ground-truth boxes scored; with none (a set of fire-free
    images) AP50 and its deltas are undefined and ``ap50`` is None."""

    ap50: float | None
    counts: dict[str, int]
    delta_ap50: dict[str, float]
    negatives: int
    alarm_conf: float
    false_alarms_per_100: float | None
    alarm_image_share: float | None
    boxes: int = 0

    def write(self, folder: Path, extra: dict[str, Any] | None = None) -> Path:
        """Write :meth:`to_dict` (and ``extra`` keys) as ``folder/errors.json`` (:data:`ERRORS_FILE`); returns its
        path."""
        path = folder / ERRORS_FILE
        path.write_text(json.dumps({**self.to_dict(), **(extra or {})}, indent=1) + "\n", encoding="utf-8")
        return path

    def to_dict(self) -> dict[str, Any]:
        return {
            "AP50": self.ap50,
            "counts": self.counts,
            "delta_AP50": self.delta_ap50,
            "negatives": self.negatives,
            "alarm_conf": self.alarm_conf,
            "false_alarms_per_100_negatives": self.false_alarms_per_100,
            "negatives_with_alarm": self.alarm_image_share,
            "boxes": self.boxes,
        }


@dataclass(frozen=True)
class ErrorCase:
    """One error to look at: a ``false_alarm`` (a detection on nothing: a background error) or a ``missed``
    ground-truth box. ``bbox`` [x, y, w, h] pixels is the detection's or the missed box's, ``category_id`` its
    class; ``score`` the detection's (a missed box: its best same-class detection's, None when there is none);
    ``iou`` the false alarm's best IoU with any ground-truth box, or the missed box's best IoU with a detection of
    its class, whose box is ``other`` (None when there is none)."""

    kind: str
    image_id: int
    bbox: tuple[float, float, float, float]
    category_id: int
    score: float | None
    iou: float
    other: tuple[float, float, float, float] | None = None


@dataclass
class _Error:
    record: int  # index into the records
    kind: str
    target: int | None  # annotation id of the box it is on (classification, localisation), else None


def error_breakdown(
    dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int], alarm_conf: float = ALARM_CONF
) -> ErrorBreakdown:
    """The breakdown of COCO result ``records`` ({image_id, category_id, bbox xywh px, score}) on ``dataset``
    (its scored images), over the categories ``cat_ids`` (module docstring)."""
    records = top_records(list(records), Params(iouType="bbox").maxDets[-1])
    cats = set(cat_ids)
    errors, matched = _classify(dataset, records, cats)
    missed = _missed(dataset, cats, matched, errors)
    base = _ap50(dataset, records, cat_ids)
    counts = {kind: sum(e.kind == kind for e in errors) for kind in ERROR_TYPES}
    counts["missed"] = len(missed)
    delta = {}
    for kind in ERROR_TYPES:
        if kind == "missed":
            fixed_ds = replace(dataset, annotations=tuple(a for a in dataset.annotations if a.id not in missed))
            fixed_ap = _ap50(fixed_ds, records, cat_ids) if missed else base
        else:
            fixed_ap = (
                _ap50(dataset, _fixed(dataset, records, errors, matched, kind), cat_ids) if counts[kind] else base
            )
        delta[kind] = fixed_ap - base
    negatives, per_100, share = _false_alarms(dataset, records, cats, alarm_conf)
    boxes = sum(a.category_id in cats for a in dataset.annotations)
    return ErrorBreakdown(base if boxes else None, counts, delta, negatives, alarm_conf, per_100, share, boxes)


def worst_errors(
    dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int], count: int
) -> dict[str, list[ErrorCase]]:
    """The ``count`` worst errors of each kind, classified as :func:`error_breakdown` does:
    ``false_alarm`` the background errors by descending score, ``missed`` the missed boxes by descending area."""
    records = top_records(list(records), Params(iouType="bbox").maxDets[-1])
    cats = set(cat_ids)
    errors, matched = _classify(dataset, records, cats)
    alarms = [records[e.record] for e in errors if e.kind == "background"][:count]
    anns = {a.id: a for a in dataset.annotations}
    missed = sorted(_missed(dataset, cats, matched, errors), key=lambda i: (-anns[i].area, i))[:count]
    gts = dataset.annotations_by_image()
    return {
        "false_alarm": [_alarm_case(r, [a for a in gts[r["image_id"]] if a.category_id in cats]) for r in alarms],
        "missed": [_missed_case(anns[i], records) for i in missed],
    }


def _best_iou(box: Sequence[float], others: Sequence[Sequence[float]]) -> tuple[float, int]:
    """(best IoU of xywh ``box`` with the xywh ``others``, its index); (0.0, -1) when there are none."""
    if not others:
        return 0.0, -1
    iou = box_iou_xyxy(xywh_to_xyxy(np.array([box], float)), xywh_to_xyxy(np.array(others, float)))[0]
    k = int(np.argmax(iou))
    return float(iou[k]), k


def _alarm_case(record: dict[str, Any], anns: Sequence[Any]) -> ErrorCase:
    iou, _ = _best_iou(record["bbox"], [a.bbox for a in anns if not a.iscrowd])
    box = tuple(float(v) for v in record["bbox"])
    return ErrorCase("false_alarm", record["image_id"], box, record["category_id"], record["score"], iou)  # type: ignore[arg-type]


def _missed_case(ann: Any, records: Sequence[dict[str, Any]]) -> ErrorCase:
    same = [r for r in records if r["image_id"] == ann.image_id and r["category_id"] == ann.category_id]
    iou, k = _best_iou(ann.bbox, [r["bbox"] for r in same])
    other = tuple(float(v) for v in same[k]["bbox"]) if k >= 0 and iou > 0 else None
    score = same[k]["score"] if other is not None else None
    return ErrorCase("missed", ann.image_id, tuple(ann.bbox), ann.category_id, score, iou, other)  # type: ignore[arg-type]


def _ap50(dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int]) -> float:
    ap = float(run_cocoeval(dataset, records, cat_ids, iou_thresholds=[T_FG]).stats[1])
    return max(ap, 0.0)  # -1 = undefined (no ground truth): nothing to gain


def _classify(dataset: Dataset, records: Sequence[dict[str, Any]], cats: set[int]) -> tuple[list[_Error], set[int]]:
    """Errors of the unmatched detections, in descending score order, and the ids of the matched boxes."""
    gts = defaultdict(list)
    for a in dataset.annotations:
        if a.category_id in cats:
            gts[a.image_id].append(a)
    by_image = defaultdict(list)
    for i, r in enumerate(records):
        by_image[r["image_id"]].append(i)
    errors: list[_Error] = []
    matched: set[int] = set()
    for image_id, idx in by_image.items():
        idx = sorted(idx, key=lambda i: -records[i]["score"])  # stable: ties keep record order, as COCOeval
        anns = gts.get(image_id, [])
        boxes = np.array([a.bbox for a in anns], dtype=np.float64).reshape(-1, 4)
        dets = np.array([records[i]["bbox"] for i in idx], dtype=np.float64).reshape(-1, 4)
        iou = box_iou_xyxy(xywh_to_xyxy(dets), xywh_to_xyxy(boxes)) if len(anns) else np.zeros((len(idx), 0))
        crowd = np.array([a.iscrowd for a in anns], dtype=bool)
        ioa = area_inside(dets, boxes) if crowd.any() else iou
        for row, i in enumerate(idx):
            error = _one(row, records[i]["category_id"], anns, iou, ioa, crowd, matched)
            if error is not None:
                errors.append(_Error(i, *error))
    errors.sort(key=lambda e: -records[e.record]["score"])
    return errors, matched


def _one(
    row: int,
    cat: int,
    anns: Sequence[Any],
    iou: NDArray[np.float64],
    ioa: NDArray[np.float64],
    crowd: NDArray[np.bool_],
    matched: set[int],
) -> tuple[str, int | None] | None:
    """Match detection ``row`` (class ``cat``) to a free box of its class, or name its error; None when it is
    a true positive or lies on a crowd box (both update ``matched`` as needed)."""
    same = np.array([a.category_id == cat for a in anns], dtype=bool)
    free = same & ~crowd & np.array([a.id not in matched for a in anns], dtype=bool)
    if free.any():
        k = int(np.argmax(np.where(free, iou[row], -1.0)))
        if iou[row, k] >= T_FG:
            matched.add(anns[k].id)
            return None
    if (same & crowd).any() and np.where(same & crowd, ioa[row], 0.0).max() >= T_FG:
        return None
    real = ~crowd
    iou_same = np.where(same & real, iou[row], 0.0)
    iou_other = np.where(~same & real, iou[row], 0.0)
    best_same = float(iou_same.max(initial=0.0))
    best_other = float(iou_other.max(initial=0.0))
    if best_same >= T_FG:
        return "duplicate", None
    if best_other >= T_FG:
        return "classification", anns[int(np.argmax(iou_other))].id
    if best_same >= T_BG:
        return "localisation", anns[int(np.argmax(iou_same))].id
    if best_other >= T_BG:
        return "both", None
    return "background", None


def area_inside(dets: NDArray[np.float64], boxes: NDArray[np.float64]) -> NDArray[np.float64]:
    """(D, G) share of each [x, y, w, h] box of ``dets`` that lies inside each of ``boxes``: intersection over the
    first's area (how COCO matches a detection to a crowd box)."""
    x0 = np.maximum(dets[:, None, 0], boxes[None, :, 0])
    y0 = np.maximum(dets[:, None, 1], boxes[None, :, 1])
    x1 = np.minimum(dets[:, None, 0] + dets[:, None, 2], boxes[None, :, 0] + boxes[None, :, 2])
    y1 = np.minimum(dets[:, None, 1] + dets[:, None, 3], boxes[None, :, 1] + boxes[None, :, 3])
    inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
    return inter / np.maximum(dets[:, None, 2] * dets[:, None, 3], 1e-12)


def _missed(dataset: Dataset, cats: set[int], matched: set[int], errors: Sequence[_Error]) -> set[int]:
    """Ids of the boxes nothing found: unmatched, not crowd, and no classification or localisation error on them."""
    targeted = {e.target for e in errors if e.target is not None}
    return {
        a.id
        for a in dataset.annotations
        if a.category_id in cats and not a.iscrowd and a.id not in matched and a.id not in targeted
    }


def _fixed(
    dataset: Dataset, records: Sequence[dict[str, Any]], errors: Sequence[_Error], matched: set[int], kind: str
) -> list[dict[str, Any]]:
    """``records`` with the errors of ``kind`` fixed (module docstring); errors are in descending score order, so
    of two fixes landing on one box the higher-scoring keeps it and the other is dropped."""
    anns = {a.id: a for a in dataset.annotations}
    drop: set[int] = set()
    changed: dict[int, dict[str, Any]] = {}
    taken = set(matched)
    for e in errors:
        if e.kind != kind:
            continue
        if e.target is None or e.target in taken:
            drop.add(e.record)
            continue
        taken.add(e.target)
        gt = anns[e.target]
        if kind == "classification":
            changed[e.record] = {**records[e.record], "category_id": gt.category_id}
        else:
            changed[e.record] = {**records[e.record], "bbox": list(gt.bbox)}
    return [changed.get(i, r) for i, r in enumerate(records) if i not in drop]


def _false_alarms(
    dataset: Dataset, records: Sequence[dict[str, Any]], cats: set[int], conf: float
) -> tuple[int, float | None, float | None]:
    """(negative images, detections >= ``conf`` per 100 of them, share of them with one or more)."""
    with_boxes = {a.image_id for a in dataset.annotations if a.category_id in cats and not a.iscrowd}
    negatives = {img.id for img in dataset.images} - with_boxes - dataset.labelled_ids(cats)
    if not negatives:
        return 0, None, None
    alarms = [r["image_id"] for r in records if r["image_id"] in negatives and r["score"] >= conf]
    return len(negatives), 100.0 * len(alarms) / len(negatives), len(set(alarms)) / len(negatives)

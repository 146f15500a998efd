"""Which ground-truth boxes a detector finds at an operating point, box by box: what a user who acts on
detections above a threshold sees, beside AP's ranking view (:mod:`eval.errors`).

At confidence ``conf`` (default :data:`eval.errors.ALARM_CONF`) each ground-truth box (not crowd, of a scored
class) is judged by the detection of its image and class that overlaps it most:

- ``found``: IoU >= 0.5 (a detection may find two boxes: this is recall per box, not COCO's one-to-one matching);
- ``missed``: no such detection, or IoU < 0.1;
- else boxed poorly, the first that fits: ``merged`` (that detection holds at least half of two or more of the
  image's boxes: neighbouring fires taken as one), ``split`` (two or more detections lie at least half inside the
  box: one fire taken as several), ``too_large``, ``too_small`` (the detection's area against the box's).

And the share found by box size (square root of the area, pixels of the image: :data:`SIZES`) and by how many
boxes share the image (:data:`curate.stats.CROWDING`): fuzzy objects boxed patch by patch crowd one image.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from curate.stats import CROWDING, crowding_bucket
from eval.errors import ALARM_CONF, T_BG, T_FG, area_inside
from ground.data.boxes import box_iou_xyxy, xywh_to_xyxy
from ground.data.dataset import Dataset

#: Box size buckets: (name, smallest, largest) square root of the area in pixels, the largest excluded.
SIZES: tuple[tuple[str, float, float], ...] = (
    ("<16", 0, 16), ("16-32", 16, 32), ("32-64", 32, 64), ("64-128", 64, 128), ("128+", 128, float("inf"))
)  # fmt: skip
OUTCOMES = ("found", "merged", "split", "too_large", "too_small", "missed")
HALF = 0.5  # the share of a box inside another that makes it "inside" (merged, split)


@dataclass(frozen=True)
class BoxesFound:
    """Per-box outcomes at ``conf``: ``outcomes`` counts (:data:`OUTCOMES`) of the ``boxes`` ground-truth boxes;
    ``by_size`` and ``by_crowding``: bucket -> (found, boxes)."""

    conf: float
    boxes: int
    outcomes: dict[str, int]
    by_size: dict[str, tuple[int, int]]
    by_crowding: dict[str, tuple[int, int]]

    def to_dict(self) -> dict[str, Any]:
        def shares(buckets: dict[str, tuple[int, int]]) -> dict[str, dict[str, int]]:
            return {k: {"found": f, "boxes": n} for k, (f, n) in buckets.items()}

        return {"conf": self.conf, "boxes": self.boxes, "outcomes": self.outcomes,
                "by_size": shares(self.by_size), "by_crowding": shares(self.by_crowding)}  # fmt: skip


def boxes_found(
    dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int], conf: float = ALARM_CONF
) -> BoxesFound:
    """The outcome of every ground-truth box of ``dataset`` (its scored images) over classes ``cat_ids``, against
    the COCO result ``records`` ({image_id, category_id, bbox xywh px, score}) at confidence >= ``conf``."""
    cats = set(cat_ids)
    dets: dict[tuple[int, int], list[Sequence[float]]] = {}
    for r in records:
        if r["score"] >= conf and r["category_id"] in cats:
            dets.setdefault((r["image_id"], r["category_id"]), []).append(r["bbox"])
    outcomes = dict.fromkeys(OUTCOMES, 0)
    by_size = {name: [0, 0] for name, _, _ in SIZES}
    by_crowd = {name: [0, 0] for name, _, _ in CROWDING}
    for image_id, anns in dataset.annotations_by_image().items():
        boxes = [a for a in anns if not a.iscrowd and a.category_id in cats]
        for ann in boxes:
            same = [b.bbox for b in boxes if b.category_id == ann.category_id]
            kind = outcome(ann.bbox, same, dets.get((image_id, ann.category_id), []))
            outcomes[kind] += 1
            side = float(np.sqrt(ann.bbox[2] * ann.bbox[3]))
            for table, key in (
                (by_size, bucket(SIZES, side)),
                (by_crowd, crowding_bucket(len(boxes))),
            ):
                table[key][0] += kind == "found"
                table[key][1] += 1
    total = sum(outcomes.values())
    return BoxesFound(conf, total, outcomes, _tuples(by_size), _tuples(by_crowd))


def outcome(box: Sequence[float], image_boxes: Sequence[Sequence[float]], dets: Sequence[Sequence[float]]) -> str:
    """The outcome (:data:`OUTCOMES`, module docstring) of ground-truth ``box`` [x, y, w, h] px, with
    ``image_boxes`` every box of its class in its image (itself included) and ``dets`` its class's detections."""
    if not dets:
        return "missed"
    d, g = np.asarray(dets, np.float64), np.asarray([box], np.float64)
    iou = box_iou_xyxy(xywh_to_xyxy(g), xywh_to_xyxy(d))[0]
    best = int(np.argmax(iou))
    if iou[best] >= T_FG:
        return "found"
    if iou[best] < T_BG:
        return "missed"
    if (area_inside(np.asarray(image_boxes, np.float64), d[best : best + 1]) >= HALF).sum() >= 2:
        return "merged"
    if (area_inside(d, g) >= HALF).sum() >= 2:
        return "split"
    return "too_large" if d[best, 2] * d[best, 3] > box[2] * box[3] else "too_small"


def bucket(buckets: Sequence[tuple[str, float, float]], value: float) -> str:
    """The name of the bucket (name, lo, hi) holding ``value``: lo <= value < hi."""
    return next(name for name, lo, hi in buckets if lo <= value < hi)


def _tuples(table: dict[str, list[int]]) -> dict[str, tuple[int, int]]:
    return {k: (int(v[0]), int(v[1])) for k, v in table.items()}

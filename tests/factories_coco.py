"""pycocotools' own COCOeval on a dataset and detection records (not a test module): the reference the vectorised
evaluation and ``run_cocoeval`` are compared with."""

from __future__ import annotations

import contextlib
import io

import numpy as np
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval


def reference(ds, records, cat_ids, iou_thresholds=None) -> COCOeval:
    """pycocotools' COCOeval on the same inputs, loaded as run_cocoeval loads them (ids 1..N, area w * h)."""
    doc = ds.to_coco()
    gt, dt = COCO(), COCO()
    anns = [{**r, "id": i, "area": r["bbox"][2] * r["bbox"][3], "iscrowd": 0} for i, r in enumerate(records, 1)]
    gt.dataset, dt.dataset = doc, {"images": doc["images"], "categories": doc["categories"], "annotations": anns}
    with contextlib.redirect_stdout(io.StringIO()):
        gt.createIndex()
        dt.createIndex()
        ev = COCOeval(gt, dt, "bbox")
        ev.params.imgIds = sorted(img.id for img in ds.images)
        ev.params.catIds = sorted(cat_ids)
        if iou_thresholds is not None:
            ev.params.iouThrs = np.asarray(iou_thresholds, dtype=np.float64)
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    return ev

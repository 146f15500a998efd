"""Per-epoch validation: detections of the (EMA) model on letterboxed images, COCO AP via pycocotools.

Post-processing mirrors what a scorer does with the exported ONNX model: score = objectness x class
probability for every (box, class) pair above ``conf``, class-aware greedy NMS, at most ``max_det`` boxes
per image, boxes mapped from letterboxed input pixels back to the original image.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from curate import boxes as bx
from curate.dataset import Dataset
from train.data import CachedImage, val_batches

#: Highest-scoring (box, class) pairs passed to NMS per image.
MAX_CANDIDATES = 30000


def postprocess(
    pred: NDArray[np.float32], conf: float, iou: float, max_det: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """One image's decoded output (N, 5 + C) -> ``(boxes (K, 4) xyxy input px, scores (K,), labels (K,))``."""
    scores = pred[:, 4:5] * pred[:, 5:]
    rows, labels = np.nonzero(scores > conf)
    values = scores[rows, labels].astype(np.float64)
    if len(values) > MAX_CANDIDATES:
        top = np.argsort(-values, kind="stable")[:MAX_CANDIDATES]
        rows, labels, values = rows[top], labels[top], values[top]
    xyxy = bx.cxcywh_to_xyxy(pred[rows, :4]).reshape(-1, 4)
    keep = bx.batched_nms_xyxy(xyxy, values, labels, iou, max_keep=max_det)
    return xyxy[keep], values[keep], labels[keep].astype(np.int64)


def coco_detections(
    cache: Sequence[CachedImage], model: torch.nn.Module, imgsz: int, batch: int, conf: float, iou: float, max_det: int
) -> list[dict[str, Any]]:
    """COCO result dicts (``image_id``, ``category_id`` = class index + 1, ``bbox`` xywh original px, ``score``)."""
    results: list[dict[str, Any]] = []
    model.eval()
    with torch.no_grad():
        for records, images in val_batches(list(cache), imgsz, batch):
            preds = model.predict(images).numpy()
            for record, pred in zip(records, preds):
                xyxy, scores, labels = postprocess(pred, conf, iou, max_det)
                xyxy = bx.letterbox_to_image_xyxy(xyxy, record.width, record.height, imgsz, imgsz)
                xywh = bx.xyxy_to_xywh(bx.clip_xyxy(xyxy, record.width, record.height)).reshape(-1, 4)
                for box, score, label in zip(xywh, scores, labels):
                    results.append(
                        {
                            "image_id": record.id,
                            "category_id": int(label) + 1,
                            "bbox": [round(float(v), 3) for v in box],
                            "score": round(float(score), 5),
                        }
                    )
    return results


def coco_ap(ground_truth: Dataset, detections: list[dict[str, Any]]) -> dict[str, float]:
    """``{"AP", "AP50"}`` (COCO AP@[.5:.95] and AP@.5, all classes, area all, 100 detections)."""
    if not detections or not ground_truth.annotations:
        return {"AP": 0.0, "AP50": 0.0}
    with contextlib.redirect_stdout(io.StringIO()):
        gt = COCO()
        gt.dataset = ground_truth.to_coco()
        gt.createIndex()
        dt = gt.loadRes(detections)
        ev = COCOeval(gt, dt, "bbox")
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    return {"AP": max(float(ev.stats[0]), 0.0), "AP50": max(float(ev.stats[1]), 0.0)}


def fitness(metrics: dict[str, float]) -> float:
    """The checkpoint-selection score: 0.1 AP50 + 0.9 AP."""
    return 0.1 * metrics["AP50"] + 0.9 * metrics["AP"]


def evaluate(
    model: torch.nn.Module,
    cache: Sequence[CachedImage],
    ground_truth: Dataset,
    imgsz: int,
    batch: int,
    conf: float,
    iou: float,
    max_det: int,
) -> dict[str, float]:
    """``{"AP", "AP50", "fitness", "detections"}`` of ``model`` on the cached validation images."""
    kept = {c.record.id for c in cache}
    gt = ground_truth.filter_images(lambda img: img.id in kept)
    dets = coco_detections(cache, model, imgsz, batch, conf, iou, max_det)
    metrics = coco_ap(gt, dets)
    return {**metrics, "fitness": fitness(metrics), "detections": float(len(dets))}

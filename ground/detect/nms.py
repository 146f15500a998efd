"""Non-maximum suppression over xyxy pixel boxes: greedy (OpenCV's C++ loop) and class-aware.

Boxes are (N, 4) ``[x_min, y_min, x_max, y_max]`` in pixels (see :mod:`ground.data.boxes`), scores (N,);
every function returns the indices kept, best first, and never modifies its input.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ground.data.boxes import box_iou_xyxy


def nms_xyxy(
    boxes: ArrayLike, scores: ArrayLike, iou_threshold: float, max_keep: int | None = None
) -> NDArray[np.int64]:
    """Greedy NMS over (N, 4) xyxy boxes and (N,) scores: indices kept, best first. A box is dropped when its
    IoU with a kept, higher-scoring box is above ``iou_threshold``; ties keep the lower index first.

    With ``max_keep`` the candidates are visited in blocks of the best ``max(512, 2 * max_keep)``: each block
    is first cleared against the boxes kept so far, then suppressed greedily, and the scan stops once
    ``max_keep`` boxes are kept. The result is the same as one greedy pass over every box; the cost no longer
    grows with the number of candidates that can never be kept (an untrained model's 30,000). OpenCV's loop
    costs candidates x kept IoUs, so a block twice ``max_keep`` wastes least: 2.5 ms per image for a random
    detector's 6,300 candidates and 300 kept, against 6.7 ms with blocks of ``4 * max_keep`` (the same boxes).
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    order = np.argsort(-np.asarray(scores, dtype=np.float64), kind="stable")
    limit = len(order) if max_keep is None else max_keep
    block = len(order) if max_keep is None else max(512, 2 * max_keep)
    keep: list[int] = []
    for start in range(0, len(order), max(block, 1)):
        if len(keep) >= limit:
            break
        cand = order[start : start + block]
        if keep:
            cand = cand[(box_iou_xyxy(b[cand], b[keep]) <= iou_threshold).all(axis=1)]
        keep += _greedy_nms(b, cand, iou_threshold, limit - len(keep))
    return np.asarray(keep, dtype=np.int64)


def _greedy_nms(b: NDArray[np.float64], order: NDArray[np.int64], iou_threshold: float, limit: int) -> list[int]:
    """Greedy NMS of the boxes ``b[order]`` (already best first): at most ``limit`` indices of ``b`` kept.

    Runs OpenCV's C++ greedy NMS (``cv2.dnn.NMSBoxes``, GIL released) with the rank as score, so the visiting
    order is exactly ``order``. OpenCV compares the IoU in float32 and counts two empty boxes as duplicates.
    """
    if order.size == 0 or limit <= 0:
        return []
    cand = b[order]
    xywh = np.concatenate((cand[:, :2], np.clip(cand[:, 2:] - cand[:, :2], 0.0, None)), axis=1)
    ranks = np.arange(len(order), 0, -1, dtype=np.float32)  # distinct and > 0 (the score threshold)
    kept = np.sort(np.asarray(cv2.dnn.NMSBoxes(xywh, ranks, 0.0, float(iou_threshold)), dtype=np.int64).ravel())
    return order[kept[:limit]].tolist()


def batched_nms_xyxy(
    boxes: ArrayLike, scores: ArrayLike, labels: ArrayLike, iou_threshold: float, max_keep: int | None = None
) -> NDArray[np.int64]:
    """Class-aware NMS over (N, 4) xyxy ``boxes``, (N,) ``scores`` and (N,) integer ``labels``: boxes of different
    labels never suppress each other. Indices kept, best first (ties: lower label, then lower index)."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    scores, labels = np.asarray(scores, dtype=np.float64), np.asarray(labels)
    kept = [
        np.flatnonzero(labels == c)[nms_xyxy(boxes[labels == c], scores[labels == c], iou_threshold, max_keep)]
        for c in np.unique(labels)
    ]
    if not kept:
        return np.zeros(0, dtype=np.int64)
    idx = np.concatenate(kept)
    idx = idx[np.argsort(-scores[idx], kind="stable")]
    return idx if max_keep is None else idx[:max_keep]

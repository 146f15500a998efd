"""Detector post-processing shared by training-time validation and scoring: confidence filter, class-aware
NMS (:func:`ground.detect.nms.batched_nms_xyxy`), boxes mapped from letterboxed input pixels back to the image.

``train`` (validation of every epoch) and ``eval`` (``fuzzyfire score``) both turn a detector's raw output
into :class:`Predictions` here and score them with :mod:`ground.detect.cocoeval`, so the AP that picks the best
epoch and the AP that scoring reports are computed by the same code."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ground.data.boxes import clip_xyxy, cxcywh_to_xyxy, letterbox_to_image_xyxy
from ground.data.problems import Problem
from ground.detect.nms import batched_nms_xyxy

#: Highest-scoring candidates passed to NMS per image (bounds the cost of an untrained model's noise).
MAX_CANDIDATES = 30000


@dataclass(frozen=True)
class PostprocessConfig:
    """How a detector's raw output becomes its detections (:func:`postprocess`): training's validation of every
    epoch (``train.postprocess``), ``fuzzyfire score`` and ``compare`` and an experiment's scoring
    (``postprocess`` of their ``inference``), and ``fuzzyfire predict`` (which draws boxes: a higher ``conf``)."""

    conf: float = 0.001  # score threshold before NMS, [0, 1); COCO-style scoring keeps low scores (they only add
    # recall)
    iou: float = 0.6  # NMS IoU threshold, (0, 1]: a box overlapping a better one of its class more is dropped
    max_det: int = 300  # detections kept per image, >= 1

    def __post_init__(self) -> None:
        if not 0.0 <= self.conf < 1.0:
            raise ValueError(f"postprocess.conf must be in [0, 1), got {self.conf}")
        if not 0.0 < self.iou <= 1.0:
            raise ValueError(f"postprocess.iou must be in (0, 1], got {self.iou}")
        if self.max_det < 1:
            raise ValueError(f"postprocess.max_det must be >= 1, got {self.max_det}")


@dataclass(frozen=True)
class ImageDetections:
    """Detections of one image: ``boxes`` (K, 4) xyxy pixels, ``scores`` (K,), ``labels`` (K,) class index
    into the model's class names; sorted by descending score."""

    boxes: NDArray[np.float64]
    scores: NDArray[np.float64]
    labels: NDArray[np.int64]

    def __len__(self) -> int:
        return len(self.scores)


@dataclass
class Predictions:
    """Detections per image id (xyxy in original pixels, labels index the model's ``class_names``) and the
    images that could not be scored."""

    class_names: tuple[str, ...]
    by_image: dict[int, ImageDetections]
    problems: list[Problem] = field(default_factory=list)


def postprocess(
    boxes_cxcywh: NDArray,
    scores: NDArray,
    settings: PostprocessConfig | None = None,
    multi_label: bool = True,
) -> ImageDetections:
    """One image's raw head output -> its detections in input pixels, with the thresholds of ``settings``
    (default: :class:`PostprocessConfig`'s).

    ``boxes_cxcywh`` (N, 4) centre boxes, ``scores`` (N, C). ``multi_label`` keeps every (box, class) pair
    above the confidence threshold (COCO-style evaluation), otherwise only each box's best class.
    """
    post = settings or PostprocessConfig()
    if multi_label:
        rows, labels = np.nonzero(scores > post.conf)
    else:
        labels = np.argmax(scores, axis=1) if scores.size else np.zeros(0, dtype=np.int64)
        rows = np.flatnonzero(scores[np.arange(len(labels)), labels] > post.conf) if scores.size else labels
        labels = labels[rows]
    picked = scores[rows, labels].astype(np.float64)
    if len(picked) > MAX_CANDIDATES:
        top = np.argsort(-picked, kind="stable")[:MAX_CANDIDATES]
        rows, labels, picked = rows[top], labels[top], picked[top]
    xyxy = cxcywh_to_xyxy(boxes_cxcywh[rows]) if len(rows) else np.zeros((0, 4))
    keep = batched_nms_xyxy(xyxy, picked, labels, post.iou, post.max_det)
    return ImageDetections(xyxy[keep], picked[keep], labels[keep].astype(np.int64))


def to_original(det: ImageDetections, size: tuple[int, int], input_size: tuple[int, int]) -> ImageDetections:
    """Boxes of ``det`` from letterboxed input pixels (``input_size`` = (W, H)) to the original image of
    ``size`` = (width, height) pixels, clipped to it."""
    width, height = size
    boxes = letterbox_to_image_xyxy(det.boxes, width, height, *input_size) if len(det) else det.boxes
    return ImageDetections(clip_xyxy(boxes, width, height), det.scores, det.labels)

"""Per-epoch validation: detections of the (EMA) model on the letterboxed validation images, scored with
the toolkit's one post-processing (:mod:`ground.detect.detections`) and one COCO evaluation (:mod:`ground.detect.cocoeval`),
the very code ``fuzzyfire score`` runs on the exported ONNX model. So the best epoch's AP is the AP that
scoring its ``best.onnx`` on the same images reports (up to ONNX float differences).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

from ground.data.dataset import Dataset
from ground.detect.cocoeval import evaluate_predictions
from ground.detect.detections import PostprocessConfig, Predictions, postprocess, to_original
from train.features import ValidationInputs


def predictions(
    model: torch.nn.Module,
    inputs: ValidationInputs,
    class_names: Sequence[str],
    imgsz: int,
    settings: PostprocessConfig,
) -> Predictions:
    """Detections of ``model`` (a :class:`train.model.Detector`) on every validation image, boxes in original
    pixels; scores ``obj * p_c`` as in the exported model."""
    by_image = {}
    model.eval()
    with torch.no_grad():
        for records, feats in inputs:
            feats = tuple(f.contiguous(memory_format=torch.channels_last) for f in feats)
            decoded = model.predict_frozen(feats).float().cpu().numpy()
            for record, pred in zip(records, decoded):
                det = postprocess(pred[:, :4], pred[:, 4:5] * pred[:, 5:], settings)
                by_image[record.id] = to_original(det, (record.width, record.height), (imgsz, imgsz))
    return Predictions(tuple(class_names), by_image)


def fitness(metrics: dict[str, float]) -> float:
    """The checkpoint-selection score: 0.1 AP50 + 0.9 AP."""
    return 0.1 * metrics["AP50"] + 0.9 * metrics["AP"]


def evaluate(
    model: torch.nn.Module,
    inputs: ValidationInputs,
    ground_truth: Dataset,
    class_names: Sequence[str],
    imgsz: int,
    settings: PostprocessConfig,
) -> dict[str, float]:
    """``{"AP", "AP50", "fitness", "detections"}`` of ``model`` on the validation images (AP 0 where COCO
    leaves it undefined, e.g. a validation set without boxes)."""
    preds = predictions(model, inputs, class_names, imgsz, settings)
    metrics, _, records = evaluate_predictions(ground_truth, preds)
    values = {k: float(np.nan_to_num(metrics.summary[k] or 0.0)) for k in ("AP", "AP50")}
    return {**values, "fitness": fitness(values), "detections": float(len(records))}

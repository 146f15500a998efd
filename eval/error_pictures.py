"""Pictures of a detector's worst errors (``fuzzyfire score --errors --out DIR``): the highest-scoring false
alarms and the largest missed boxes (:func:`eval.errors.worst_errors`), each on its whole image with the
ground-truth boxes in green and the detection in red, labelled with class, score and IoU.

Written as ``DIR/errors/false_alarm_NN_<image stem>.png`` and ``missed_NN_<image stem>.png`` (NN = rank from 01)
plus ``DIR/errors/index.json`` (the cases: picture, image file, kind, boxes [x, y, w, h] in pixels of the original
image, score, IoU). Small images are enlarged by a whole factor (their longer side to at least
:data:`MIN_SIDE` pixels, nearest neighbour) so labels stay readable; boxes are scaled with them.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from eval.draw import GROUND_TRUTH, PREDICTION, draw_labelled
from eval.errors import ErrorCase, worst_errors
from eval.predict_media import write_image
from ground.data.boxes import xywh_to_xyxy
from ground.data.dataset import Dataset
from ground.data.problems import Problem
from ground.image.imageio import ImageError, read_image

FOLDER = "errors"
MIN_SIDE = 640  # pixels: smaller images are enlarged by a whole factor to at least this longer side
WORST = 12  # cases shown per kind


def enlargement(width: int, height: int, min_side: int = MIN_SIDE) -> int:
    """The whole factor (>= 1) that brings the longer side of a ``width`` x ``height`` image to ``min_side``."""
    return max(1, math.ceil(min_side / max(width, height, 1)))


def _score(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def case_boxes(case: ErrorCase, dataset: Dataset, names: dict[int, str]) -> tuple[list, list[str], list]:
    """(xywh boxes, labels, RGB colours) drawn for ``case``: every ground-truth box of its image (green, the
    missed one labelled ``missed``), then the false alarm or the missed box's best same-class detection (red)."""
    name = names.get(case.category_id, str(case.category_id))
    boxes, labels, colours = [], [], []
    for ann in dataset.annotations_by_image()[case.image_id]:
        is_case = case.kind == "missed" and tuple(ann.bbox) == case.bbox and ann.category_id == case.category_id
        boxes.append(ann.bbox)
        labels.append(f"missed {name}" if is_case else f"truth {names.get(ann.category_id, '?')}")
        colours.append(GROUND_TRUTH)
    detection = case.bbox if case.kind == "false_alarm" else case.other
    if detection is not None:
        boxes.append(detection)
        labels.append(f"{name} {_score(case.score)} IoU {case.iou:.2f}")
        colours.append(PREDICTION)
    return boxes, labels, colours


def case_picture(case: ErrorCase, dataset: Dataset, names: dict[int, str]) -> NDArray[np.uint8]:
    """(k H, k W, 3) uint8 RGB: the case's image enlarged by :func:`enlargement` with :func:`case_boxes` drawn;
    raises :class:`ground.image.imageio.ImageError` when the image cannot be read."""
    img = next(i for i in dataset.images if i.id == case.image_id)
    pixels = read_image(dataset.image_path(img))
    k = enlargement(pixels.shape[1], pixels.shape[0])
    if k > 1:
        pixels = cv2.resize(pixels, None, fx=k, fy=k, interpolation=cv2.INTER_NEAREST)
    boxes, labels, colours = case_boxes(case, dataset, names)
    xyxy = xywh_to_xyxy(np.array(boxes, float).reshape(-1, 4)) * k
    return draw_labelled(pixels, xyxy, labels, colours)


def _entry(case: ErrorCase, picture: Path, file_name: str, names: dict[int, str]) -> dict[str, Any]:
    return {
        "picture": picture.name,
        "file_name": file_name,
        "kind": case.kind,
        "category": names.get(case.category_id, str(case.category_id)),
        "bbox": [round(v, 3) for v in case.bbox],
        "score": case.score,
        "iou": round(case.iou, 4),
        "detection_bbox": [round(v, 3) for v in case.other] if case.other else None,
    }


def write_error_pictures(
    dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int], out: Path, count: int = WORST
) -> tuple[Path, list[Problem]]:
    """Write the pictures of the ``count`` worst false alarms and missed boxes of COCO result ``records`` on
    ``dataset`` (its scored images) into ``out/errors/`` with ``index.json`` (module docstring); returns the
    folder and the images that could not be read."""
    folder = out / FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    names = {c.id: c.name for c in dataset.categories}
    files = {img.id: img.file_name for img in dataset.images}
    index, problems = [], []
    for kind, cases in worst_errors(dataset, records, cat_ids, count).items():
        for rank, case in enumerate(cases, 1):
            path = folder / f"{kind}_{rank:02d}_{Path(files[case.image_id]).stem}.png"
            try:
                write_image(path, case_picture(case, dataset, names))
            except ImageError as exc:
                problems.append(Problem(exc.path, f"no error picture: {exc.reason}"))
                continue
            index.append(_entry(case, path, files[case.image_id], names))
    (folder / "index.json").write_text(json.dumps(index, indent=1) + "\n", encoding="utf-8")
    return folder, problems

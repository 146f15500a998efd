"""Boxes drawn on pictures: detections with their class and score (``fuzzyfire predict``), ground truth beside
predictions (``score --errors --out``), boxes on report samples.

Every function takes an (H, W, 3) uint8 RGB image and returns a new one (the input is never modified); boxes are
in pixels of that image. A box is outlined on its own pixels: ``xyxy`` ``[x0, y0, x1, y1]`` (x1, y1 exclusive,
rounded to whole pixels) outlines columns x0..x1-1 and rows y0..y1-1, inwards from that edge by the line width; a
label sits on a filled strip just above the box (inside its top edge when there is no room above).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ground.data.boxes import xywh_to_xyxy

RGB = tuple[int, int, int]

#: Colour per model class index (RGB), repeated past its end: fire orange-red, smoke blue, then others.
CLASS_COLOURS: tuple[RGB, ...] = ((255, 64, 0), (40, 140, 255), (255, 210, 0), (200, 60, 220), (0, 200, 120))
PREDICTION: RGB = (255, 40, 40)  # a detection where ground truth is drawn beside it
GROUND_TRUTH: RGB = (40, 220, 60)
FONT = cv2.FONT_HERSHEY_SIMPLEX


def class_colour(index: int) -> RGB:
    """The RGB colour of model class ``index`` (:data:`CLASS_COLOURS`)."""
    return CLASS_COLOURS[index % len(CLASS_COLOURS)]


def line_width(shape: Sequence[int]) -> int:
    """Box outline width in pixels for an image of ``shape`` (H, W, ...): 1 px per 300 px of its longer side."""
    return max(1, round(max(shape[0], shape[1]) / 300))


def font_scale(shape: Sequence[int]) -> float:
    """OpenCV font scale of labels on an image of ``shape`` (H, W, ...): 0.35 up to 500 px, growing after."""
    return max(0.35, max(shape[0], shape[1]) / 1400)


def _outline(image: NDArray[np.uint8], box: ArrayLike, colour: RGB, width: int) -> tuple[int, int, int, int]:
    """Outline xyxy ``box`` inwards by ``width`` pixels, in place; returns its integer (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = (int(round(float(v))) for v in np.asarray(box, float).reshape(4))
    x1, y1 = max(x1, x0 + 1), max(y1, y0 + 1)
    for k in range(width):  # nested 1-px rectangles: the outline never leaves the box
        if x0 + k <= x1 - 1 - k and y0 + k <= y1 - 1 - k:
            cv2.rectangle(image, (x0 + k, y0 + k), (x1 - 1 - k, y1 - 1 - k), colour, 1)
    return x0, y0, x1, y1


def _label(image: NDArray[np.uint8], text: str, x0: int, y0: int, colour: RGB) -> None:
    """``text`` in white-or-black on a ``colour`` strip whose bottom-left is (x0, y0), or below y0 when the strip
    would leave the image at the top; in place."""
    scale = font_scale(image.shape)
    (tw, th), base = cv2.getTextSize(text, FONT, scale, 1)
    h = th + base + 2
    top = y0 - h if y0 - h >= 0 else y0
    x0 = min(max(x0, 0), max(image.shape[1] - tw - 2, 0))
    cv2.rectangle(image, (x0, top), (x0 + tw + 1, top + h - 1), colour, -1)
    ink = (0, 0, 0) if sum(colour) > 450 else (255, 255, 255)
    cv2.putText(image, text, (x0 + 1, top + th + 1), FONT, scale, ink, 1, cv2.LINE_AA)


def draw_labelled(
    image: NDArray[np.uint8],
    boxes_xyxy: ArrayLike,
    labels: Sequence[str],
    colours: Sequence[RGB],
    width: int | None = None,
) -> NDArray[np.uint8]:
    """A copy of ``image`` with each xyxy box outlined in its colour and labelled (an empty label draws none).
    ``width`` defaults to :func:`line_width`."""
    out = image.copy()
    boxes = np.asarray(boxes_xyxy, float).reshape(-1, 4)
    width = width or line_width(image.shape)
    drawn = [_outline(out, box, colour, width) for box, colour in zip(boxes, colours)]
    for (x0, y0, _, _), text, colour in zip(drawn, labels, colours):  # labels last: boxes never cover them
        if text:
            _label(out, text, x0, y0, colour)
    return out


def draw_detections(
    image: NDArray[np.uint8],
    boxes_xyxy: ArrayLike,
    scores: Sequence[float],
    labels: Sequence[int],
    class_names: Sequence[str],
) -> NDArray[np.uint8]:
    """A copy of ``image`` with detections (xyxy boxes, scores in [0, 1], class indices into ``class_names``)
    drawn in their class colour and labelled ``"<class> <score>"``."""
    texts = [f"{class_names[int(k)]} {float(s):.2f}" for s, k in zip(scores, labels)]
    return draw_labelled(image, boxes_xyxy, texts, [class_colour(int(k)) for k in labels])


def draw_boxes(image: NDArray[np.uint8], boxes_xywh: ArrayLike, colour: RGB = CLASS_COLOURS[0]) -> NDArray[np.uint8]:
    """A copy of ``image`` with xywh pixel boxes outlined in ``colour``, unlabelled."""
    boxes = xywh_to_xyxy(np.asarray(boxes_xywh, float).reshape(-1, 4))
    return draw_labelled(image, boxes, [""] * len(boxes), [colour] * len(boxes))

"""Letterbox an image for inference: one aspect-preserving resize, centred on a grey canvas.

The geometry and the mapping of boxes back to original pixels live in :mod:`ground.data.boxes`
(:func:`~ground.data.boxes.letterbox_params`, :func:`~ground.data.boxes.letterbox_to_image_xyxy`).
"""

from __future__ import annotations

from typing import Literal, get_args

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.data.boxes import letterbox_params

#: Padding grey of YOLO-family detectors (114 of 255).
PAD_VALUE = 114
#: How the image is resized: ``area`` = area averaging when shrinking, bilinear when enlarging (ours and
#: YOLOv5's); ``linear`` = always bilinear (ultralytics 8.x).
ResizeMode = Literal["area", "linear"]
RESIZE_MODES: tuple[str, ...] = get_args(ResizeMode)


def letterbox_image(
    image: NDArray[np.uint8], out_width: int, out_height: int, pad_value: int = PAD_VALUE, resize: str = "area"
) -> NDArray[np.uint8]:
    """(H, W, 3) uint8 -> (out_height, out_width, 3) uint8: resized (see :data:`RESIZE_MODES`) and centred on a
    ``pad_value`` canvas. Channel order is kept."""
    if resize not in RESIZE_MODES:
        raise ValueError(f"unknown resize {resize!r}; choose one of {', '.join(RESIZE_MODES)}")
    height, width = image.shape[:2]
    new_w, new_h, pad_x, pad_y = letterbox_params(width, height, out_width, out_height)
    if (new_w, new_h) != (width, height):
        area = resize == "area" and new_w < width and new_h < height
        image = cv2.resize(image, (new_w, new_h), interpolation=cv2.INTER_AREA if area else cv2.INTER_LINEAR)
    canvas = np.full((out_height, out_width, 3), pad_value, dtype=np.uint8)
    canvas[pad_y : pad_y + new_h, pad_x : pad_x + new_w] = image
    return canvas


def to_nchw_float(images: list[NDArray[np.uint8]]) -> NDArray[np.float32]:
    """A list of (H, W, 3) uint8 RGB images of one size -> (N, 3, H, W) float32 in [0, 1]."""
    batch = np.empty((len(images), 3, *images[0].shape[:2]), np.float32)
    for image, slot in zip(images, batch):
        to_chw_float(image, slot)
    return batch


def to_chw_float(image: NDArray[np.uint8], out: NDArray[np.float32]) -> NDArray[np.float32]:
    """One (H, W, 3) uint8 RGB image -> ``out`` (3, H, W) float32 in [0, 1] (pixel x float32(1 / 255)), in one
    pass: a decoding thread fills its slot of a batch."""
    return np.multiply(image.transpose(2, 0, 1), np.float32(1.0 / 255.0), out=out)

"""Pure box math. Every function takes and returns new float64 arrays and never modifies its input.

Formats, always named in the function name:
- ``xywh``: COCO, ``[x_min, y_min, width, height]`` in pixels.
- ``xyxy``: ``[x_min, y_min, x_max, y_max]`` in pixels (x_max exclusive edge, as COCO's ``x + w``).
- ``cxcywhn``: YOLO, ``[cx, cy, w, h]`` normalised by image width/height to [0, 1].
- ``voc``: Pascal VOC, ``[xmin, ymin, xmax, ymax]`` 1-based inclusive pixel indices.

Arrays are shaped (N, 4); a single box (4,) is accepted and returned as (4,).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

Boxes = NDArray[np.float64]


def _as_boxes(boxes: ArrayLike) -> Boxes:
    arr = np.array(boxes, dtype=np.float64, copy=True)
    if arr.shape[-1:] != (4,) or arr.ndim not in (1, 2):
        raise ValueError(f"boxes must be shaped (4,) or (N, 4), got {arr.shape}")
    return arr


def xywh_to_xyxy(boxes: ArrayLike) -> Boxes:
    """(N, 4) xywh pixels -> (N, 4) xyxy pixels."""
    b = _as_boxes(boxes)
    b[..., 2:] += b[..., :2]
    return b


def xyxy_to_xywh(boxes: ArrayLike) -> Boxes:
    """(N, 4) xyxy pixels -> (N, 4) xywh pixels."""
    b = _as_boxes(boxes)
    b[..., 2:] -= b[..., :2]
    return b


def cxcywhn_to_xywh(boxes: ArrayLike, width: float, height: float) -> Boxes:
    """(N, 4) YOLO normalised centre boxes -> (N, 4) xywh pixels of a ``width`` x ``height`` image."""
    b = _as_boxes(boxes)
    scale = np.array([width, height, width, height], dtype=np.float64)
    b = b * scale
    b[..., :2] -= b[..., 2:] / 2.0
    return b


def xywh_to_cxcywhn(boxes: ArrayLike, width: float, height: float) -> Boxes:
    """(N, 4) xywh pixels -> (N, 4) YOLO normalised centre boxes of a ``width`` x ``height`` image."""
    b = _as_boxes(boxes)
    b[..., :2] += b[..., 2:] / 2.0
    return b / np.array([width, height, width, height], dtype=np.float64)


def voc_to_xywh(boxes: ArrayLike) -> Boxes:
    """(N, 4) VOC 1-based inclusive ``[xmin, ymin, xmax, ymax]`` -> (N, 4) xywh pixels.

    VOC pixel ``i`` (1-based) covers the continuous interval ``[i - 1, i)``, so a box from pixel 1 to 10
    is ``x = 0, w = 10``.
    """
    b = _as_boxes(boxes)
    out = b.copy()
    out[..., :2] = b[..., :2] - 1.0
    out[..., 2:] = b[..., 2:] - b[..., :2] + 1.0
    return out


def clip_xyxy(boxes: ArrayLike, width: float, height: float) -> Boxes:
    """(N, 4) xyxy pixels clipped to the image ``[0, width] x [0, height]``."""
    b = _as_boxes(boxes)
    b[..., 0::2] = np.clip(b[..., 0::2], 0.0, width)
    b[..., 1::2] = np.clip(b[..., 1::2], 0.0, height)
    return b


def clip_xywh(boxes: ArrayLike, width: float, height: float) -> Boxes:
    """(N, 4) xywh pixels clipped to the image; boxes fully outside get zero width or height."""
    return xyxy_to_xywh(clip_xyxy(xywh_to_xyxy(boxes), width, height))


def inside_xywh(boxes: ArrayLike, width: float, height: float, tol: float = 1e-6) -> NDArray[np.bool_]:
    """(N, 4) xywh -> (N,) True where the box lies within the image, up to ``tol`` pixels."""
    b = xywh_to_xyxy(boxes)
    return (b[..., 0] >= -tol) & (b[..., 1] >= -tol) & (b[..., 2] <= width + tol) & (b[..., 3] <= height + tol)


def xywh_overlaps_any(box: ArrayLike, others: ArrayLike) -> bool:
    """Whether the [x, y, w, h] ``box`` intersects (positive area) any of the (N, 4) xywh ``others``."""
    x, y, w, h = (float(v) for v in box)
    o = np.asarray(others, dtype=np.float64).reshape(-1, 4)
    hit = (x < o[:, 0] + o[:, 2]) & (o[:, 0] < x + w) & (y < o[:, 1] + o[:, 3]) & (o[:, 1] < y + h)
    return bool(hit.any())


def box_iou_xyxy(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """IoU matrix (N, M) between (N, 4) and (M, 4) xyxy boxes; 0 where the union is empty."""
    a2 = np.atleast_2d(_as_boxes(a))
    b2 = np.atleast_2d(_as_boxes(b))
    lt = np.maximum(a2[:, None, :2], b2[None, :, :2])
    rb = np.minimum(a2[:, None, 2:], b2[None, :, 2:])
    inter = np.prod(np.clip(rb - lt, 0.0, None), axis=-1)
    area_a = np.prod(np.clip(a2[:, 2:] - a2[:, :2], 0.0, None), axis=-1)
    area_b = np.prod(np.clip(b2[:, 2:] - b2[:, :2], 0.0, None), axis=-1)
    union = area_a[:, None] + area_b[None, :] - inter
    return np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


def cxcywh_to_xyxy(boxes: ArrayLike) -> Boxes:
    """(N, 4) centre boxes ``[cx, cy, w, h]`` in pixels -> (N, 4) xyxy pixels (detector heads emit these)."""
    b = _as_boxes(boxes)
    out = b.copy()
    out[..., :2] = b[..., :2] - b[..., 2:] / 2.0
    out[..., 2:] = b[..., :2] + b[..., 2:] / 2.0
    return out


def letterbox_params(width: int, height: int, out_width: int, out_height: int) -> tuple[int, int, int, int]:
    """``(new_width, new_height, pad_left, pad_top)`` fitting a ``width`` x ``height`` image into
    ``out_width`` x ``out_height`` at one aspect-preserving scale, centred, padding split evenly (left/top
    get the smaller half). Per-axis scales are ``new_width / width`` and ``new_height / height``."""
    if min(width, height, out_width, out_height) <= 0:
        raise ValueError(f"letterbox sizes must be positive, got {width}x{height} -> {out_width}x{out_height}")
    scale = min(out_width / width, out_height / height)
    new_w = min(out_width, max(1, int(round(width * scale))))
    new_h = min(out_height, max(1, int(round(height * scale))))
    return new_w, new_h, (out_width - new_w) // 2, (out_height - new_h) // 2


def image_to_letterbox_xyxy(boxes: ArrayLike, width: int, height: int, out_width: int, out_height: int) -> Boxes:
    """(N, 4) xyxy pixels of a ``width`` x ``height`` image -> xyxy pixels of its letterboxed
    ``out_width`` x ``out_height`` version (see :func:`letterbox_params`)."""
    new_w, new_h, pad_x, pad_y = letterbox_params(width, height, out_width, out_height)
    b = _as_boxes(boxes)
    scale = np.array([new_w / width, new_h / height] * 2)
    return b * scale + np.array([pad_x, pad_y, pad_x, pad_y], dtype=np.float64)


def letterbox_to_image_xyxy(boxes: ArrayLike, width: int, height: int, out_width: int, out_height: int) -> Boxes:
    """(N, 4) xyxy pixels of a letterboxed ``out_width`` x ``out_height`` input -> xyxy pixels of the original
    ``width`` x ``height`` image (inverse of :func:`image_to_letterbox_xyxy`; not clipped)."""
    new_w, new_h, pad_x, pad_y = letterbox_params(width, height, out_width, out_height)
    b = _as_boxes(boxes) - np.array([pad_x, pad_y, pad_x, pad_y], dtype=np.float64)
    return b / np.array([new_w / width, new_h / height] * 2)


def mask_to_xywh(mask: ArrayLike) -> Boxes:
    """(H, W) mask (non-zero = inside) -> (4,) xywh pixel box tightly enclosing it; pixel ``(row, col)`` covers
    ``[col, col + 1) x [row, row + 1)``. An empty mask gives ``[0, 0, 0, 0]``."""
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"mask must be 2-D (H, W), got shape {m.shape}")
    rows = np.flatnonzero(m.any(axis=1))
    cols = np.flatnonzero(m.any(axis=0))
    if rows.size == 0:
        return np.zeros(4, dtype=np.float64)
    return np.array([cols[0], rows[0], cols[-1] + 1 - cols[0], rows[-1] + 1 - rows[0]], dtype=np.float64)


def affine_xyxy(boxes: ArrayLike, matrix: ArrayLike) -> Boxes:
    """(N, 4) xyxy pixels -> (N, 4) xyxy pixels: the box enclosing the four corners moved by ``matrix``,
    a 2x3 or 3x3 affine map of pixel coordinates (the same matrix ``cv2.warpAffine`` applies to pixels)."""
    b = np.atleast_2d(_as_boxes(boxes))
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape not in ((2, 3), (3, 3)):
        raise ValueError(f"matrix must be 2x3 or 3x3, got {m.shape}")
    corners = b[:, [0, 1, 2, 1, 2, 3, 0, 3]].reshape(-1, 4, 2)  # (N, 4 corners, xy)
    moved = corners @ m[:2, :2].T + m[:2, 2]
    return np.concatenate((moved.min(axis=1), moved.max(axis=1)), axis=1)


def points_to_xyxy(points: ArrayLike) -> Boxes:
    """(N, 2) points (x, y) in pixels, N >= 1 -> (4,) xyxy box enclosing them (e.g. a plane's projected corners)."""
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) == 0:
        raise ValueError(f"points must be (N, 2) with N >= 1, got shape {p.shape}")
    return np.concatenate((p.min(axis=0), p.max(axis=0)))


def xyxy_to_cxcywh(boxes: ArrayLike) -> Boxes:
    """(N, 4) xyxy pixels -> (N, 4) centre boxes ``[cx, cy, w, h]`` in pixels (inverse of :func:`cxcywh_to_xyxy`)."""
    b = _as_boxes(boxes)
    out = b.copy()
    out[..., :2] = (b[..., :2] + b[..., 2:]) / 2.0
    out[..., 2:] = b[..., 2:] - b[..., :2]
    return out

"""Annotation audit: written boxes against the boxes of the pixel-truth flame masks kept beside the images.

For an image ``images/<name>.<ext>`` the mask is ``masks/<name>.png``: value k marks the k-th fire box of that
image (annotations in id order). ``masks/box_modes.json`` (Method 1) may hold alternative box sets per image,
audited too: ``{file_name: {mode: [xywh | null, ...]}}``, entry k against instance k + 1 (no mask: IoU 0;
``null``: the mode gives no box for that flame, skipped). Smoke boxes (category ``smoke``) are audited against
``masks/<name>.smoke.png`` the same way.

Visibility (Method 2): each fire box's contrast against the flame-free plate (median ΔE*ab over its flame, see
:mod:`synth.compose.visibility`) as recorded in ``manifest.json``, and how many flames were erased as unseen.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ground.data.boxes import box_iou_xyxy, mask_to_xywh, xywh_to_xyxy


def _summary(ious: list[float], images: int) -> dict[str, Any]:
    return {
        "images": images,
        "boxes": len(ious),
        "mean_iou": float(np.mean(ious)) if ious else 1.0,
        "min_iou": float(np.min(ious)) if ious else 1.0,
    }


def _iou(box: list[float], truth: np.ndarray) -> float:
    return float(box_iou_xyxy(xywh_to_xyxy(box), xywh_to_xyxy(truth))[0, 0])


def _truths(path: Path) -> list[np.ndarray]:
    labels = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if labels is None:
        raise FileNotFoundError(f"{path}: pixel-truth mask missing")
    return [mask_to_xywh(labels == k) for k in range(1, int(labels.max()) + 1)]


def _boxes_by_image(coco: dict, name: str) -> dict[int, list] | None:
    cat = next((c["id"] for c in coco["categories"] if c["name"] == name), None)
    if cat is None:
        return None
    boxes: dict[int, list] = {img["id"]: [] for img in coco["images"]}
    for a in sorted(coco["annotations"], key=lambda a: a["id"]):
        if a["category_id"] == cat:
            boxes[a["image_id"]].append(a["bbox"])
    return boxes


def _ious(boxes: list, truths: list[np.ndarray]) -> list[float]:
    """IoU of box k with truth k (0 when instance k has no mask); ``None`` boxes are skipped."""
    return [_iou(b, truths[k]) if k < len(truths) else 0.0 for k, b in enumerate(boxes) if b is not None]


def visibility_summary(folder: Path) -> dict[str, Any] | None:
    """``{"boxes", "min_contrast", "median_contrast", "erased"}`` from the per-image records of
    ``manifest.json`` (fire boxes with a recorded contrast, ΔE*ab; flames erased as unseen); None when no image
    recorded any (Method 1, or a pool made before visibility was measured)."""
    path = folder / "manifest.json"
    if not path.is_file():
        return None
    per_image = json.loads(path.read_text(encoding="utf-8")).get("args", {}).get("per_image") or []
    contrast = [f["contrast"] for meta in per_image for f in meta.get("flames", []) if "contrast" in f]
    if not any("erased" in meta for meta in per_image):
        return None
    return {
        "boxes": len(contrast),
        "min_contrast": round(float(np.min(contrast)), 2) if contrast else None,
        "median_contrast": round(float(np.median(contrast)), 2) if contrast else None,
        "erased": int(sum(meta.get("erased", 0) for meta in per_image)),
    }


def _frame_boxes(folder: Path, images: int, key: str = "frame_boxes") -> list[int]:
    """Per image (in ``annotations.json`` order), how many of its last fire boxes (``key`` frame_boxes) or smoke
    boxes (frame_smoke_boxes) are a labelled frame's own (in the manifest's per-image records,
    :mod:`synth.places.frames`): labels without a mask, not audited."""
    path = folder / "manifest.json"
    manifest = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}
    per_image = manifest.get("args", {}).get("per_image")
    if not per_image or len(per_image) != images:
        return [0] * images
    return [len(meta.get(key, [])) for meta in per_image]


def audit_dataset(folder: Path) -> dict[str, Any]:
    """``{"images", "boxes", "mean_iou", "min_iou"}`` of the written fire boxes vs their mask boxes, plus
    ``"modes": {mode: {...}}`` when alternative box sets were kept, ``"smoke": {...}`` for smoke boxes and
    ``"visibility": {...}`` (:func:`visibility_summary`) when the images recorded it, and ``"frame_boxes"``: how
    many boxes were a labelled frame's own (not audited) when there were any."""
    coco = json.loads((folder / "annotations.json").read_text(encoding="utf-8"))
    fire = _boxes_by_image(coco, "fire")
    if fire is None:
        raise ValueError(f"{folder}: no 'fire' category to audit")
    smoke = _boxes_by_image(coco, "smoke")
    modes_path = folder / "masks" / "box_modes.json"
    modes = json.loads(modes_path.read_text(encoding="utf-8")) if modes_path.is_file() else {}
    ious: list[float] = []
    smoke_ious: list[float] = []
    mode_ious: dict[str, list[float]] = {}
    frames = _frame_boxes(folder, len(coco["images"]))
    smoke_frames = _frame_boxes(folder, len(coco["images"]), "frame_smoke_boxes")
    for k, img in enumerate(coco["images"]):
        mask_path = folder / "masks" / Path(img["file_name"]).relative_to("images").with_suffix(".png")
        truths = _truths(mask_path)
        flames = fire[img["id"]][: len(fire[img["id"]]) - frames[k]]  # a frame's own boxes come last, unmasked
        ious += _ious(flames, truths)
        for mode, boxes in modes.get(img["file_name"], {}).items():
            mode_ious.setdefault(mode, []).extend(_ious(boxes, truths))
        if smoke is not None:
            plumes = smoke[img["id"]][: len(smoke[img["id"]]) - smoke_frames[k]]
            smoke_ious += _ious(plumes, _truths(mask_path.with_suffix(".smoke.png")))
    result = _summary(ious, len(coco["images"]))
    if any(frames) or any(smoke_frames):
        result["frame_boxes"] = sum(frames) + sum(smoke_frames)
    if mode_ious:
        result["modes"] = {m: _summary(v, len(coco["images"])) for m, v in sorted(mode_ious.items())}
    if smoke is not None:
        result["smoke"] = _summary(smoke_ious, len(coco["images"]))
    visibility = visibility_summary(folder)
    if visibility is not None:
        result["visibility"] = visibility
    return result

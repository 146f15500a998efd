"""Flame cut-outs from a labelled real dataset: the fire-coloured pixels inside each box as an RGBA sprite.

A flame library of real flames (Method 1 and 2 take it with ``--flames`` / ``flames.folders``) measures how
much of the synthetic-to-real gap is the flames' appearance and how much the scenes around them: the same
pipeline with real flames in place of simulated ones. It is also copy-paste augmentation (real flames put in
new surroundings) for a user who has labelled fire images.

The mask is a colour rule, not a segmentation: a pixel is fire when it is warm (R > 0.5, R >= G >= 0.9 B,
R - B > 0.25, channels in [0, 1]) or a bright core (R > 0.8, G > 0.65, R >= B); the mask is closed (5x5) and
its holes filled, then softened into the alpha channel. Warm surfaces lit by the fire pass the rule too; boxes
whose fire-coloured share is below ``min_cover`` are skipped.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.core.classes import canonical_class
from curate.core.dataset import Dataset
from curate.core.imageio import ImageError, read_image
from curate.core.names import check_names
from curate.core.problems import Problem
from curate.core.progress import progress
from synth.sprites import write_png

#: Cut-outs per sequence folder (Method 1/2 pick a sequence, then one of its frames).
PER_SEQUENCE = 25


@dataclass(frozen=True)
class Cutout:
    """One cut-out: ``rgba`` (h, w, 4) uint8 straight alpha, cropped to its source ``box`` (x, y, w, h pixels,
    integer, inside the image) of image ``file``; ``cover`` the fire-coloured share of the box."""

    rgba: NDArray[np.uint8]
    file: str
    box: tuple[int, int, int, int]
    cover: float


def fire_mask(rgb: NDArray[np.uint8]) -> NDArray[np.bool_]:
    """(h, w) bool: fire-coloured pixels of an (h, w, 3) RGB image (the rule in the module docstring)."""
    f = rgb.astype(np.float32) / 255.0
    r, g, b = f[..., 0], f[..., 1], f[..., 2]
    warm = (r > 0.5) & (r >= g) & (g >= 0.9 * b) & (r - b > 0.25)
    core = (r > 0.8) & (g > 0.65) & (r >= b)
    return warm | core


def filled(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """``mask`` closed with a 5x5 square and every hole of its outer contours filled."""
    m = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
    contours, _ = cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    return cv2.drawContours(np.zeros_like(m), contours, -1, 1, thickness=-1).astype(bool)


def cut(
    rgb: NDArray[np.uint8], box: tuple[int, int, int, int], min_cover: float
) -> tuple[NDArray[np.uint8], float] | None:
    """The RGBA cut-out (h, w, 4) of integer box (x, y, w, h) of ``rgb`` and its fire share, or None when less
    than ``min_cover`` of the box is fire-coloured."""
    x, y, w, h = box
    crop = rgb[y : y + h, x : x + w]
    raw = fire_mask(crop)
    cover = float(raw.mean())
    if cover < min_cover:
        return None
    alpha = cv2.GaussianBlur(filled(raw).astype(np.float32), (0, 0), 1.0)
    return np.dstack([crop, np.round(np.clip(alpha, 0.0, 1.0) * 255.0).astype(np.uint8)]), cover


def pixel_box(bbox: tuple[float, float, float, float], width: int, height: int) -> tuple[int, int, int, int]:
    """COCO ``[x, y, w, h]`` (float pixels) -> the integer pixel box covering it, clipped to the image
    (coordinates rounded to 1/1000 pixel first: normalised labels carry float noise)."""
    x, y, w, h = (round(float(v), 3) for v in bbox)
    x0, y0 = max(int(np.floor(x)), 0), max(int(np.floor(y)), 0)
    x1, y1 = min(int(np.ceil(round(x + w, 3))), width), min(int(np.ceil(round(y + h, 3))), height)
    return x0, y0, max(x1 - x0, 0), max(y1 - y0, 0)


def cutouts(
    ds: Dataset, category: str, min_side: int = 16, min_cover: float = 0.08, problems: list[Problem] | None = None
) -> Iterator[Cutout]:
    """Cut-outs of every ``category`` box of ``ds`` at least ``min_side`` pixels on both sides, image by image
    in the dataset's order (each image read once). Unreadable images are appended to ``problems``."""
    category = canonical_class(category)
    check_names("class", [category], ds.category_names, str(ds.root), "classes", "--class")
    cat_ids = {c.id for c in ds.categories if c.name == category}
    boxes: dict[int, list[tuple[float, float, float, float]]] = {}
    for a in ds.annotations:
        if a.category_id in cat_ids and not a.iscrowd and min(a.bbox[2], a.bbox[3]) >= min_side:
            boxes.setdefault(a.image_id, []).append(tuple(a.bbox))
    images = [img for img in ds.images if img.id in boxes]
    for img in progress(images, total=len(images), desc="cut-outs", unit="img"):
        path = ds.image_path(img)
        try:
            rgb = read_image(path)
        except ImageError as exc:
            if problems is not None:
                problems.append(Problem(str(path), f"skipped: {exc.reason}"))
            continue
        height, width = rgb.shape[:2]
        for bbox in boxes[img.id]:
            box = pixel_box(bbox, width, height)
            got = cut(rgb, box, min_cover) if min(box[2], box[3]) >= min_side else None
            if got is not None:
                yield Cutout(got[0], str(img.file_name), box, got[1])


def write_cutouts(items: Iterator[Cutout], out: Path, per_sequence: int = PER_SEQUENCE) -> int:
    """Write ``items`` as RGBA PNG sequence folders ``out/real-KKK/NNNNN.png`` (``per_sequence`` each) and
    ``out/cutouts.json`` (source file, box, cover of each PNG); returns the count. ``out`` must be new or empty
    (:class:`FileExistsError` otherwise); when writing fails, what was written is removed."""
    if (out / "cutouts.json").exists():
        raise FileExistsError(f"{out}: holds cut-outs already (cutouts.json); choose an empty folder")
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise FileExistsError(f"{out}: is not an empty folder; choose a new or empty one")
    created = not out.exists()
    try:
        return _write_sequences(items, out, per_sequence)
    except BaseException:
        for child in [out] if created else list(out.iterdir()):
            shutil.rmtree(child, ignore_errors=True)
        raise


def _write_sequences(items: Iterator[Cutout], out: Path, per_sequence: int) -> int:
    index = []
    for n, item in enumerate(items):
        name = f"real-{n // per_sequence:03d}/{n:05d}.png"
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        write_png(out / name, item.rgba)
        index.append({"png": name, "file": item.file, "box": list(item.box), "cover": round(item.cover, 4)})
    out.mkdir(parents=True, exist_ok=True)
    (out / "cutouts.json").write_text(json.dumps(index, indent=1) + "\n", encoding="utf-8")
    return len(index)

"""Labelled frames as Method 2 backgrounds: the images of a labelled dataset (e.g. a user's own CCTV frames with
their fire boxes, or the real training images of a mixture) are composited on like photos (:mod:`synth.places.photos`:
sites, random crops), and each keeps its own fire boxes: they are carried through the crop into the composite's
labels, and no flame is placed over them. A frame is a site whose ground is estimated (or read
from a sidecar) like a photo's.

A frame's box survives a crop when at least :data:`MIN_KEPT` of its area and :data:`MIN_SIDE_PX` pixels of each
side are inside (the rule YOLOv5's augmentation keeps boxes by); the boxes cut off more are dropped.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from ground.data.dataset import Dataset
from ground.data.problems import Problem

#: A box [x, y, w, h] in pixels of the image it is in.
Box = tuple[float, float, float, float]

#: The class whose boxes a frame keeps.
FIRE = "fire"

UNREADABLE = "unreadable image"  # how every dataset reader's problem for an image it skipped begins
MIN_KEPT = 0.2  # share of a frame box's area a crop must keep for the box to stay a label
MIN_SIDE_PX = 2.0  # pixels of each side of a kept box, in the output image


def load_frames(paths: Iterable[Path | str], problems: list[Problem] | None = None) -> dict[Path, tuple[Box, ...]]:
    """Every image of the labelled datasets at ``paths`` (any format the toolkit reads, every split) and its
    ``fire`` boxes [x, y, w, h] px (other classes dropped; an image without fire boxes is a frame too, with
    none), in the datasets' order; ValueError when a dataset has no images. The images the reader skipped as
    unreadable are appended to ``problems`` (when given), as the reader names them."""
    from ground.data.formats.registry import read_dataset

    out: dict[Path, tuple[Box, ...]] = {}
    for path in paths:
        result = read_dataset(path)
        if problems is not None:
            problems += [p for p in result.problems if p.reason.startswith(UNREADABLE)]
        ds = fire_only(result.dataset, path)
        boxes = ds.annotations_by_image()
        for img in ds.images:
            out[ds.image_path(img)] = tuple(tuple(float(v) for v in a.bbox) for a in boxes[img.id])  # type: ignore[misc]
    return out


def frame_fingerprints(paths: Iterable[Path | str]) -> list[dict[str, Any]]:
    """Each labelled dataset at ``paths`` by content (:func:`ground.data.fingerprint.fingerprint` of its fire
    boxes and image bytes): what a pool composited on it is made of, wherever the folder lies."""
    from ground.data.fingerprint import fingerprint
    from ground.data.load import load_split

    return [fingerprint(fire_only(load_split(path), path)).to_dict() for path in paths]


def fire_only(ds: Dataset, where: Path | str) -> Dataset:
    """``ds`` (every image) with its fire boxes alone: a frame whose boxes are all of other classes stays a frame,
    with none (their classes count as negatives, :func:`ground.data.load.with_classes`)."""
    from ground.data.load import prepare

    return prepare(ds, None, [FIRE], where=where, negatives=[n for n in ds.category_names if n != FIRE])


def crop_boxes(boxes: Sequence[Box], crop: Sequence[int], width: int, height: int) -> list[list[float]]:
    """``boxes`` [x, y, w, h] px of a photo, seen in its ``crop`` [x, y, w, h] px resized to ``width`` x
    ``height``: clipped to the crop, in output pixels (rounded to 0.01), and only those that keep
    :data:`MIN_KEPT` of their area and :data:`MIN_SIDE_PX` per side (module docstring)."""
    cx, cy, cw, ch = crop
    sx, sy = width / cw, height / ch
    out = []
    for x, y, w, h in boxes:
        x0, y0 = max(x, cx), max(y, cy)
        x1, y1 = min(x + w, cx + cw), min(y + h, cy + ch)
        if x1 <= x0 or y1 <= y0 or (x1 - x0) * (y1 - y0) < MIN_KEPT * w * h:
            continue
        kept = [(x0 - cx) * sx, (y0 - cy) * sy, (x1 - x0) * sx, (y1 - y0) * sy]
        if min(kept[2], kept[3]) >= MIN_SIDE_PX:
            out.append([round(v, 2) for v in kept])
    return out

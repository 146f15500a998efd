"""Labelled frames as Method 2 backgrounds: the images of a labelled dataset (e.g. a user's own CCTV frames with
their fire boxes, or the real training images of a mixture) are composited on like photos (:mod:`synth.places.photos`:
sites, random crops), and each keeps its own boxes of the pool's classes (fire, and smoke when the pool boxes smoke:
:func:`frame_classes`): they are carried through the crop into the composite's labels, and no flame is placed over
its fires. A frame whose smoke a fire-only pool cannot label keeps it unlabelled, as a fire-only study counts smoke. A frame is a site whose ground is estimated (or read
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

#: A frame's boxes [x, y, w, h] px by class: ``fire``, and ``smoke`` when the pool boxes smoke.
FrameLabels = dict[str, tuple[Box, ...]]

#: The class whose boxes every frame keeps ...
FIRE = "fire"
#: ... and the one it keeps too when the pool boxes smoke (``smoke_class``).
SMOKE = "smoke"

UNREADABLE = "unreadable image"  # how every dataset reader's problem for an image it skipped begins
MIN_KEPT = 0.2  # share of a frame box's area a crop must keep for the box to stay a label
MIN_SIDE_PX = 2.0  # pixels of each side of a kept box, in the output image


def frame_classes(smoke: bool) -> tuple[str, ...]:
    """The classes a frame keeps: fire, and smoke when the pool boxes ``smoke``."""
    return (FIRE, SMOKE) if smoke else (FIRE,)


def load_frames(
    paths: Iterable[Path | str], problems: list[Problem] | None = None, classes: Sequence[str] = (FIRE,)
) -> dict[Path, FrameLabels]:
    """Every image of the labelled datasets at ``paths`` (any format the toolkit reads, every split) and its boxes
    [x, y, w, h] px of each of ``classes`` (:func:`frame_classes`; other classes dropped; an image without such
    boxes is a frame too, with none), in the datasets' order; ValueError when a dataset has no images. The images
    the reader skipped as unreadable are appended to ``problems`` (when given), as the reader names them."""
    from ground.data.formats.registry import read_dataset

    out: dict[Path, FrameLabels] = {}
    for path in paths:
        result = read_dataset(path)
        if problems is not None:
            problems += [p for p in result.problems if p.reason.startswith(UNREADABLE)]
        ds = kept_classes(result.dataset, path, classes)
        boxes, names = ds.annotations_by_image(), {c.id: c.name for c in ds.categories}
        for img in ds.images:
            out[ds.image_path(img)] = {
                name: tuple(tuple(float(v) for v in a.bbox) for a in boxes[img.id] if names[a.category_id] == name)  # type: ignore[misc]
                for name in classes
            }
    return out


def frame_fingerprints(paths: Iterable[Path | str], classes: Sequence[str] = (FIRE,)) -> list[dict[str, Any]]:
    """Each labelled dataset at ``paths`` by content (:func:`ground.data.fingerprint.fingerprint` of its boxes of
    ``classes`` and image bytes): what a pool composited on it is made of, wherever the folder lies."""
    from ground.data.fingerprint import fingerprint
    from ground.data.load import load_split

    return [fingerprint(kept_classes(load_split(path), path, classes)).to_dict() for path in paths]


def kept_classes(ds: Dataset, where: Path | str, classes: Sequence[str]) -> Dataset:
    """``ds`` (every image) with its boxes of ``classes`` alone: a frame whose boxes are all of other classes stays
    a frame, with none (their classes count as negatives, :func:`ground.data.load.with_classes`)."""
    from ground.data.load import prepare

    others = [n for n in ds.category_names if n not in classes]
    return prepare(ds, None, list(classes), where=where, negatives=others)


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

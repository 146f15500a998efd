"""Flame cut-outs from a labelled real dataset: the flame pixels inside each box as an RGBA sprite.

A flame library of real flames (Method 1 and 2 take it with ``--flames`` / ``flames.folders``) measures how
much of the synthetic-to-real gap is the flames' appearance and how much the scenes around them: the same
pipeline with real flames in place of simulated ones. It is also copy-paste augmentation (real flames put in
new surroundings) for a user who has labelled fire images.

Two mask rules (:data:`MASK_RULES`, the ``mask`` key of :class:`CutoutConfig`). ``colour``: a pixel is fire
when it is warm (R > 0.5, R >= G >= 0.9 B, R - B > 0.25, channels in [0, 1]) or a bright core (R > 0.8,
G > 0.65, R >= B); the mask is closed (5x5) and its holes filled. Warm or bright surfaces lit by the fire pass it too, so a box on a lit wall becomes a filled
rectangle. ``grabcut`` (the default): that mask only starts ``cv2.grabCut`` (its pixels probable flame, the
box's other pixels probable background, a ring of ``context`` x the box's longer side around the box
background), which learns the image's own flame and background colours and cuts along their edges; when it
keeps under :data:`MIN_KEPT` of the box (or the box has no background pixel to learn from) the colour mask is
kept. ``experiments/cutout_masks.py`` measures both against true masks. Either mask is softened into the alpha
channel and multiplied by a super-elliptical window (:data:`FLAME_WINDOW`): where fire fills its box, the mask is
the whole box, and without the window the pasted flame showed as a rectangular patch of its source frame. Boxes
whose colour-rule share is below ``min_cover`` are skipped.

``class_name: smoke`` cuts smoke instead: each smoke box is *matted* (:func:`synth.smoke.matte.matte`: a soft
opacity by the dark channel prior, never a cut edge), and the cut-outs are written as smoke sprite sequences
(:func:`synth.flames.sprites.save_sequence`, ``kind: smoke``), which Method 2 lays as plumes. Every setting is a key of
:class:`CutoutConfig` (``fuzzyfire synth cutouts``, ``synth colour`` and the experiment's own pools).
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, get_args

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.data.classes import canonical_class
from ground.data.dataset import Dataset
from ground.data.names import check_names
from ground.data.problems import Problem
from ground.image.imageio import ImageError, read_image, unit_to_u8
from ground.run.progress import progress
from synth.compose.ramps import window
from synth.flames.firepixels import fire_mask
from synth.flames.sprites import SMOKE_KIND, Sprite, SpriteSequence, save_sequence, write_png

#: Cut-outs per sequence folder (Method 1/2 pick a sequence, then one of its frames).
PER_SEQUENCE = 25

#: A mask rule of :func:`cut` (module docstring).
MaskRule = Literal["colour", "grabcut"]
MASK_RULES: tuple[str, ...] = get_args(MaskRule)

#: GrabCut iterations (colour models re-fitted, graph cut again).
GRABCUT_ITERATIONS = 5

#: A GrabCut mask keeping less than this share of the box is discarded for the colour mask.
MIN_KEPT = 0.05

#: A flame cut-out's alpha window (:func:`synth.compose.ramps.window`): (inner share, super-ellipse power): 1 inside
#: 0.8 of the way to the box's edge, 0 on it and in the corners.
FLAME_WINDOW = (0.8, 4.0)


@dataclass(frozen=True)
class CutoutConfig:
    """Which boxes are cut out and how: ``fuzzyfire synth cutouts`` and ``synth colour`` (its flame pixels), and,
    at these defaults, the experiment's own cut-out pools (:mod:`fuzzyfire.cutout_pools`)."""

    class_name: str = "fire"  # class whose boxes are cut out (a synonym such as Flames reads as fire); smoke boxes
    # are matted into soft smoke sprites (synth.smoke.matte)
    min_side: int = 16  # skip boxes smaller than this on either side, pixels, >= 1
    min_cover: float = 0.08  # skip boxes less fire-coloured (colour rule) than this share, 0..1
    mask: MaskRule = "grabcut"  # flame mask rule: grabcut (the colour mask refined by cv2.grabCut) | colour
    # (the colour mask alone)
    context: float = 0.3  # grabcut: the background ring around a box, fraction of the box's longer side (clipped
    # to the image), >= 0

    def __post_init__(self) -> None:
        if self.mask not in MASK_RULES:
            raise ValueError(f"unknown cut-out mask rule {self.mask!r}; choose one of {', '.join(MASK_RULES)}")
        if self.min_side < 1 or not 0.0 <= self.min_cover <= 1.0:
            raise ValueError(f"min_side must be >= 1 and min_cover in 0..1, got {self.min_side}, {self.min_cover}")
        if self.context < 0:
            raise ValueError(f"context must be >= 0, got {self.context}")
        if not self.class_name.strip():
            raise ValueError("class_name must name a class")


@dataclass(frozen=True)
class Cutout:
    """One cut-out: ``rgba`` (h, w, 4) uint8 straight alpha, cropped to its source ``box`` (x, y, w, h pixels,
    integer, inside the image) of image ``file``; ``cover`` the fire-coloured share of the box (a smoke cut-out:
    its mean opacity); ``category`` fire or smoke."""

    rgba: NDArray[np.uint8]
    file: str
    box: tuple[int, int, int, int]
    cover: float
    category: str = "fire"


def filled(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """``mask`` closed with a 5x5 square and every hole of its outer contours filled."""
    m = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
    contours, _ = cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    return cv2.drawContours(np.zeros_like(m), contours, -1, 1, thickness=-1).astype(bool)


def grabcut_mask(
    rgb: NDArray[np.uint8], box: tuple[int, int, int, int], start: NDArray[np.bool_], context: float
) -> NDArray[np.bool_]:
    """(h, w) bool flame mask of integer box (x, y, w, h) of the (H, W, 3) RGB image ``rgb``: GrabCut started
    from ``start`` ((h, w) bool, the colour mask) with a background ring of ``context`` x the box's longer side,
    as the module docstring says; ``start`` itself when GrabCut
    keeps too little or has no background to learn from. Deterministic: OpenCV draws its k-means start from the
    calling thread's RNG, which is reset before the call, so a mask never depends on what was cut before it."""
    x, y, w, h = box
    height, width = rgb.shape[:2]
    pad = max(4, int(round(context * max(w, h))))
    x0, y0, x1, y1 = max(x - pad, 0), max(y - pad, 0), min(x + w + pad, width), min(y + h + pad, height)
    labels = np.full((y1 - y0, x1 - x0), cv2.GC_BGD, np.uint8)
    labels[y - y0 : y - y0 + h, x - x0 : x - x0 + w] = np.where(start, cv2.GC_PR_FGD, cv2.GC_PR_BGD)
    if not start.any() or not (labels != cv2.GC_PR_FGD).any():
        return start
    bgr = np.ascontiguousarray(rgb[y0:y1, x0:x1, ::-1])
    cv2.setRNGSeed(0)
    models = (np.zeros((1, 65), np.float64), np.zeros((1, 65), np.float64))
    cv2.grabCut(bgr, labels, None, models[0], models[1], GRABCUT_ITERATIONS, cv2.GC_INIT_WITH_MASK)
    kept = np.isin(labels[y - y0 : y - y0 + h, x - x0 : x - x0 + w], (cv2.GC_FGD, cv2.GC_PR_FGD))
    return kept if kept.mean() >= MIN_KEPT else start


def cut(
    rgb: NDArray[np.uint8], box: tuple[int, int, int, int], cfg: CutoutConfig
) -> tuple[NDArray[np.uint8], float] | None:
    """The RGBA cut-out (h, w, 4) of integer box (x, y, w, h) of ``rgb`` and its fire share (colour rule), or
    None when less than ``cfg.min_cover`` of the box is fire-coloured; the flame by the ``cfg.mask`` rule."""
    x, y, w, h = box
    crop = rgb[y : y + h, x : x + w]
    raw = fire_mask(crop)
    cover = float(raw.mean())
    if cover < cfg.min_cover:
        return None
    flame = filled(raw) if cfg.mask == "colour" else grabcut_mask(rgb, box, filled(raw), cfg.context)
    alpha = cv2.GaussianBlur(flame.astype(np.float32), (0, 0), 1.0) * window(h, w, *FLAME_WINDOW)
    return np.dstack([crop, unit_to_u8(alpha)]), cover


def pixel_box(bbox: tuple[float, float, float, float], width: int, height: int) -> tuple[int, int, int, int]:
    """COCO ``[x, y, w, h]`` (float pixels) -> the integer pixel box covering it, clipped to the image
    (coordinates rounded to 1/1000 pixel first: normalised labels carry float noise)."""
    x, y, w, h = (round(float(v), 3) for v in bbox)
    x0, y0 = max(int(np.floor(x)), 0), max(int(np.floor(y)), 0)
    x1, y1 = min(int(np.ceil(round(x + w, 3))), width), min(int(np.ceil(round(y + h, 3))), height)
    return x0, y0, max(x1 - x0, 0), max(y1 - y0, 0)


def cutouts(ds: Dataset, cfg: CutoutConfig, problems: list[Problem] | None = None) -> Iterator[Cutout]:
    """Cut-outs of every ``cfg.class_name`` box of ``ds`` at least ``cfg.min_side`` pixels on both sides, image by
    image in the dataset's order (each image read once), by :func:`cut` (fire) or
    :func:`synth.smoke.matte.matte` (smoke, its image's fire boxes kept clear). Unreadable images are appended to
    ``problems``."""
    from synth.smoke.matte import matte

    category, min_side = canonical_class(cfg.class_name), cfg.min_side
    check_names("class", [category], ds.category_names, str(ds.root), "classes", "--class")
    names = {c.id: c.name for c in ds.categories}
    boxes: dict[int, list[tuple[float, float, float, float]]] = {}
    fires: dict[int, list[tuple[float, float, float, float]]] = {}
    for a in ds.annotations:
        if names[a.category_id] == "fire":
            fires.setdefault(a.image_id, []).append(tuple(a.bbox))
        if names[a.category_id] == category and not a.iscrowd and min(a.bbox[2], a.bbox[3]) >= min_side:
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
        clear = [pixel_box(b, width, height) for b in fires.get(img.id, [])]
        for bbox in boxes[img.id]:
            box = pixel_box(bbox, width, height)
            if min(box[2], box[3]) < min_side:
                continue
            got = matte(rgb, box, clear) if category == "smoke" else cut(rgb, box, cfg)
            if got is not None:
                yield Cutout(got[0], str(img.file_name), box, got[1], category)


def write_cutouts(items: Iterator[Cutout], out: Path, per_sequence: int = PER_SEQUENCE) -> int:
    """Write ``items`` as sequence folders of ``per_sequence`` each and ``out/cutouts.json`` (class, source file,
    box, cover of each); returns the count. Flames: RGBA PNGs ``out/real-KKK/NNNNN.png``; smoke: smoke sprite
    sequences ``out/smoke-KKK/`` (:func:`synth.flames.sprites.save_sequence`, ``kind: smoke``, frame j its j-th
    cut-out). ``out`` must be new or empty
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
    index: list[dict] = []
    smoke: list[Cutout] = []
    flames = 0
    for item in items:
        if item.category == "smoke":
            smoke.append(item)
            if len(smoke) == per_sequence:
                _write_smoke(out, smoke, index, per_sequence)
                smoke = []
            continue
        name = f"real-{flames // per_sequence:03d}/{flames:05d}.png"
        flames += 1
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        write_png(out / name, item.rgba)
        index.append(
            {"class": "fire", "png": name, "file": item.file, "box": list(item.box), "cover": round(item.cover, 4)}
        )
    if smoke:
        _write_smoke(out, smoke, index, per_sequence)
    out.mkdir(parents=True, exist_ok=True)
    (out / "cutouts.json").write_text(json.dumps(index, indent=1) + "\n", encoding="utf-8")
    return len(index)


def _write_smoke(out: Path, items: list[Cutout], index: list[dict], per_sequence: int) -> None:
    """One smoke sprite sequence of ``items`` (mattes laid over, no flame, no emission), entries added to ``index``."""
    k = sum(e["class"] == "smoke" for e in index) // per_sequence
    name = f"smoke-{k:03d}"
    sprites = tuple(
        Sprite(c.rgba, np.zeros((*c.rgba.shape[:2], 3), np.uint8), np.zeros(c.rgba.shape[:2], bool)) for c in items
    )
    save_sequence(out / name, SpriteSequence(name, sprites, {"generator": "smoke-cutouts", "kind": SMOKE_KIND}))
    for j, c in enumerate(items):
        entry = {"class": "smoke", "sequence": name, "frame": j, "file": c.file, "box": list(c.box)}
        index.append({**entry, "cover": round(c.cover, 4)})

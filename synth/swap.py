"""Fire swaps on labelled frames: a frame's own fires erased and other flames drawn in their boxes.

A labelled frame (:mod:`synth.frames`: a user's CCTV frame, or a mixture's own real training image) shows each
fire where fires happen, lit and smoked as the camera saw it, and boxed as its annotator boxes fires. A swap keeps
all of that and changes the flame: the fire pixels of each of its boxes are erased (:func:`erased`: the
fire-coloured pixels of the box and a margin around it, grown a little and filled in from their surroundings by
``cv2.inpaint``, Telea's method) and a flame of the library is drawn over the box (:func:`best_fit`, :func:`spanning`: of
:data:`CANDIDATES` random library frames, the one whose flame is shaped most like the box, its flame mask's box
stretched onto the frame's box; a cut-out whose mask holds more than flame — a sign, a car, a wall the fire lit
— is passed over while a candidate with at least :data:`MIN_FIRE_SHARE` fire-coloured mask pixels is there). The
flame is composited and its visibility measured like any other flame
(:func:`synth.method2.visible_composite`): it is boxed by its seen pixels, and erased when it cannot be seen (then
the box's place holds no fire and no box).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.cutouts import filled, fire_mask
from synth.library import FlameLibraryConfig, pick_sequence
from synth.sprites import Sprite, SpriteSequence, flame_extent, flame_rect

#: Library frames drawn for each swapped box; the one shaped most like the box is drawn.
CANDIDATES = 8

#: A candidate is taken only when at least this share of its flame mask's pixels is fire-coloured (unless none is).
MIN_FIRE_SHARE = 0.6

#: The erased region: the fire-coloured pixels of each box grown by this fraction of its sides on every side ...
MARGIN = 0.1

#: ... and then dilated by this fraction of the box's shorter side (at least 2 pixels): a flame's soft, dim edge.
GROW = 0.1

#: ``cv2.inpaint`` neighbourhood radius, pixels.
INPAINT_RADIUS = 3


def fire_region(rgb: NDArray[np.uint8], boxes: Sequence[Sequence[float]]) -> NDArray[np.bool_]:
    """(H, W) bool: the pixels :func:`erased` fills in for ``boxes`` [x, y, w, h] px of the (H, W, 3) RGB image —
    per box, the fire-coloured pixels (:func:`synth.cutouts.fire_mask`, holes filled) of the box grown by
    :data:`MARGIN`, dilated by :data:`GROW`; the whole box when none of its pixels is fire-coloured."""
    height, width = rgb.shape[:2]
    region = np.zeros((height, width), bool)
    for x, y, w, h in boxes:
        mx, my = MARGIN * w, MARGIN * h
        x0, y0 = max(int(np.floor(x - mx)), 0), max(int(np.floor(y - my)), 0)
        x1, y1 = min(int(np.ceil(x + w + mx)), width), min(int(np.ceil(y + h + my)), height)
        if x1 <= x0 or y1 <= y0:
            continue
        fire = filled(fire_mask(rgb[y0:y1, x0:x1]))
        if not fire.any():
            bx0, by0 = max(int(np.floor(x)), 0), max(int(np.floor(y)), 0)
            region[by0 : int(np.ceil(y + h)), bx0 : int(np.ceil(x + w))] = True
            continue
        r = max(2, int(round(GROW * min(w, h))))
        grown = cv2.dilate(fire.astype(np.uint8), cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
        region[y0:y1, x0:x1] |= grown.astype(bool)
    return region


def erased(rgb: NDArray[np.uint8], boxes: Sequence[Sequence[float]]) -> NDArray[np.uint8]:
    """A new (H, W, 3) uint8 RGB image: ``rgb`` with the fires of ``boxes`` [x, y, w, h] px filled in from their
    surroundings (:func:`fire_region`, ``cv2.inpaint`` Telea); pixels outside that region are unchanged."""
    region = fire_region(rgb, boxes)
    if not region.any():
        return rgb.copy()
    bgr = np.ascontiguousarray(rgb[..., ::-1])
    filled_in = cv2.inpaint(bgr, region.astype(np.uint8), INPAINT_RADIUS, cv2.INPAINT_TELEA)
    return np.ascontiguousarray(filled_in[..., ::-1])


def fire_share(sprite: Sprite) -> float:
    """The share of ``sprite``'s flame mask pixels whose colour (its ``over`` RGB) is fire-coloured
    (:func:`synth.cutouts.fire_mask`); 0 for an empty mask."""
    if not sprite.mask.any():
        return 0.0
    return float(fire_mask(np.ascontiguousarray(sprite.over[..., :3]))[sprite.mask].mean())


def best_fit(
    library: Sequence[SpriteSequence], cfg: FlameLibraryConfig, aspect: float, rng: np.random.Generator
) -> tuple[SpriteSequence, int]:
    """(sequence, frame index) of the library frame, of :data:`CANDIDATES` drawn with ``rng`` (each a sequence by
    :func:`synth.library.pick_sequence`, then a frame), whose flame mask's width / height is nearest ``aspect`` in
    log ratio among those whose :func:`fire_share` is at least :data:`MIN_FIRE_SHARE` (among all when none is;
    the first of equals)."""
    best: tuple[tuple[bool, float], SpriteSequence, int] | None = None
    for _ in range(CANDIDATES):
        seq = pick_sequence(library, cfg, rng)
        frame = int(rng.integers(len(seq.sprites)))
        sprite = seq.sprites[frame]
        fw, fh = flame_extent(sprite)
        miss = float(abs(np.log(fw / fh) - np.log(aspect)))
        key = (fire_share(sprite) < MIN_FIRE_SHARE, miss)
        if best is None or key < best[0]:
            best = (key, seq, frame)
    assert best is not None
    return best[1], best[2]


def spanning(sprite: Sprite, box: Sequence[float]) -> tuple[int, int, int, int]:
    """(x, y, width, height) pixels of the placement that stretches ``sprite``'s flame mask box onto ``box``
    [x, y, w, h] px (the canvas around the mask scaled with it; width and height at least 1)."""
    c0, r0, _, _ = flame_rect(sprite)
    (sw, sh), (fw, fh) = sprite.size, flame_extent(sprite)
    sx, sy = box[2] / fw, box[3] / fh
    width, height = max(int(round(sw * sx)), 1), max(int(round(sh * sy)), 1)
    return int(round(box[0] - c0 * sx)), int(round(box[1] - r0 * sy)), width, height

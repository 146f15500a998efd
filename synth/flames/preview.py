"""A flame library's preview sheet: what each sequence looks like once composited, since its files alone do not
show it (the emission is light on black, the smoke a translucent layer, the mask black and white).

One band per sequence: its name, then a row of frames composited over a dark background and a row over a light
one, by :func:`synth.compose.composite.composite` with Method 2's default placement (screen blend, glow, warm cast), so
flames show as they will in a dataset: bright on dark walls, and their smoke visible on light ones.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.compose.composite import Placement, composite
from synth.flames.sprites import SpriteSequence, write_png

DARK = (24, 24, 28)  # RGB of the dark background row
LIGHT = (205, 205, 200)  # RGB of the light background row
LABEL_HEIGHT = 18  # pixels of the name strip above each band


def frame_indices(count: int, shown: int) -> list[int]:
    """Up to ``shown`` frame indices of a ``count``-frame sequence, evenly spread, first and last included."""
    if count <= shown:
        return list(range(count))
    return sorted({int(round(i)) for i in np.linspace(0, count - 1, shown)})


def flame_tile(sprite_seq: SpriteSequence, index: int, background: tuple[int, int, int], tile: int) -> NDArray:
    """(tile, tile, 3) uint8 RGB: frame ``index`` of ``sprite_seq`` scaled to fit 80 % of the tile, standing on
    its bottom, composited over a flat ``background``."""
    sprite = sprite_seq.sprites[index]
    sw, sh = sprite.size
    scale = 0.8 * tile / max(sw, sh)
    w, h = max(1, round(sw * scale)), max(1, round(sh * scale))
    canvas = np.empty((tile, tile, 3), np.uint8)
    canvas[:] = background
    placed = Placement(sprite, (tile - w) // 2, tile - h - tile // 20, w, h)
    return composite(canvas, [placed]).image


def _label(text: str, width: int) -> NDArray[np.uint8]:
    strip = np.full((LABEL_HEIGHT, width, 3), 255, np.uint8)
    cv2.putText(strip, text, (4, LABEL_HEIGHT - 5), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (0, 0, 0), 1, cv2.LINE_AA)
    return strip


def _caption(seq: SpriteSequence) -> str:
    params = seq.meta.get("params", {})
    parts = [seq.name, f"{len(seq.sprites)} frames"]
    if params:
        parts += [str(params.get("shape", "")), str(params.get("palette", "")), f"smoke {params.get('smoke', 0):.2f}"]
    return "  ".join(p for p in parts if p)


def preview_sheet(seqs: Sequence[SpriteSequence], shown: int = 8, tile: int = 96) -> NDArray[np.uint8]:
    """(H, W, 3) uint8 RGB sheet, W = ``shown`` x ``tile``: per sequence a name strip, its frames (at most
    ``shown``, evenly spread) over :data:`DARK`, then the same frames over :data:`LIGHT`; one white pixel row
    between bands. Raises ValueError for an empty library."""
    if not seqs:
        raise ValueError("no flame sequence to preview")
    width = shown * tile
    bands = []
    for seq in seqs:
        idx = frame_indices(len(seq.sprites), shown)
        rows = []
        for bg in (DARK, LIGHT):
            row = np.zeros((tile, width, 3), np.uint8)
            row[:] = bg
            for k, i in enumerate(idx):
                row[:, k * tile : (k + 1) * tile] = flame_tile(seq, i, bg, tile)
            rows.append(row)
        bands.append(np.vstack([_label(_caption(seq), width), *rows, np.full((1, width, 3), 255, np.uint8)]))
    return np.vstack(bands)


def write_preview(seqs: Sequence[SpriteSequence], path: Path, shown: int = 8, tile: int = 96) -> Path:
    """Write :func:`preview_sheet` of ``seqs`` as a PNG at ``path``; returns ``path``."""
    write_png(path, preview_sheet(seqs, shown, tile))
    return path

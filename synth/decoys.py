"""Decoy pastes: patches of the background pasted elsewhere on it with a flame's silhouette and the blend
treatment flames get (:mod:`synth.blend`, :mod:`synth.harmonise`), and no box. With them, a paste's edge, halo,
tint, blur or grain says nothing about whether a region holds fire.

A decoy is a :class:`synth.composite.Placement` whose sprite holds the patch as its ``over`` layer (alpha = the
silhouette of a random library flame's mask, slightly dilated), no emission and an empty flame mask. Frames: image
pixels, row 0 at the top; boxes [x, y, w, h]. Randomness only through the explicit ``rng``.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.blend import BlendConfig, margin, sample_style
from synth.composite import Placement
from synth.distractors import overlaps
from synth.sprites import Sprite, SpriteSequence

DECOY_HEIGHT = (0.08, 0.35)  # decoy height, fraction of the image height


def silhouette(mask: NDArray[np.bool_], width: int, height: int) -> NDArray[np.uint8]:
    """(height, width) uint8 alpha (0 or 255) of a flame ``mask`` resized and dilated by 1 px."""
    resized = cv2.resize(mask.astype(np.uint8) * 255, (width, height), interpolation=cv2.INTER_LINEAR) >= 128
    return cv2.dilate(resized.astype(np.uint8), np.ones((3, 3), np.uint8)) * np.uint8(255)


def make_decoy(
    cfg: BlendConfig, scene: NDArray[np.uint8], library: Sequence[SpriteSequence], rng: np.random.Generator
) -> Placement | None:
    """A decoy for the (H, W, 3) uint8 ``scene``: a patch of it (flipped half the time) shaped like a random library
    flame and placed at another random spot, with a blend mode drawn from ``cfg.modes`` and that mode's edge and
    look; None when the drawn flame has an empty mask."""
    h, w = scene.shape[:2]
    seq = library[int(rng.integers(len(library)))]
    mask = seq.sprites[int(rng.integers(len(seq.sprites)))].mask
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if not rows.size:
        return None
    mask = mask[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
    ph = min(max(int(h * rng.uniform(*DECOY_HEIGHT)), 8), h)
    pw = min(max(int(round(ph * mask.shape[1] / mask.shape[0])), 4), w)
    sx, sy = int(rng.integers(0, w - pw + 1)), int(rng.integers(0, h - ph + 1))
    patch = scene[sy : sy + ph, sx : sx + pw]
    if rng.random() < 0.5:
        patch = np.ascontiguousarray(patch[:, ::-1])
    over = np.concatenate([patch, silhouette(mask, pw, ph)[..., None]], axis=-1)
    sprite = Sprite(np.ascontiguousarray(over), np.zeros((ph, pw, 3), np.uint8), np.zeros((ph, pw), bool))
    x, y = int(rng.integers(-pw // 4, w - 3 * pw // 4 + 1)), int(rng.integers(-ph // 4, h - 3 * ph // 4 + 1))
    mode = str(cfg.modes[int(rng.integers(len(cfg.modes)))])
    edge, look = sample_style(cfg, mode, scene, (x, y, pw, ph), patch, rng)
    return Placement(sprite, x, y, pw, ph, mode, 0.0, 0.0, False, edge, look)


def footprint(p: Placement) -> list[int]:
    """[x, y, w, h] of every pixel a placement may change: its rect grown by its paste margin and softening."""
    m = max(margin(p.blend, p.edge), int(np.ceil(3.0 * p.look.soften)))
    return [p.x - m, p.y - m, p.width + 2 * m, p.height + 2 * m]


def plan_decoys(
    cfg: BlendConfig,
    scene: NDArray[np.uint8],
    library: Sequence[SpriteSequence],
    avoid: Sequence[Sequence[float]],
    rng: np.random.Generator,
    tries: int = 8,
) -> list[Placement]:
    """The decoys of one image: none for a ``1 - cfg.decoys`` share of images, else 1 or 2, each redrawn up to
    ``tries`` times until its :func:`footprint` overlaps none of ``avoid`` ([x, y, w, h]: flames, distractors)
    nor another decoy."""
    if rng.random() >= cfg.decoys:
        return []
    out: list[Placement] = []
    for _ in range(int(rng.integers(1, 3))):
        for _ in range(tries):
            d = make_decoy(cfg, scene, library, rng)
            if d is not None and not overlaps(footprint(d), [*avoid, *(footprint(o) for o in out)]):
                out.append(d)
                break
    return out

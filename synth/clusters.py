"""Fires of several flames side by side, boxed whole.

A simulated sequence is one plume, so a pool of them holds isolated candle-like flames, each boxed alone. The
fires of a real set are mostly burning regions — a row of tongues of different heights rising from one base — and
their annotators box such a region whole: on the common set a detector loses most of its AP50 to boxes that cover
part of a fire boxed whole or several fires at once (README, "Where the common AP50 is lost"), and the simulated
flames' boxes lack the real boxes' wide tail (w/h at the 90th percentile 1.07 against the train split's 1.27).

:func:`clustered_library` makes each sprite of a sequence a *fire* of 1 to ``max_flames`` flames: the sprite itself
(the tallest) and others of the same sequence (other frames, so other shapes), each scaled to a share of its
height (:data:`HEIGHTS`) and set beside it on the same base line, alternately left and right, each
:data:`SPACING` of the main flame's width farther out. The layers are merged — emission by the brightest value,
smoke laid over, flame masks joined — into one sprite, so the compositor, visibility check and boxes treat the fire
as one flame with one box.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from curate.core.imageio import unit_to_u8
from synth.composite import scaled_layers
from synth.sprites import Sprite, SpriteSequence, flame_rect

#: Heights of the other flames of a fire, share of the main flame's height (uniform).
HEIGHTS = (0.4, 0.95)
#: Distance between neighbouring flames' centres on one side, share of the main flame's width (uniform).
SPACING = (0.35, 0.7)


def merged_fire(flames: Sequence[Sprite], heights: Sequence[float], offsets: Sequence[float]) -> Sprite:
    """One sprite of ``flames`` (the first the main one; ``heights`` and ``offsets`` per flame, the first 1 and 0):
    flame k scaled so its flame mask is ``heights[k]`` x the main flame's high, its flame's centre
    ``offsets[k]`` x the main flame's width right of the main one's (negative: left), the bottoms of all flame masks
    on one row. Emission: per-pixel maximum; smoke (``over``): laid over in order; mask: union."""
    c0, r0, c1, r1 = flame_rect(flames[0])
    main_w, main_h = c1 - c0 + 1, r1 - r0 + 1
    main_cx, base = (c0 + c1 + 1) / 2.0, r1 + 1
    placed = []
    for sprite, height, offset in zip(flames, heights, offsets, strict=True):
        f0, g0, f1, g1 = flame_rect(sprite)
        scale = height * main_h / (g1 - g0 + 1)
        w, h = max(int(round(sprite.size[0] * scale)), 1), max(int(round(sprite.size[1] * scale)), 1)
        x = int(round(main_cx + offset * main_w - (f0 + f1 + 1) / 2.0 * scale))
        y = int(round(base - (g1 + 1) * scale))
        placed.append((x, y, scaled_layers(sprite, w, h)))
    x0, y0 = min(p[0] for p in placed), min(p[1] for p in placed)
    x1 = max(x + layers[2].shape[1] for x, _, layers in placed)
    y1 = max(y + layers[2].shape[0] for _, y, layers in placed)
    over = np.zeros((y1 - y0, x1 - x0, 4), np.float32)
    emission = np.zeros((y1 - y0, x1 - x0, 3), np.float32)
    mask = np.zeros((y1 - y0, x1 - x0), bool)
    for x, y, (o, e, m, _) in placed:
        cut = (slice(y - y0, y - y0 + m.shape[0]), slice(x - x0, x - x0 + m.shape[1]))
        over[cut] = _over(o, over[cut])
        np.maximum(emission[cut], e, out=emission[cut])
        mask[cut] |= m
    return Sprite(_bytes(over), _bytes(emission), mask)


def _over(top: NDArray[np.float32], below: NDArray[np.float32]) -> NDArray[np.float32]:
    """Straight-alpha RGBA ``top`` laid over ``below`` (both (h, w, 4) float in [0, 1])."""
    a, b = top[..., 3:4], below[..., 3:4]
    out_a = a + b * (1.0 - a)
    rgb = (top[..., :3] * a + below[..., :3] * b * (1.0 - a)) / np.maximum(out_a, 1e-6)
    return np.concatenate([rgb, out_a], axis=-1)


def _bytes(layer: NDArray[np.float32]) -> NDArray[np.uint8]:
    return unit_to_u8(layer)


def clustered_sequence(seq: SpriteSequence, max_flames: int, rng: np.random.Generator) -> SpriteSequence:
    """``seq`` with each sprite made a fire of 1..``max_flames`` flames (uniform; :func:`merged_fire`), the others
    drawn from ``seq``'s sprites, their heights in :data:`HEIGHTS`, spacing in :data:`SPACING`, first side random;
    a fire of one flame is the sprite itself. Draws from ``rng`` in sprite order."""
    fires = []
    for sprite in seq.sprites:
        n = int(rng.integers(1, max_flames + 1))
        others = [seq.sprites[int(rng.integers(len(seq.sprites)))] for _ in range(n - 1)]
        heights = [1.0] + [float(rng.uniform(*HEIGHTS)) for _ in others]
        side, reach, offsets = (1.0 if rng.random() < 0.5 else -1.0), {1.0: 0.0, -1.0: 0.0}, [0.0]
        for _ in others:
            reach[side] += float(rng.uniform(*SPACING))
            offsets.append(side * reach[side])
            side = -side
        fires.append(sprite if n == 1 else merged_fire([sprite, *others], heights, offsets))
    return replace(seq, sprites=tuple(fires))


def clustered_library(seqs: Sequence[SpriteSequence], max_flames: int, seed: int) -> list[SpriteSequence]:
    """Every sequence of ``seqs`` clustered (:func:`clustered_sequence`), sequence k from
    ``default_rng([seed, 7, k])``; ``max_flames`` 1 returns them as they are."""
    if max_flames <= 1:
        return list(seqs)
    return [clustered_sequence(s, max_flames, np.random.default_rng([seed, 7, k])) for k, s in enumerate(seqs)]

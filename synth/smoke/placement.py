"""Where a plume goes in a Method 2 image, how big, and in what colour and light.

- **Above a flame** (``smoke.above`` of the flames): the plume's source sits a third of the way down from the top
  of the flame's visible body, so the smoke rises out of its tips; it is 2-4 times the flame's width (a plume's
  source is its narrow lower part) and keeps its sprite's shape. It is laid before the flames, which stay in front of their own smoke.
- **Alone** (probability ``smoke.alone`` per image): smouldering, or a distant fire whose flames do not show. When
  the view has sky (:func:`ground.image.sky.sky_mask`, at least :data:`MIN_SKY` of the image) a share ``smoke.sky``
  of them rise into it from the sky's lower edge at a random column (a plume over a ridge or a roof), 15-45 % of
  the image wide; the others stand on a ground pixel (depth > 0), ``smoke.height_m`` high at that depth.
- **Never over a labelled object**: on a labelled frame no plume's box overlaps the frame's own smoke or fire boxes
  (``avoid``). A pasted plume is boxed where a viewer sees it, a frame's smoke where its annotator drew it (often a
  haze across half the frame): a plume inside that box would label one smoke twice, in two ways; a plume over a
  labelled fire would hide the fire its box still claims. A plume above a flame that would overlap one is not laid;
  a lone plume's spot is drawn again, up to :data:`TRIES` times.
- **Colour**: white steam (weight 0.35, grey level 0.85-1.0), grey smoke (0.4, 0.45-0.75) or black soot (0.25,
  0.08-0.3) for a simulated plume (:data:`FAMILIES`); a matted plume keeps its own colour. Either is **lit by the
  scene**: multiplied by ``clip(0.35 + 1.3 L, 0.35, 1)``, ``L`` the mean luma (0..1) of the background under it, and
  tinted a fifth of the way towards that background's mean colour (dark in a dark frame, warm under warm light).

Every draw comes from the rng the caller gives (Method 2: its own ``default_rng([seed, 2, i, 3])``, so turning
smoke on keeps every flame's draws).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ground.data.boxes import xywh_overlaps_any
from ground.image.imageio import unit_to_u8
from ground.image.sky import sky_mask
from synth.compose.composite import Placement
from synth.compose.light import REC601
from synth.flames.sprites import Sprite, SpriteSequence, mask_span
from synth.smoke.library import SmokeConfig

#: Smoke colours of a simulated plume: (name, weight, grey level range).
FAMILIES: tuple[tuple[str, float, tuple[float, float]], ...] = (
    ("white", 0.35, (0.85, 1.0)),
    ("grey", 0.4, (0.45, 0.75)),
    ("black", 0.25, (0.08, 0.3)),
)
MIN_SKY = 0.05  # share of the image that must be sky for a plume to rise into it
TRIES = 10  # draws of a lone plume's spot clear of a frame's labelled boxes
#: Version of the placement rules beyond SmokeConfig's keys, in the identity of every cached pool that lays plumes
#: (fuzzyfire.stages.synth_stage): 2 = no plume over a labelled frame's smoke; 3 = nor over its fire.
RULES_VERSION = 3


@dataclass(frozen=True)
class Plume:
    """A planned plume: its placement, the name of its sprite (``sequence/frame``), ``where`` (above, ground, sky)
    and ``colour`` (a family of :data:`FAMILIES`, or ``own`` for a matte)."""

    placement: Placement
    name: str
    where: str
    colour: str

    def record(self) -> dict:
        return {"plume": self.name, "where": self.where, "colour": self.colour}


def lit(sprite: Sprite, grey: float | None, background: NDArray[np.uint8], rect: Sequence[int]) -> Sprite:
    """``sprite`` (its ``over`` RGB a shading, or a matte's own colour when ``grey`` is None) coloured ``grey`` and
    lit by the (H, W, 3) uint8 ``background`` under ``rect`` (x, y, w, h px; module docstring)."""
    x, y, w, h = (int(v) for v in rect)
    height, width = background.shape[:2]
    under = background[max(y, 0) : min(y + h, height), max(x, 0) : min(x + w, width)]
    mean = under.reshape(-1, 3).mean(axis=0) / 255.0 if under.size else np.full(3, 0.5)
    light = float(np.clip(0.35 + 1.3 * float(mean @ REC601), 0.35, 1.0))
    tint = 0.8 + 0.2 * mean / max(float(mean.mean()), 1e-3)
    rgb = sprite.over[..., :3].astype(np.float32) / 255.0 * (grey if grey is not None else 1.0)
    over = np.dstack([unit_to_u8(np.clip(rgb * light * tint, 0.0, 1.0)), sprite.over[..., 3]])
    return replace(sprite, over=over)


def smoke_placement(sprite: Sprite, rect: Sequence[int]) -> Placement:
    """``sprite`` laid over at ``rect`` (x, y, w, h px): no light of its own, no glow, no cast."""
    return Placement(sprite, *(int(v) for v in rect), "screen", 0.0, 0.0, False)


def _draw_colour(rng: np.random.Generator) -> tuple[str, float]:
    weights = np.array([f[1] for f in FAMILIES])
    name, _, (lo, hi) = FAMILIES[int(rng.choice(len(FAMILIES), p=weights / weights.sum()))]
    return name, float(rng.uniform(lo, hi))


def _draw_sprite(plumes: Sequence[SpriteSequence], rng: np.random.Generator) -> tuple[Sprite, str, bool]:
    seq = plumes[int(rng.integers(len(plumes)))]
    frame = int(rng.integers(len(seq.sprites)))
    return seq.sprites[frame], f"{seq.name}/{frame}", seq.meta.get("generator") == "plume"


def _plume(sprite: Sprite, rect: list[int], simulated: bool, background, name: str, where: str, rng) -> Plume:
    colour, grey = _draw_colour(rng) if simulated else ("own", None)
    return Plume(smoke_placement(lit(sprite, grey, background, rect), rect), name, where, colour)


def plan_plumes(
    cfg: SmokeConfig,
    plumes: Sequence[SpriteSequence],
    flames: Sequence[Placement],
    background: NDArray[np.uint8],
    depth: NDArray[np.float32],
    fy: float,
    rng: np.random.Generator,
    avoid: Sequence[Sequence[int]] = (),
) -> list[Plume]:
    """The plumes of one image (module docstring): one above each of ``flames`` drawn at ``cfg.above``, then one
    alone at ``cfg.alone``; ``background`` (H, W, 3) uint8 the scene as exposed, ``depth`` (H, W) metres (0 off the
    ground), ``fy`` the focal length in pixels, ``avoid`` a labelled frame's fire and smoke boxes [x, y, w, h] px
    that no plume's box may overlap. None without ``plumes``."""
    if not plumes or not cfg.plumes:
        return []
    out = []
    for f in flames:
        if rng.random() >= cfg.above:
            continue
        span = mask_span(f.sprite)
        if span is None:
            continue
        sx, sy = f.width / f.sprite.size[0], f.height / f.sprite.size[1]
        fx0, fy0, fx1, fy1 = f.x + span[0] * sx, f.y + span[1] * sy, f.x + (span[2] + 1) * sx, f.y + (span[3] + 1) * sy
        sprite, name, simulated = _draw_sprite(plumes, rng)
        w = max(int((fx1 - fx0) * rng.uniform(2.0, 4.0)), 8)
        h = max(int(w * sprite.size[1] / sprite.size[0]), 8)
        base = fy0 + (fy1 - fy0) / 3.0
        rect = [int((fx0 + fx1) / 2 - w / 2), int(base - h), w, h]
        if not xywh_overlaps_any(rect, avoid):
            out.append(_plume(sprite, rect, simulated, background, name, "above", rng))
    if rng.random() < cfg.alone:
        sprite, name, simulated = _draw_sprite(plumes, rng)
        spot = _lone_spot(cfg, sprite.size[1] / sprite.size[0], background, depth, fy, avoid, rng)
        if spot is not None:
            out.append(_plume(sprite, spot[0], simulated, background, name, spot[1], rng))
    return out


def _lone_spot(
    cfg: SmokeConfig,
    aspect: float,
    background: NDArray[np.uint8],
    depth: NDArray[np.float32],
    fy: float,
    avoid: Sequence[Sequence[int]],
    rng: np.random.Generator,
) -> tuple[list[int], str] | None:
    """(rect [x, y, w, h] px, where: sky or ground) of a lone plume ``aspect`` (height / width) high, clear of
    ``avoid`` (drawn again up to :data:`TRIES` times), or None (no ground, or no clear spot)."""
    sky = sky_mask(background)
    if sky.mean() >= MIN_SKY and rng.random() < cfg.sky:
        where, draw = "sky", lambda: _sky_rect(sky, aspect, rng)
    elif len(ground := np.flatnonzero(depth > 0)):
        where, draw = "ground", lambda: _ground_rect(ground, depth, fy, cfg.height_m, aspect, rng)
    else:
        return None
    for _ in range(TRIES):
        rect = draw()
        if not xywh_overlaps_any(rect, avoid):
            return rect, where
    return None


def _sky_rect(sky: NDArray[np.bool_], aspect: float, rng: np.random.Generator) -> list[int]:
    """A plume's rect [x, y, w, h] px rising into ``sky`` (H, W) bool from its lower edge at a random column, 15-45 %
    of the image wide, ``aspect`` (height / width) high."""
    cols = np.flatnonzero(sky.any(axis=0))
    col = int(cols[rng.integers(len(cols))])
    edge = int(np.flatnonzero(sky[:, col])[-1])  # the sky's lower edge in that column
    w = max(int(sky.shape[1] * rng.uniform(0.15, 0.45)), 8)
    h = max(int(w * aspect), 8)
    return [col - w // 2, edge + h // 20 - h, w, h]


def _ground_rect(
    ground: NDArray[np.intp],
    depth: NDArray[np.float32],
    fy: float,
    height_m: tuple[float, float],
    aspect: float,
    rng: np.random.Generator,
) -> list[int]:
    """A plume's rect [x, y, w, h] px standing on a random pixel of ``ground`` (flat indices into ``depth`` (H, W)
    metres), ``height_m`` [lo, hi] metres high at its depth (``fy`` px focal length), 24 px to 0.8 of the image."""
    height, width = depth.shape
    row, col = divmod(int(ground[rng.integers(len(ground))]), width)
    h = int(np.clip(fy * rng.uniform(*height_m) / float(depth[row, col]), 24, 0.8 * height))
    w = max(int(h / aspect), 8)
    return [col - w // 2, row - h, w, h]

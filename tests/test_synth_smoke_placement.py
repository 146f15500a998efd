"""Plume placement: a plume rises from its flame's tips, a lone plume rises into the sky from its lower edge or stands
on the ground, every plume is lit by its scene, and the same rng places the same plumes."""

from __future__ import annotations

import numpy as np

from synth.compose.composite import Placement
from synth.flames.sprites import Sprite, SpriteSequence
from synth.smoke.library import SmokeConfig
from synth.smoke.placement import lit, plan_plumes, smoke_placement
from synth.smoke.plume import plume_library

PLUMES = plume_library(2, seed=0, frames=2)


def _flame(x: int, y: int, w: int, h: int) -> Placement:
    """A placement of a sprite whose flame fills its lower half (its top at y + h / 2)."""
    mask = np.zeros((20, 10), bool)
    mask[10:] = True
    sprite = Sprite(np.zeros((20, 10, 4), np.uint8), np.zeros((20, 10, 3), np.uint8), mask)
    return Placement(sprite, x, y, w, h)


def test_a_plume_rises_out_of_its_flames_tips() -> None:
    scene = np.full((200, 300, 3), 120, np.uint8)
    depth = np.full((200, 300), 5.0, np.float32)
    flame = _flame(100, 60, 20, 80)  # flame body x 100-120, y 100-140
    plumes = plan_plumes(SmokeConfig(above=1.0), PLUMES, [flame], scene, depth, 300.0, np.random.default_rng(0))
    assert len(plumes) == 1 and plumes[0].where == "above" and plumes[0].colour in ("white", "grey", "black")
    p = plumes[0].placement
    assert 40 <= p.width <= 80 and abs(p.x + p.width / 2 - 110) <= 1  # 2-4 flame widths, centred on it
    assert abs(p.y + p.height - (100 + 40 / 3)) <= 1  # its source a third of the way down the flame's body
    assert p.glow == 0.0 and p.opacity == 0.0 and not p.cast and p.sprite.smoke  # laid over: no light of its own


def test_a_lone_plume_rises_into_the_sky_or_stands_on_the_ground() -> None:
    scene = np.zeros((120, 160, 3), np.uint8)
    scene[:50] = (120, 170, 230)  # a clear blue sky above row 50
    scene[50:] = np.random.default_rng(1).integers(0, 255, (70, 160, 3))  # textured ground
    depth = np.zeros((120, 160), np.float32)
    depth[60:] = 8.0
    where = set()
    for seed in range(12):
        for q in plan_plumes(SmokeConfig(alone=1.0), PLUMES, [], scene, depth, 150.0, np.random.default_rng(seed)):
            p = q.placement
            where.add(q.where)
            if q.where == "sky":
                assert 44 <= p.y + p.height - p.height // 20 <= 50  # its base on the sky's lower edge (row 49)
            else:
                assert q.where == "ground" and 60 <= p.y + p.height < 120  # standing on a ground pixel
    assert where == {"sky", "ground"}


def test_plumes_are_lit_by_their_scene_and_placed_reproducibly() -> None:
    sprite = PLUMES[0].sprites[0]
    dark, bright = np.full((100, 100, 3), 15, np.uint8), np.full((100, 100, 3), 200, np.uint8)
    rect = [10, 10, 60, 80]
    shade = [lit(sprite, 1.0, bg, rect).over[..., :3][sprite.over[..., 3] > 60].mean() for bg in (dark, bright)]
    assert shade[0] < 0.6 * shade[1]  # white smoke in a dark frame is dim
    assert np.array_equal(lit(sprite, 1.0, bright, rect).over[..., 3], sprite.over[..., 3])  # alpha kept
    scene, depth = np.full((80, 80, 3), 90, np.uint8), np.full((80, 80), 4.0, np.float32)
    args = (SmokeConfig(above=0.5, alone=0.5), PLUMES, [_flame(30, 20, 10, 40)], scene, depth, 100.0)
    a, b = (plan_plumes(*args, np.random.default_rng(5)) for _ in range(2))
    assert [q.record() for q in a] == [q.record() for q in b] and [q.placement.x for q in a] == [
        q.placement.x for q in b
    ]
    assert plan_plumes(SmokeConfig(), *args[1:], np.random.default_rng(5)) == []  # no plumes asked: none
    assert smoke_placement(sprite, rect).width == 60


def test_no_plume_is_laid_over_a_frames_labelled_smoke() -> None:
    scene = np.zeros((120, 160, 3), np.uint8)
    scene[:50] = (120, 170, 230)
    scene[50:] = np.random.default_rng(1).integers(0, 255, (70, 160, 3))
    depth = np.zeros((120, 160), np.float32)
    depth[60:] = 8.0
    haze = [[0, 0, 90, 120]]  # an annotator's smoke box over the left of the frame
    flame = _flame(20, 40, 20, 60)  # a flame inside it: its plume would be too
    cfg, laid, free = SmokeConfig(above=1.0, alone=1.0), 0, 0
    for seed in range(12):
        rng, again = np.random.default_rng(seed), np.random.default_rng(seed)
        for q in plan_plumes(cfg, PLUMES, [flame], scene, depth, 150.0, rng, haze):
            p = q.placement
            assert q.where != "above" and p.x >= 90  # clear of the box: right of it
            laid += 1
        free += len(plan_plumes(cfg, PLUMES, [flame], scene, depth, 150.0, again))
    assert laid >= 6 and free >= laid + 12  # lone plumes still found a spot; without the box every flame got one
    covered = [[0, 0, 160, 120]]  # smoke over the whole frame: no room for a plume
    assert plan_plumes(cfg, PLUMES, [flame], scene, depth, 150.0, np.random.default_rng(0), covered) == []


def _matte_library() -> list[SpriteSequence]:
    """One light-grey matted plume (luma 0.7, textured), as synth.smoke.matte makes them."""
    rgb = np.clip(np.random.default_rng(2).normal(178, 20, (40, 30, 3)), 0, 255).astype(np.uint8)
    over = np.dstack([rgb, np.full((40, 30), 200, np.uint8)])
    sprite = Sprite(over, np.zeros((40, 30, 3), np.uint8), np.zeros((40, 30), bool), smoke=True)
    return [SpriteSequence("smoke-000", (sprite,), {"kind": "smoke"})]


def test_a_matted_plume_keeps_its_own_colour_only_lit_by_its_scene() -> None:
    own = _matte_library()
    scene, depth = np.full((120, 160, 3), 90, np.uint8), np.full((120, 160), 6.0, np.float32)
    (kept,) = plan_plumes(SmokeConfig(alone=1.0), own, [], scene, depth, 150.0, np.random.default_rng(3))
    p = kept.placement
    assert kept.colour == "own"
    assert np.array_equal(p.sprite.over, lit(own[0].sprites[0], None, scene, [p.x, p.y, p.width, p.height]).over)

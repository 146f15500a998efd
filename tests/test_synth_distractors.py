"""Distractors: every kind draws something that is not a flame, never over the boxes it avoids, the sun only
in open blue sky above the horizon, the same seed the same pixels."""

from __future__ import annotations

import numpy as np
import pytest

from synth.distractors import (
    ALL_KINDS,
    DRAWERS,
    KINDS,
    OUTDOOR_KINDS,
    PHOTO_KIND,
    PHOTO_KINDS,
    PHOTO_SCALE,
    DistractorConfig,
    draw_distractors,
    draw_sun,
    horizon_row,
    kinds_here,
    make_distractor,
    overlaps,
    plan_distractors,
)


def _outdoor(h=96, w=128, horizon=40):
    """Blue sky above row ``horizon``, textured green ground below; depth 5 m on the ground."""
    rng = np.random.default_rng(0)
    img = np.empty((h, w, 3), np.uint8)
    img[:horizon] = (110, 160, 230)
    img[horizon:] = np.clip(rng.normal((70, 120, 50), 25, (h - horizon, w, 3)), 0, 255).astype(np.uint8)
    depth = np.zeros((h, w), np.float32)
    depth[horizon + 2 :] = 5.0
    return img, depth


def test_config_rejects_bad_values():
    for bad in ({"share": -0.1}, {"max": 0}, {"kinds": ("lamp", "dragon")}, {"kinds": ()}):
        with pytest.raises(ValueError, match="distractors"):
            DistractorConfig(**bad)


@pytest.mark.parametrize("kind", sorted(DRAWERS))
def test_every_kind_draws_something_that_is_no_flame_and_repeats_per_seed(kind):
    img, depth = _outdoor()
    one = make_distractor(kind, img, depth, 100.0, 40.0, np.random.default_rng(3))
    two = make_distractor(kind, img, depth, 100.0, 40.0, np.random.default_rng(3))
    assert one is not None and not one.sprite.mask.any()
    assert one.sprite.over[..., 3].any() or one.sprite.emission.any()
    assert one.box == two.box and np.array_equal(one.sprite.over, two.sprite.over)
    assert np.array_equal(one.sprite.emission, two.sprite.emission)


def test_sun_stands_above_the_horizon_only_under_open_blue_sky():
    img, _ = _outdoor()
    for seed in range(5):
        rgb, alpha, light = draw_sun(img, 40.0, np.random.default_rng(seed))
        brightest = np.unravel_index(np.argmax(light.max(axis=-1)), light.shape[:2])
        assert brightest[0] < 40 and alpha[42:].max() < 0.05  # the disc above the horizon, no tint on the ground
    ceiling = img.copy()
    ceiling[:40] = 235  # a white ceiling, not a sky
    assert draw_sun(ceiling, 40.0, np.random.default_rng(0)) is None
    assert draw_sun(img, 5.0, np.random.default_rng(0)) is None  # no room for the disc


def test_horizon_from_photo_panorama_and_render_metadata():
    assert horizon_row({"horizon": 0.25}, 400, 300.0) == 100.0
    assert horizon_row({"pitch": 0.0}, 400, 300.0) == 200.0
    assert horizon_row({"pitch": -20.0}, 400, 300.0) < 200.0  # looking down: the horizon moves up
    level = np.eye(4).tolist()  # looking along -z, level
    assert horizon_row({"camera": {"pose": level, "yfov": 1.0}}, 400, 300.0) == pytest.approx(200.0)
    assert horizon_row({"camera": {"yfov": 1.0}}, 400, 300.0) is None


def test_plans_never_overlap_what_they_avoid_and_draw_nothing_elsewhere():
    img, depth = _outdoor()
    cfg = DistractorConfig(share=1.0, max=3)
    meta = {"horizon": 40 / 96}
    found = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        avoid = [[int(rng.integers(0, 100)), int(rng.integers(0, 70)), 20, 25] for _ in range(2)]
        items = plan_distractors(cfg, img, depth, meta, 100.0, avoid, rng)
        found += len(items)
        for k, d in enumerate(items):
            assert not overlaps(d.box, avoid) and not overlaps(d.box, [o.box for o in items[:k]])
            assert overlaps(d.box, [[0, 0, 128, 96]])
        drawn = draw_distractors(draw_distractors(img, items, False), items, True)
        changed = np.any(drawn != img, axis=-1)
        inside = np.zeros_like(changed)
        for d in items:
            x, y, w, h = d.box
            inside[max(y, 0) : y + h, max(x, 0) : x + w] = True
        assert not (changed & ~inside).any()
    assert found >= 20
    assert plan_distractors(DistractorConfig(), img, depth, meta, 100.0, [], np.random.default_rng(0)) == []


def test_rooms_get_no_outdoor_kinds():
    room = {"environment": "kitchen", "camera": {"pose": np.eye(4).tolist(), "yfov": 1.0}}
    assert set(kinds_here(KINDS, room)) == set(KINDS) - set(OUTDOOR_KINDS)
    assert kinds_here(KINDS, {**room, "kind": "street"}) == KINDS  # a kit street is outdoors
    assert kinds_here(KINDS, {"pitch": 0.0, "camera": {"yfov": 1.0}}) == KINDS  # a panorama view
    img, depth = _outdoor()
    cfg = DistractorConfig(share=1.0, max=3, kinds=("taillights",))
    assert plan_distractors(cfg, img, depth, room, 100.0, [], np.random.default_rng(0)) == []
    for seed in range(10):
        items = plan_distractors(
            DistractorConfig(share=1.0, max=3), img, depth, room, 100.0, [], np.random.default_rng(seed)
        )
        assert not {d.kind for d in items} & set(OUTDOOR_KINDS)


def test_kinds_cover_the_brief():
    assert set(KINDS) == set(DRAWERS) | {"sun"}


def _regions():
    """Two fire-like regions as :mod:`synth.photo_regions` cuts them: an orange disc and a red bar."""
    from synth.photo_regions import Region

    disc = np.zeros((20, 20, 4), np.uint8)
    disc[..., :3] = (230, 90, 30)
    disc[..., 3] = (np.hypot(*np.mgrid[-9.5:10:1, -9.5:10:1]) < 10) * 255  # touches its four sides
    bar = np.full((6, 30, 4), (200, 30, 20, 255), np.uint8)
    return (Region(disc, 0.25, "a.jpg"), Region(bar, 0.1, "b.jpg"))


def test_photo_regions_are_pasted_whole_inside_the_image_at_their_share_of_its_height_and_repeat_per_seed():
    img, depth = _outdoor()
    regions = _regions()
    heights = {0.25: [], 0.1: []}
    for seed in range(30):
        one = make_distractor(PHOTO_KIND, img, depth, 100.0, 40.0, np.random.default_rng(seed), regions)
        two = make_distractor(PHOTO_KIND, img, depth, 100.0, 40.0, np.random.default_rng(seed), regions)
        assert one is not None and one.kind == PHOTO_KIND and not one.emissive and not one.sprite.mask.any()
        assert one.box == two.box and np.array_equal(one.sprite.over, two.sprite.over)
        assert not one.sprite.emission.any() and one.sprite.over[..., 3].max() == 255
        x, y, w, h = one.box
        assert 0 <= x and x + w <= 128 and 0 <= y and y + h <= 96
        red = one.sprite.over[..., 0].astype(int) - one.sprite.over[..., 2]
        heights[0.25 if red.max() == 200 else 0.1].append(h)  # the disc: 230 - 30, the bar: 200 - 20
    for share, hs in heights.items():
        assert hs and all(max(8, share * 96 * PHOTO_SCALE[0]) - 1 <= h <= share * 96 * PHOTO_SCALE[1] + 1 for h in hs)
    assert make_distractor(PHOTO_KIND, img, depth, 100.0, 40.0, np.random.default_rng(0)) is None  # no regions


def test_photo_kind_is_opt_in_and_planned_only_from_regions():
    assert not set(PHOTO_KINDS) & set(KINDS) and set(ALL_KINDS) == {*KINDS, *PHOTO_KINDS} and PHOTO_KIND in PHOTO_KINDS
    assert DistractorConfig(share=0.5, kinds=(PHOTO_KIND,)).photo and not DistractorConfig(share=0.5).photo
    assert not DistractorConfig(share=0.0, kinds=(PHOTO_KIND,)).photo
    assert DistractorConfig(share=0.5, kinds=("lights", "lamp", "photo")).photo_kinds == ("photo", "lights")
    assert DistractorConfig(share=0.0, kinds=("lights",)).photo_kinds == ()
    img, depth = _outdoor()
    cfg = DistractorConfig(share=1.0, max=2, kinds=(PHOTO_KIND,))
    avoid = [[40, 30, 30, 30]]
    found = 0
    for seed in range(10):
        items = plan_distractors(cfg, img, depth, {}, 100.0, avoid, np.random.default_rng(seed), regions=_regions())
        found += len(items)
        assert all(d.kind == PHOTO_KIND and not overlaps(d.box, avoid) for d in items)
    assert found >= 10
    assert plan_distractors(cfg, img, depth, {}, 100.0, [], np.random.default_rng(0)) == []


def test_each_photo_kind_is_cut_only_from_the_regions_of_its_rule():
    from synth.photo_regions import Region

    img, depth = _outdoor()
    glow = np.zeros((16, 16, 4), np.uint8)
    glow[..., :3], glow[..., 3] = (255, 250, 240), 255
    regions = (*_regions(), Region(glow, 0.2, "lamp.jpg", "lights"))
    for seed in range(20):
        light = make_distractor("lights", img, depth, 100.0, 40.0, np.random.default_rng(seed), regions)
        photo = make_distractor(PHOTO_KIND, img, depth, 100.0, 40.0, np.random.default_rng(seed), regions)
        assert light is not None and light.kind == "lights" and light.photo == "lamp.jpg" and not light.emissive
        assert photo is not None and photo.kind == PHOTO_KIND and photo.photo in ("a.jpg", "b.jpg")
        assert light.to_json()["kind"] == "lights"
    assert make_distractor("lights", img, depth, 100.0, 40.0, np.random.default_rng(0), _regions()) is None
    only_photo = make_distractor(PHOTO_KIND, img, depth, 100.0, 40.0, np.random.default_rng(3), _regions())
    mixed = make_distractor(PHOTO_KIND, img, depth, 100.0, 40.0, np.random.default_rng(3), regions)
    assert only_photo is not None and mixed is not None and only_photo.box == mixed.box  # lights never change photo

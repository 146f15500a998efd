"""Compositing: visible flame and smoke masks after clipping and occlusion by later sprites."""

from __future__ import annotations

import numpy as np
import pytest

from ground.data.boxes import mask_to_xywh
from synth.compose.composite import Placement, composite
from synth.flames.sprites import SMOKE_ALPHA, Sprite


def _flame(h=10, w=10, value=200):
    return Sprite(np.zeros((h, w, 4), np.uint8), np.full((h, w, 3), value, np.uint8), np.ones((h, w), bool))


def _smoky(h=20, w=10):
    """Flame in the bottom half; smoke above: rows 0-4 faint (alpha below SMOKE_ALPHA), rows 5-9 dense."""
    over = np.zeros((h, w, 4), np.uint8)
    over[..., :3] = 70
    over[: h // 4, :, 3] = round(0.5 * SMOKE_ALPHA * 255)
    over[h // 4 : h // 2, :, 3] = 200
    emission = np.zeros((h, w, 3), np.uint8)
    emission[h // 2 :] = (255, 150, 30)
    mask = np.zeros((h, w), bool)
    mask[h // 2 :] = True
    return Sprite(over, emission, mask)


def test_occluded_flames_lose_their_hidden_pixels():
    bg = np.zeros((20, 30, 3), np.uint8)
    sprite = _flame()
    out = composite(
        bg, [Placement(sprite, 2, 2, 10, 10), Placement(sprite, 7, 2, 10, 10), Placement(sprite, 25, 15, 10, 10)]
    )
    masks = out.flames
    assert masks[0].sum() == 50 and masks[1].sum() == 100  # the second flame hides half of the first
    assert masks[2].sum() == 5 * 5  # truncated at the image border
    assert out.image[5, 4].max() > 150
    with pytest.raises(ValueError, match="blend"):
        Placement(sprite, 0, 0, 5, 5, blend="multiply")


def test_smoke_mask_is_dense_smoke_only():
    sprite = _smoky()
    assert np.array_equal(np.nonzero(sprite.smoke_mask().any(axis=1))[0], np.arange(5, 10))
    out = composite(np.zeros((40, 40, 3), np.uint8), [Placement(sprite, 10, 5, 10, 20, glow=0.0)])
    assert mask_to_xywh(out.smoke[0]).tolist() == [10, 10, 10, 5]
    assert mask_to_xywh(out.flames[0]).tolist() == [10, 15, 10, 10]
    assert not (out.smoke[0] & out.flames[0]).any()


def test_later_flames_hide_earlier_smoke():
    sprite = _smoky()
    out = composite(
        np.zeros((40, 40, 3), np.uint8), [Placement(sprite, 10, 5, 10, 20), Placement(_flame(), 15, 8, 10, 10)]
    )
    assert mask_to_xywh(out.smoke[0]).tolist() == [10, 10, 5, 5]
    assert out.smoke[1].sum() == 0


def test_bright_flames_outshine_bright_walls():
    sprite = _flame(value=0)
    sprite.emission[:] = (255, 150, 30)
    white = np.full((10, 10, 3), 255, np.uint8)
    lit = composite(white, [Placement(sprite, 0, 0, 10, 10, "screen", glow=0.0, opacity=1.0)]).image
    assert np.abs(lit[5, 5].astype(int) - (255, 150, 30)).max() <= 1  # the flame's colour, not white
    washed = composite(white, [Placement(sprite, 0, 0, 10, 10, "screen", glow=0.0, opacity=0.0)]).image
    assert washed[5, 5].min() == 255


def test_a_flame_casts_warm_light_around_its_base_outside_its_mask():
    sprite = _flame(value=0)
    sprite.emission[:] = (255, 150, 30)
    grey = np.full((80, 80, 3), 100, np.uint8)
    p = Placement(sprite, 35, 30, 10, 10, "screen", glow=0.5, opacity=0.8)
    lit = composite(grey, [p])
    dark = composite(grey, [Placement(sprite, 35, 30, 10, 10, "screen", glow=0.0, opacity=0.8)])
    below = lit.image[50, 40].astype(int)  # on the floor under the flame, outside the sprite and its glow ring
    assert below[0] > 110 and below[0] > below[1] > below[2] >= 100  # warmer, red most
    assert tuple(lit.image[2, 2]) == (100, 100, 100)  # far away: untouched
    assert np.array_equal(lit.flames[0], dark.flames[0])  # the light is never part of the box
    unlit = composite(grey, [Placement(sprite, 35, 30, 10, 10, "screen", glow=0.5, opacity=0.8, cast=False)])
    assert tuple(unlit.image[50, 40]) == (100, 100, 100)  # light: false


def test_a_bright_flame_body_hides_what_is_behind_it_and_a_dim_edge_does_not_darken_a_wall():
    from synth.compose.composite import OPAQUE_BRIGHTNESS, coverage

    assert coverage(np.float32(OPAQUE_BRIGHTNESS)) == 1.0 and coverage(np.float32(0.1)) == 0.0
    core = _flame(value=0)
    core.emission[:] = (255, 240, 150)  # a yellow-white core
    rng = np.random.default_rng(0)
    outs = [
        composite(rng.integers(0, 256, (10, 10, 3), dtype=np.uint8), [Placement(core, 0, 0, 10, 10, b, 0.0, 1.0)])
        for b in ("screen", "add")
        for _ in range(3)
    ]
    for out in outs:  # whatever the background, the core shows its own colour
        assert np.abs(out.image.astype(int) - (255, 240, 150)).max() <= 1
    edge = _flame(value=0)
    edge.emission[:] = (45, 8, 0)  # the dim red edge
    white = np.full((10, 10, 3), 230, np.uint8)
    lit = composite(white, [Placement(edge, 0, 0, 10, 10, "screen", 0.0, 1.0)]).image
    assert lit[5, 5, 0] >= 230 and lit[5, 5].astype(int).mean() >= 200  # reddened, not a dark outline


@pytest.mark.parametrize("blend", ["add", "screen"])
def test_never_darken_keeps_the_luma_behind_a_mid_bright_edge(blend: str) -> None:
    """An orange edge of brightness ~0.45 half-covers a pale wall and outlines it darker; capped, it reddens it."""
    from synth.compose.light import luma as rec709

    edge = _flame(value=0)
    edge.emission[:] = (115, 55, 10)  # orange, brightest channel 0.45: coverage ~0.75
    pale = np.full((10, 10, 3), 235, np.uint8)
    luma = lambda img: float(rec709(img.astype(np.float32) / 255.0).mean())  # noqa: E731
    outlined = composite(pale, [Placement(edge, 0, 0, 10, 10, blend, 0.0, 1.0)]).image
    kept = composite(pale, [Placement(edge, 0, 0, 10, 10, blend, 0.0, 1.0, never_darken=True)]).image
    assert luma(outlined) < luma(pale) - 0.2  # the outline: darker than the wall
    assert luma(kept) >= luma(pale) - 0.03  # (a channel clipped at 255 loses a little)
    assert kept[5, 5, 0] > kept[5, 5, 2]  # reddened
    core = _flame(value=0)
    core.emission[:] = (255, 240, 150)
    for never_darken in (False, True):  # a bright core still hides the wall behind it
        out = composite(pale, [Placement(core, 0, 0, 10, 10, blend, 0.0, 1.0, never_darken=never_darken)]).image
        assert np.abs(out.astype(int) - (255, 240, 150)).max() <= 1


def test_a_sprite_that_emits_nothing_keeps_the_bytes_of_a_blurred_zero_glow(monkeypatch) -> None:
    """An RGBA cut-out (no emission) skips the glow's blur: the same image as the glow before (the blur of the
    zero emission, added), screen and add, also for a sprite far larger than the image."""
    from dataclasses import replace

    import cv2

    import synth.compose.composite as C

    def blurred_glow(img, emission, p, cut):  # the glow as every pool before this change was made
        h, w = img.shape[:2]
        r = max(int(0.25 * max(p.width, p.height)), 2)
        canvas = np.zeros((p.height + 2 * r, p.width + 2 * r, 3), np.float32)
        canvas[r : r + p.height, r : r + p.width] = emission
        blurred = cv2.GaussianBlur(canvas, (0, 0), sigmaX=r / 2.5) * p.glow
        c = C._clip(replace(p, x=p.x - r, y=p.y - r, width=p.width + 2 * r, height=p.height + 2 * r), w, h)
        if c is not None:
            img[c[0], c[1]] = C._add_light(img[c[0], c[1]], blurred[c[2], c[3]], p.blend)

    rng = np.random.default_rng(4)
    background = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8)
    rgba = rng.integers(0, 256, (10, 6, 4), dtype=np.uint8)
    sprite = Sprite(rgba, np.zeros((10, 6, 3), np.uint8), rgba[..., 3] > 128)
    lit = Sprite(rgba, rng.integers(0, 256, (10, 6, 3), dtype=np.uint8), rgba[..., 3] > 128)
    cases = [Placement(s, x, y, w, h, blend, 0.4, 1.0) for s in (sprite, lit) for blend in ("screen", "add")
             for x, y, w, h in ((20, 10, 12, 20), (-40, -200, 300, 500))]  # fmt: skip
    now = [composite(background, [p]).image for p in cases]
    monkeypatch.setattr(C, "_glow", blurred_glow)
    before = [composite(background, [p]).image for p in cases]
    assert all(np.array_equal(a, b) for a, b in zip(now, before, strict=True))
    assert not np.array_equal(now[-1], composite(background, [replace(cases[-1], glow=0.0)]).image)  # lit: a glow

"""synth.swap: a frame's fires erased only where they are, the swapped flame's mask box on the frame's box, and
the library frame shaped like the box and made of fire chosen."""

from __future__ import annotations

import numpy as np

from synth import swap as S
from synth.composite import Placement
from synth.cutouts import fire_mask
from synth.library import FlameLibraryConfig
from synth.method2 import mask_box
from synth.sprites import Sprite, SpriteSequence


def _scene(seed: int = 0) -> np.ndarray:
    """(96, 128, 3) uint8: a textured grey-blue scene with an orange fire blob at rows 30-60, columns 40-70."""
    rng = np.random.default_rng(seed)
    rgb = np.clip(rng.normal([90, 100, 120], 12, (96, 128, 3)), 0, 255).astype(np.uint8)
    yy, xx = np.mgrid[:96, :128]
    blob = ((yy - 45) / 15.0) ** 2 + ((xx - 55) / 15.0) ** 2 <= 1.0
    rgb[blob] = (250, 140, 30)
    return rgb


def _sprite(w: int, h: int, rect: tuple[int, int, int, int], colour: tuple[int, int, int]) -> Sprite:
    """A (h, w) cut-out-like sprite whose flame mask is ``rect`` (x0, y0, x1, y1 end exclusive) in ``colour``."""
    over = np.zeros((h, w, 4), np.uint8)
    mask = np.zeros((h, w), bool)
    x0, y0, x1, y1 = rect
    mask[y0:y1, x0:x1] = True
    over[mask] = (*colour, 255)
    return Sprite(over, np.zeros((h, w, 3), np.uint8), mask)


def test_erased_fills_in_the_fire_of_a_box_and_leaves_every_other_pixel():
    rgb = _scene()
    box = [40, 30, 31, 31]
    region = S.fire_region(rgb, [box])
    out = S.erased(rgb, [box])
    assert out.shape == rgb.shape and out.dtype == np.uint8 and out is not rgb
    assert np.array_equal(out[~region], rgb[~region])
    assert fire_mask(rgb[30:61, 40:71]).mean() > 0.6 and fire_mask(out[30:61, 40:71]).mean() < 0.02
    assert region[30:61, 40:71].mean() > 0.6 and not region[:, :25].any()  # the blob and its margin, not the scene


def test_a_box_without_fire_colours_is_erased_whole_and_no_box_leaves_the_image_as_it_is():
    rgb = _scene()
    region = S.fire_region(rgb, [[90, 5, 20, 15]])
    assert region[5:20, 90:110].all() and region.sum() == 20 * 15
    assert np.array_equal(S.erased(rgb, []), rgb)


def test_spanning_puts_the_flame_mask_box_on_the_frame_box():
    sprite = _sprite(40, 60, (10, 20, 30, 50), (255, 150, 20))
    for box in ([50, 30, 20, 30], [5, 40, 33, 17], [0, 0, 7, 9]):
        x, y, width, height = S.spanning(sprite, box)
        got = mask_box(Placement(sprite, x, y, width, height))
        assert all(abs(g - b) <= 1 for g, b in zip(got, box, strict=True)), (got, box)


def test_best_fit_takes_the_fire_coloured_flame_shaped_most_like_the_box():
    tall_fire = _sprite(30, 60, (5, 5, 25, 55), (255, 160, 30))  # 20 x 50: aspect 0.4
    wide_fire = _sprite(60, 30, (5, 5, 55, 25), (255, 160, 30))  # 50 x 20: aspect 2.5
    tall_wall = _sprite(30, 60, (5, 5, 25, 55), (120, 120, 130))  # shaped like the box, not fire
    library = [SpriteSequence(n, (s,), {}) for n, s in (("tall", tall_fire), ("wide", wide_fire), ("wall", tall_wall))]
    cfg = FlameLibraryConfig()
    assert S.fire_share(tall_fire) == 1.0 and S.fire_share(tall_wall) == 0.0
    fire_or_wall = [library[0], library[2]]  # the same shape: fire wins whenever drawn (each draw: 7 more)
    picks = [S.best_fit(fire_or_wall, cfg, 0.4, np.random.default_rng(k))[0].name for k in range(20)]
    assert set(picks) == {"tall"}
    shapes = library[:2]  # both fire: the nearer aspect wins
    assert {S.best_fit(shapes, cfg, 3.0, np.random.default_rng(k))[0].name for k in range(20)} == {"wide"}
    assert {S.best_fit(shapes, cfg, 0.3, np.random.default_rng(k))[0].name for k in range(20)} == {"tall"}
    only_walls = [library[2]]
    assert S.best_fit(only_walls, cfg, 0.4, np.random.default_rng(0))[0].name == "wall"  # none is fire: the best shape

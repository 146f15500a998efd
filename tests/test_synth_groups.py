"""Real fires of several boxes pasted whole: group index, placement geometry, and Method 2's plans."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from synth.composite import Placement
from synth.cutouts import Cutout, write_cutouts
from synth.groups import FIT, group_index, grouped
from synth.library import cutout_library


def _rgba(h: int, w: int, pad: int = 0) -> np.ndarray:
    """An (h, w, 4) cut-out whose flame fills it but for ``pad`` transparent pixels on each side."""
    rgba = np.zeros((h, w, 4), np.uint8)
    rgba[pad : h - pad, pad : w - pad] = (255, 170, 40, 255)
    return rgba


def _library(root: Path) -> list:
    """Cut-outs of two images: ``a.jpg`` with a 20x40 box at (100, 50) and a 10x20 one at (160, 70) (2 px margins),
    ``b.jpg`` with one box."""
    items = [
        Cutout(_rgba(40, 20, pad=2), "a.jpg", (100, 50, 20, 40), 1.0),
        Cutout(_rgba(30, 30), "b.jpg", (0, 0, 30, 30), 1.0),
        Cutout(_rgba(20, 10, pad=2), "a.jpg", (160, 70, 10, 20), 1.0),
    ]
    write_cutouts(iter(items), root)
    return cutout_library(root)


def test_cutouts_know_where_they_sat_and_which_share_an_image(tmp_path):
    library = _library(tmp_path / "cut")
    origins = library[0].meta["origins"]
    assert origins == (("a.jpg", 101, 51), ("b.jpg", 0, 0), ("a.jpg", 161, 71))  # box corner + 2 px margin - 1 px pad
    index = group_index(library)
    assert [m[0] for m in index["real-000/0"]] == ["real-000/0", "real-000/2"]
    assert index["real-000/0"] is index["real-000/2"] and [m[0] for m in index["real-000/1"]] == ["real-000/1"]
    assert cutout_library(tmp_path / "cut", canvas=True)[0].meta["origins"][0] == ("a.jpg", 100, 50)
    assert cutout_library(tmp_path / "cut", feather=0.2)[0].meta["origins"][2][0] == "a.jpg"


def _anchor(sprite, x: int, y: int, scale: float) -> Placement:
    w, h = sprite.size
    return Placement(sprite, x, y, round(w * scale), round(h * scale), "add", 0.4, 0.7)


def test_a_group_keeps_its_layout_and_sizes_at_the_anchors_scale(tmp_path):
    library = _library(tmp_path / "cut")
    index, (a, _, b) = group_index(library), library[0].sprites
    anchor = _anchor(a, 10, 20, 0.5)
    (first, n1), (other, n2) = grouped(anchor, "real-000/0", index, 416, 416)
    assert (first, n1) == (anchor, "real-000/0")  # small enough: the anchor stays as drawn
    assert n2 == "real-000/2" and other.sprite is b
    assert (other.x, other.y) == (10 + round(60 * 0.5), 20 + round(20 * 0.5))  # its offset in a.jpg, scaled
    assert (other.width, other.height) == (round(b.size[0] * 0.5), round(b.size[1] * 0.5))
    assert (other.blend, other.glow, other.opacity) == (anchor.blend, anchor.glow, anchor.opacity)
    assert grouped(_anchor(library[0].sprites[1], 5, 5, 2.0), "real-000/1", index, 416, 416) == [
        (_anchor(library[0].sprites[1], 5, 5, 2.0), "real-000/1")
    ]  # alone in its image: as drawn, even enlarged


def test_a_group_is_never_larger_than_in_its_image_nor_than_fits(tmp_path):
    library = _library(tmp_path / "cut")
    index, a = group_index(library), library[0].sprites[0]
    anchor = _anchor(a, 100, 100, 3.0)
    (first, _), (other, _) = grouped(anchor, "real-000/0", index, 416, 416)
    assert (first.width, first.height) == a.size  # back to its source pixels
    base = (anchor.x + anchor.width / 2, anchor.y + anchor.height)
    assert abs(first.x + first.width / 2 - base[0]) <= 1 and first.y + first.height == base[1]  # same base
    assert other.width == library[0].sprites[2].size[0]
    small = grouped(_anchor(a, 0, 0, 1.0), "real-000/0", index, 60, 60)  # the group spans 72 px: shrunk to FIT
    x0 = min(p.x for p, _ in small)
    x1 = max(p.x + p.width for p, _ in small)
    assert x1 - x0 <= FIT * 60 + 2
    gone = grouped(_anchor(a, 400, 10, 1.0), "real-000/0", index, 416, 416)
    assert [n for _, n in gone] == ["real-000/0"]  # the other member would lie right of the image


def test_method2_brings_each_cutouts_image_mates_and_keeps_its_other_draws(tmp_path):
    from dataclasses import replace

    from synth.library import FlameLibraryConfig
    from synth.method2 import Method2Config, plan_flames

    library = _library(tmp_path / "cut")
    depth = np.full((120, 160), 5.0, np.float32)
    flames = FlameLibraryConfig(source="cutouts")
    cfg = Method2Config(scenes=0, width=160, height=120, max_flames=3, negatives=0.0, frames=(tmp_path,), flames=flames)
    on = replace(cfg, flames=replace(flames, cutout_groups=True))

    def keys(plan):
        return [(name, p.x, p.y, p.width, p.height) for p, name in plan]

    index, mates = group_index(library), 0
    for seed in range(20):
        plain = plan_flames(cfg, library, depth, 1.0, np.random.default_rng(seed), avoid=[])
        both = plan_flames(on, library, depth, 1.0, np.random.default_rng(seed), avoid=[])
        expected = [m for p, name in plain for m in grouped(p, name, index, cfg.width, cfg.height)]
        assert keys(both) == keys(expected)  # each drawn flame, then its image mates: no other draw moved
        mates += len(both) - len(plain)
    assert mates > 5


def test_image_mates_keep_clear_of_what_a_view_keeps_clear(tmp_path):
    from dataclasses import replace

    from synth.distractors import overlaps
    from synth.library import FlameLibraryConfig
    from synth.method2 import Method2Config, mask_box, plan_flames

    library = _library(tmp_path / "cut")
    index, depth = group_index(library), np.full((120, 160), 5.0, np.float32)
    flames = FlameLibraryConfig(source="cutouts")
    cfg = Method2Config(scenes=0, width=160, height=120, max_flames=3, negatives=0.0, frames=(tmp_path,), flames=flames)
    on = replace(cfg, flames=replace(flames, cutout_groups=True))
    avoid, kept, dropped = [[100, 0, 60, 120]], 0, 0
    for seed in range(30):
        plain = plan_flames(cfg, library, depth, 1.0, np.random.default_rng(seed), avoid=avoid)
        both = plan_flames(on, library, depth, 1.0, np.random.default_rng(seed), avoid=avoid)
        expected = []
        for p, name in plain:
            first, *mates = grouped(p, name, index, cfg.width, cfg.height)
            clear = [m for m in mates if not overlaps(mask_box(m[0]), avoid)]
            expected += [first, *clear]
            kept, dropped = kept + len(clear), dropped + len(mates) - len(clear)
        assert [(n, p.x, p.y, p.width) for p, n in both] == [(n, p.x, p.y, p.width) for p, n in expected]
    assert kept and dropped  # both cases were met

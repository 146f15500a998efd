"""Decoy pastes: background patches in a flame's shape, never over what they avoid, never a flame mask."""

from __future__ import annotations

import numpy as np

from synth import flames as F
from synth.blend import BlendConfig
from synth.composite import composite
from synth.decoys import footprint, plan_decoys, silhouette
from synth.distractors import overlaps


def _library():
    p = F.FlameParams(rows=40, cols=28, frames=40, keep_every=20, warmup=30)
    return [F.generate_sequence("f0", p, np.random.default_rng(0))]


def test_silhouette_is_binary_and_sized():
    mask = np.zeros((10, 6), bool)
    mask[2:8, 1:5] = True
    out = silhouette(mask, 12, 20)
    assert out.shape == (20, 12) and set(np.unique(out)) <= {0, 255}


def test_decoys_avoid_boxes_hold_no_flame_and_repeat_per_seed():
    rng0 = np.random.default_rng(5)
    scene = np.clip(rng0.normal(120, 40, (90, 120, 3)), 0, 255).astype(np.uint8)
    library = _library()
    cfg = BlendConfig(modes=("alpha", "blur", "poisson", "screen"), harmonise=True, match_noise=True, decoys=1.0)
    avoid = [[40, 30, 25, 40]]
    total = 0
    for seed in range(8):
        decoys = plan_decoys(cfg, scene, library, avoid, np.random.default_rng(seed))
        again = plan_decoys(cfg, scene, library, avoid, np.random.default_rng(seed))
        total += len(decoys)
        out = composite(scene, decoys)
        assert all(not m.any() for m in out.flames) and all(not d.sprite.mask.any() for d in decoys)
        assert np.array_equal(out.image, composite(scene, again).image)
        for d in decoys:
            assert not overlaps(footprint(d), avoid)
        x, y, w, h = avoid[0]
        assert np.array_equal(out.image[y : y + h, x : x + w], scene[y : y + h, x : x + w])
    assert total >= 8
    assert plan_decoys(BlendConfig(), scene, library, [], np.random.default_rng(0)) == []

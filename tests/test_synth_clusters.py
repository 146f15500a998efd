"""synth.clusters: simulated flames grouped into fires on one base line, one mask each."""

from __future__ import annotations

import numpy as np
import pytest

from synth.clusters import HEIGHTS, clustered_library, clustered_sequence, merged_fire
from synth.sprites import Sprite, SpriteSequence, mask_span


def _flame(w: int, h: int, top: int = 6, value: int = 200) -> Sprite:
    """A w x h sprite: smoke over its top ``top`` rows, a flame (emission, mask) below."""
    over = np.zeros((h, w, 4), np.uint8)
    over[:top] = (90, 90, 90, 120)
    emission = np.zeros((h, w, 3), np.uint8)
    emission[top:] = (value, value // 2, 20)
    mask = np.zeros((h, w), bool)
    mask[top:] = True
    return Sprite(over, emission, mask)


def test_a_fire_stands_its_flames_on_one_base_beside_the_main_one() -> None:
    main, other = _flame(10, 46), _flame(20, 26, top=6, value=250)
    fire = merged_fire([main, other], [1.0, 0.5], [0.0, 1.5])
    c0, r0, c1, r1 = mask_span(fire)
    rows = np.flatnonzero(fire.mask.any(axis=1))
    assert r1 - r0 + 1 == 40  # the main flame keeps its height: the fire is as tall as its tallest flame
    cols = np.flatnonzero(fire.mask[r1])
    assert cols[0] == c0 and cols[-1] == c1  # every flame reaches the bottom row: one base line
    assert c1 - c0 + 1 > 10 and rows[-1] == r1
    right = fire.mask[:, c0 + 12 :]
    assert np.flatnonzero(right.any(axis=1))[0] > r0 + 15  # the side flame is half as high (20 of 40 px)
    assert fire.emission[r1, c1, 0] > 240 and fire.emission[r1, c0, 0] == 200  # emission: the brighter value
    assert fire.over[..., 3].max() > 0 and fire.mask.shape == fire.emission.shape[:2]  # smoke kept above


def test_clustered_sequences_keep_length_and_single_flames_as_they_are() -> None:
    seq = SpriteSequence("s", tuple(_flame(8 + k, 30) for k in range(6)), {"generator": "fluid"})
    assert clustered_library([seq], 1, 0) == [seq]
    fires = clustered_sequence(seq, 3, np.random.default_rng(0))
    assert len(fires.sprites) == 6 and fires.name == "s" and fires.meta == seq.meta
    widths = [f.size[0] for f in fires.sprites]
    assert any(f is s for f, s in zip(fires.sprites, seq.sprites))  # some fires are one flame, the sprite itself
    assert max(w / s.size[0] for w, s in zip(widths, seq.sprites)) > 1.3  # and some are wider: several flames
    again = clustered_library([seq], 3, 0)[0]
    assert all(np.array_equal(a.mask, b.mask) for a, b in zip(again.sprites, clustered_library([seq], 3, 0)[0].sprites))
    assert 0 < HEIGHTS[0] < HEIGHTS[1] < 1


def test_the_config_groups_only_simulated_flames() -> None:
    from synth.library import FlameLibraryConfig, build_library

    with pytest.raises(ValueError, match="flames.cluster"):
        FlameLibraryConfig(cluster=0)
    with pytest.raises(ValueError, match="source simulated or both"):
        FlameLibraryConfig(source="cutouts", cluster=3)
    cfg = FlameLibraryConfig(sequences=1, frames=24, keep_every=12, cluster=3)
    plain = build_library(FlameLibraryConfig(sequences=1, frames=24, keep_every=12))
    fires = build_library(cfg)
    assert [s.name for s in fires] == [s.name for s in plain] and len(fires[0].sprites) == len(plain[0].sprites)

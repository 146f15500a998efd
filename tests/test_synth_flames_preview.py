"""The flame library preview sheet: one band per sequence, frames over a dark and a light background."""

from __future__ import annotations

import numpy as np
import pytest

from synth.flames import preview as P
from synth.flames import simulate as F
from synth.flames.sprites import Sprite, SpriteSequence


def _seq(name: str, smoke: float, seed: int = 0) -> SpriteSequence:
    p = F.FlameParams(rows=40, cols=32, frames=60, keep_every=20, warmup=30, smoke=smoke, smoke_grey=0.1)
    return F.generate_sequence(name, p, np.random.default_rng(seed))


@pytest.mark.parametrize(("count", "shown"), [(1, 8), (3, 8), (8, 8), (9, 8), (50, 8), (50, 1)])
def test_frame_indices_are_spread_and_keep_the_ends(count, shown):
    idx = P.frame_indices(count, shown)
    assert len(idx) == min(count, shown) and idx == sorted(set(idx))
    assert idx[0] == 0 and (shown == 1 or idx[-1] == count - 1) and all(0 <= i < count for i in idx)


def test_sheet_has_a_band_per_sequence_and_shows_flames_and_smoke():
    seqs = [_seq("clear", 0.0), _seq("smoky", 5.0, seed=1)]
    tile, shown = 48, 4
    sheet = P.preview_sheet(seqs, shown=shown, tile=tile)
    band = P.LABEL_HEIGHT + 2 * tile + 1
    assert sheet.shape == (len(seqs) * band, shown * tile, 3) and sheet.dtype == np.uint8
    for k, seq in enumerate(seqs):
        dark = sheet[k * band + P.LABEL_HEIGHT : k * band + P.LABEL_HEIGHT + tile]
        light = sheet[k * band + P.LABEL_HEIGHT + tile : (k + 1) * band - 1]
        for j in range(len(seq.sprites)):
            d, li = dark[:, j * tile : (j + 1) * tile], light[:, j * tile : (j + 1) * tile]
            assert d.max() > 200 > max(P.DARK)  # the flame is bright on the dark row
            assert np.ptp(li.astype(int), axis=-1).max() > 100  # a saturated flame shows on the light row
    smoky_light = sheet[band + P.LABEL_HEIGHT + tile : 2 * band - 1].astype(int)
    clear_light = sheet[P.LABEL_HEIGHT + tile : band - 1].astype(int)
    dark = lambda a: int((a.max(axis=-1) < 150).sum())  # noqa: E731 - darker than any lit wall in every channel
    assert dark(clear_light) == 0 and dark(smoky_light) > 100  # dark smoke shows on the light row only


def test_tile_is_the_compositor_output_over_a_flat_background():
    mask = np.zeros((10, 6), bool)
    mask[4:, 2:4] = True
    emission = np.zeros((10, 6, 3), np.uint8)
    emission[mask] = (255, 128, 0)
    seq = SpriteSequence("s", (Sprite(np.zeros((10, 6, 4), np.uint8), emission, mask),), {})
    tile = P.flame_tile(seq, 0, P.DARK, 40)
    assert tile.shape == (40, 40, 3)
    assert np.abs(tile[0, 0].astype(int) - P.DARK).max() <= 8  # far from the flame: the background, barely lit
    assert tile[..., 0].max() == 255 and tile[..., 2].max() < 128  # an orange flame


def test_empty_library_is_refused(tmp_path):
    with pytest.raises(ValueError, match="no flame sequence"):
        P.write_preview([], tmp_path / "p.png")

"""The smoke library: simulated plumes or a mixture's own smoke cut-outs, none without plumes, and settings checked."""

from __future__ import annotations

import numpy as np
import pytest

from synth.flames.sprites import SMOKE_KIND, Sprite, SpriteSequence, is_smoke
from synth.smoke.library import SmokeConfig, smoke_library, split_library
from synth.smoke.plume import plume_library


def test_simulated_plumes_or_own_smoke_and_none_without_plumes(library) -> None:
    assert smoke_library(SmokeConfig()) == []  # no plumes asked for
    simulated = smoke_library(SmokeConfig(alone=0.5, sequences=3, frames=2))
    assert len(simulated) == 3 and all(is_smoke(s) and len(s.sprites) == 2 for s in simulated)
    own = plume_library(1, seed=9, frames=1)
    mixed = [*library, *own]
    assert smoke_library(SmokeConfig(above=1.0, source="cutouts"), mixed) == own
    assert split_library(mixed) == (list(library), own)
    with pytest.raises(ValueError, match="smoke.source cutouts: no smoke cut-outs given"):
        smoke_library(SmokeConfig(above=1.0, source="cutouts"), library)


def _fog(w: int = 90, h: int = 120) -> SpriteSequence:
    """A matte of fog that fills its box: grey, opacity 0.8 everywhere (the shape a matte's window would give)."""
    over = np.dstack([np.full((h, w, 3), 170, np.uint8), np.full((h, w), 204, np.uint8)])
    sprite = Sprite(over, np.zeros((h, w, 3), np.uint8), np.zeros((h, w), bool))
    return SpriteSequence("smoke-000", (sprite, sprite), {"kind": SMOKE_KIND, "generator": "matte"})


def test_own_smoke_in_a_plumes_shape_keeps_its_colour_and_rises_from_a_narrow_source() -> None:
    cfg = SmokeConfig(alone=1.0, source="cutouts", shape="plume", sequences=3, frames=2)
    shaped = smoke_library(cfg, [_fog()])
    assert len(shaped) == 1 and shaped[0].name == "smoke-000" and shaped[0].meta["shape"] == "plume"
    assert shaped[0].meta["generator"] == "matte"  # still own smoke: it keeps its colour when laid
    again = smoke_library(cfg, [_fog()])
    for sp, same in zip(shaped[0].sprites, again[0].sprites):
        assert np.array_equal(sp.over, same.over)  # the same shapes every time
        assert np.array_equal(sp.over[..., :3], _fog().sprites[0].over[..., :3])  # colour and texture kept
        alpha = sp.over[..., 3].astype(np.float32)
        assert alpha.max() <= 204 and alpha.max() >= 0.9 * 204  # never denser than the matte; its core as dense
        assert alpha[:, :5].max() < 0.1 * 204 and alpha[:, -5:].max() < 0.1 * 204  # no side of the box shows ...
        assert (alpha[-5:] >= 0.1 * 204).any(axis=0).mean() < 0.4  # ... nor its bottom: only the plume's source
        x = np.arange(alpha.shape[1])
        spread = [
            np.sqrt((alpha[r] * (x - (alpha[r] * x).sum() / alpha[r].sum()) ** 2).sum() / alpha[r].sum())
            for r in (alpha.shape[0] - 15, alpha.shape[0] // 4)
        ]
        assert spread[0] < 0.6 * spread[1]  # narrow at its source, spreading as it rises (a matte's ellipse: 0.68)
    assert smoke_library(SmokeConfig(alone=1.0, source="cutouts"), [_fog()])[0].sprites[0].over[..., 3].min() == 204


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"above": 1.5}, "smoke.above must be in 0..1"),
        ({"sky": -0.1}, "smoke.sky must be in 0..1"),
        ({"source": "fluid"}, "unknown smoke.source 'fluid'"),
        ({"sequences": 0}, "smoke.sequences and frames must be >= 1"),
        ({"height_m": (5.0, 1.0)}, r"smoke.height_m must be \[lo, hi\]"),
        ({"shape": "disc"}, "unknown smoke.shape 'disc'"),
        ({"shape": "plume"}, "smoke.shape plume shapes own smoke: it needs smoke.source cutouts"),
        ({"density": (3.0, 1.0)}, r"smoke.density must be \[lo, hi\]"),
        ({"density": (0.0, 1.0)}, r"smoke.density must be .* with lo >= 0.1"),
    ],
)
def test_bad_smoke_settings_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SmokeConfig(**kwargs)

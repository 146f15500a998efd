"""The smoke library: simulated plumes or a mixture's own smoke cut-outs, none without plumes, and settings checked."""

from __future__ import annotations

import pytest

from synth.flames.sprites import is_smoke
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


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"above": 1.5}, "smoke.above must be in 0..1"),
        ({"sky": -0.1}, "smoke.sky must be in 0..1"),
        ({"source": "fluid"}, "unknown smoke.source 'fluid'"),
        ({"sequences": 0}, "smoke.sequences and frames must be >= 1"),
        ({"height_m": (5.0, 1.0)}, r"smoke.height_m must be \[lo, hi\]"),
    ],
)
def test_bad_smoke_settings_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SmokeConfig(**kwargs)

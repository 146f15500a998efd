"""The flame library config and builder; the shipped synth YAML configs load into their schemas."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ground.config.loader import ConfigError, load_config
from synth.flames import library as L
from synth.flames.sprites import save_sequence
from synth.method1 import Method1Config
from synth.method2 import Method2Config

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


@pytest.mark.parametrize(
    ("name", "schema"), [("synth-method1.yaml", Method1Config), ("synth-method2.yaml", Method2Config)]
)
def test_shipped_configs_load_and_state_the_defaults(name, schema):
    cfg = load_config(CONFIGS / name, schema)
    assert cfg == schema()  # the YAML documents the defaults: a changed default must change the file too
    small = load_config(CONFIGS / name, schema, ["n=5", "flames.sequences=2", "flame_height_m=[0.5, 1.0]"])
    assert small.n == 5 and small.flames.sequences == 2 and small.flame_height_m == (0.5, 1.0)


def test_configs_reject_bad_values(tmp_path):
    with pytest.raises(ConfigError, match="box_mode"):
        load_config(CONFIGS / "synth-method1.yaml", Method1Config, ["box_mode=tight"])
    with pytest.raises(ConfigError, match="flames.colour"):
        load_config(CONFIGS / "synth-method2.yaml", Method2Config, ["flames.colour=red"])
    with pytest.raises(ValueError, match="flame_height_m"):
        load_config(CONFIGS / "synth-method2.yaml", Method2Config, ["flame_height_m=[2.0, 1.0]"])
    with pytest.raises(ValueError, match="generator"):
        L.FlameLibraryConfig(generator="embergen")


def test_procedural_library_is_seeded_and_folders_load(tmp_path):
    a = L.procedural_library(2, 7, 40, 20, 0.0)
    b = L.procedural_library(2, 7, 40, 20, 0.0)
    assert [s.name for s in a] == ["fluid-7-000", "fluid-7-001"]
    assert all(np.array_equal(x.emission, y.emission) for s, t in zip(a, b) for x, y in zip(s.sprites, t.sprites))
    save_sequence(tmp_path / "lib" / "one", a[0])
    loaded = L.build_library(L.FlameLibraryConfig(folders=(tmp_path / "lib",)))
    assert [s.name for s in loaded] == ["fluid-7-000"] and len(loaded[0].sprites) == len(a[0].sprites)
    exposed = L.build_library(
        L.FlameLibraryConfig(sequences=2, seed=7, frames=40, keep_every=20, rare=0.0, exposed=True)
    )
    assert all(s.meta["params"]["gain"] > 0 for s in exposed) and all(s.meta["params"]["gain"] == 0 for s in a)
    assert [len(s.sprites) for s in exposed] == [len(s.sprites) for s in a]  # the same frames, coloured otherwise


def _tagged(name: str, generator: str) -> L.SpriteSequence:
    seq = L.procedural_library(1, 3, 24, 12, 0.0)[0]
    return L.SpriteSequence(name, seq.sprites, {"generator": generator})


def test_flame_sources_are_checked_in_one_line():
    with pytest.raises(ValueError, match="unknown flames.source 'real'"):
        L.FlameLibraryConfig(source="real")
    with pytest.raises(ValueError, match="unknown flames.source 'both'"):
        L.FlameLibraryConfig(source="both")
    with pytest.raises(ValueError, match="texture must be in"):
        L.FlameLibraryConfig(texture=1.0)
    with pytest.raises(ValueError, match="folders are simulated flames' stand-ins"):
        L.FlameLibraryConfig(source="cutouts", folders=(Path("x"),))
    with pytest.raises(ValueError, match="cut-out flames are for Method 2 pools only"):
        Method1Config(flames=L.FlameLibraryConfig(source="cutouts"))
    with pytest.raises(ConfigError, match="flames.source"):
        load_config(CONFIGS / "synth-method2.yaml", Method2Config, ["flames.source=5"])


def test_a_library_takes_the_cutouts_its_source_names():
    cut = [_tagged("real-000", "user-rgba")]  # as a synth cutouts folder loads
    small = {"sequences": 1, "frames": 24, "keep_every": 12}
    assert [s.name for s in L.build_library(L.FlameLibraryConfig(source="cutouts", **small), cut)] == ["real-000"]
    with pytest.raises(ValueError, match="flames.source cutouts: no cut-outs given"):
        L.build_library(L.FlameLibraryConfig(source="cutouts"))
    with pytest.raises(ValueError, match="source is simulated"):
        L.build_library(L.FlameLibraryConfig(**small), cut)


def _cutout_folder(root: Path) -> Path:
    """A ``synth cutouts``-style folder: one sequence of two 30x40 RGBA cut-outs whose flame fills only the middle
    (the rest of the box transparent, as GrabCut leaves an annotator's margin)."""
    from synth.flames.sprites import write_png

    (root / "real-000").mkdir(parents=True)
    for k in range(2):
        rgba = np.zeros((40, 30, 4), np.uint8)
        rgba[6 + k : 34, 5:24] = (255, 170, 40, 255)
        write_png(root / "real-000" / f"{k:05d}.png", rgba)
    return root

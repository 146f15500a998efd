"""The flame library config and builder; the shipped synth YAML configs load into their schemas."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from curate.core.config import ConfigError, load_config
from synth import library as L
from synth.method1 import Method1Config
from synth.method2 import Method2Config
from synth.sprites import save_sequence

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
    risen = L.build_library(
        L.FlameLibraryConfig(sequences=2, seed=7, frames=40, keep_every=20, rare=0.0, rising_smoke=True)
    )
    assert [s.meta["params"]["rising_smoke"] for s in risen] == [True, True]  # the key reaches the flames
    pairs = [(x, y) for s, t in zip(a, risen) for x, y in zip(s.sprites, t.sprites)]  # the same flames (their
    assert all(abs(int(x.mask.sum()) - int(y.mask.sum())) <= 0.03 * x.mask.sum() for x, y in pairs)  # crops differ)
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
    with pytest.raises(ValueError, match="cutout_share must be in 0..1"):
        L.FlameLibraryConfig(source="both", cutout_share=1.5)
    with pytest.raises(ValueError, match="cutout_share is the cut-outs' share with source both"):
        L.FlameLibraryConfig(cutout_share=0.3)
    with pytest.raises(ValueError, match="folders are simulated flames' stand-ins"):
        L.FlameLibraryConfig(source="cutouts", folders=(Path("x"),))
    with pytest.raises(ValueError, match="cut-out flames are for Method 2 pools only"):
        Method1Config(flames=L.FlameLibraryConfig(source="cutouts"))
    with pytest.raises(ConfigError, match="flames.source"):
        load_config(CONFIGS / "synth-method2.yaml", Method2Config, ["flames.source=5"])


def test_a_library_takes_the_cutouts_its_source_names():
    cut = [_tagged("real-000", L.CUTOUT_GENERATOR)]
    small = {"sequences": 1, "frames": 24, "keep_every": 12}
    assert [s.name for s in L.build_library(L.FlameLibraryConfig(source="cutouts", **small), cut)] == ["real-000"]
    both = L.build_library(L.FlameLibraryConfig(source="both", **small), cut)
    assert [s.name for s in both] == ["real-000", "fluid-0-000"]
    with pytest.raises(ValueError, match="flames.source cutouts: no cut-outs given"):
        L.build_library(L.FlameLibraryConfig(source="cutouts"))
    with pytest.raises(ValueError, match="source is simulated"):
        L.build_library(L.FlameLibraryConfig(**small), cut)


def test_picks_keep_old_draws_and_share_flames_by_cutout_share():
    library = [_tagged(f"real-{k}", L.CUTOUT_GENERATOR) for k in range(3)] + [_tagged("sim", "fluid")]
    old = np.random.default_rng(5)
    expected = [library[int(old.integers(len(library)))].name for _ in range(50)]
    rng = np.random.default_rng(5)
    assert [L.pick_sequence(library, L.FlameLibraryConfig(), rng).name for _ in range(50)] == expected
    for share in (0.2, 0.8):
        cfg, rng = L.FlameLibraryConfig(source="both", cutout_share=share), np.random.default_rng(0)
        picks = [L.pick_sequence(library, cfg, rng).meta["generator"] for _ in range(4000)]
        assert abs(picks.count(L.CUTOUT_GENERATOR) / 4000 - share) < 0.03  # not the 3/4 of a uniform pick
    only = L.FlameLibraryConfig(source="both", cutout_share=1.0)
    assert {L.pick_sequence(library, only, np.random.default_rng(k)).name for k in range(20)} <= {
        "real-0",
        "real-1",
        "real-2",
    }


def _cutout_folder(root: Path) -> Path:
    """A ``synth cutouts``-style folder: one sequence of two 30x40 RGBA cut-outs whose flame fills only the middle
    (the rest of the box transparent, as GrabCut leaves an annotator's margin)."""
    from synth.sprites import write_png

    (root / "real-000").mkdir(parents=True)
    for k in range(2):
        rgba = np.zeros((40, 30, 4), np.uint8)
        rgba[6 + k : 34, 5:24] = (255, 170, 40, 255)
        write_png(root / "real-000" / f"{k:05d}.png", rgba)
    return root


def test_cutouts_keep_the_box_they_were_cut_from_only_when_asked(tmp_path):
    folder = _cutout_folder(tmp_path / "cut")
    cropped, whole = L.cutout_library(folder), L.cutout_library(folder, canvas=True)
    assert [s.meta["generator"] for s in cropped + whole] == [L.CUTOUT_GENERATOR] * 2
    assert {s.size for s in whole[0].sprites} == {(30, 40)}  # the box: flame pixels span part of it
    assert [s.size for s in cropped[0].sprites] == [(21, 30), (21, 29)]  # the flame and a 1 px pad
    for a, b in zip(cropped[0].sprites, whole[0].sprites):
        assert a.mask.sum() == b.mask.sum()  # the same flame either way


def test_feathered_cutouts_fade_where_the_box_cut_the_flame(tmp_path):
    """``feather``: sprites faded on their whole canvas (the toy flames reach their box's bottom, not its other
    sides), then cropped; 0 leaves the library as it was."""
    from synth.sprites import write_png

    folder = tmp_path / "cut"
    (folder / "real-000").mkdir(parents=True)
    for k in range(2):
        rgba = np.zeros((40, 30, 4), np.uint8)
        rgba[6 + k :, 5:24] = (255, 170, 40, 255)
        write_png(folder / "real-000" / f"{k:05d}.png", rgba)
    plain, soft = L.cutout_library(folder), L.cutout_library(folder, feather=0.25)
    assert [s.meta["generator"] for s in soft] == [L.CUTOUT_GENERATOR]
    assert [s.sprites[0].over.tobytes() for s in L.cutout_library(folder, feather=0.0)] == [
        s.sprites[0].over.tobytes() for s in plain
    ]
    for a, b in zip(plain[0].sprites, soft[0].sprites):
        assert a.size[0] == b.size[0] and b.mask.sum() < a.mask.sum()  # the cut bottom fades, the sides stay
        middle = b.size[0] // 2
        assert b.over[-1, middle, 3] < 10 and b.over[5, middle, 3] == 255 and b.over[5, 1, 3] == 255
    whole = L.cutout_library(folder, canvas=True, feather=0.25)
    assert {s.size for s in whole[0].sprites} == {(30, 40)}
    with pytest.raises(ValueError, match="cutout_feather"):
        L.FlameLibraryConfig(cutout_feather=0.2)  # simulated flames have no box sides
    with pytest.raises(ValueError, match="cutout_feather"):
        L.FlameLibraryConfig(source="cutouts", cutout_feather=0.7)


def test_cutout_groups_are_for_real_cutouts_in_method2_only():
    with pytest.raises(ValueError, match="cutout_groups"):
        L.FlameLibraryConfig(cutout_groups=True)  # simulated flames have no image mates
    assert L.FlameLibraryConfig(source="cutouts", cutout_groups=True).cutout_groups
    assert L.FlameLibraryConfig(folders=(Path("cut"),), cutout_groups=True).cutout_groups
    with pytest.raises(ValueError, match="Method 2 pools only"):
        Method1Config(flames=L.FlameLibraryConfig(folders=(Path("cut"),), cutout_groups=True))

"""Leakage of a pool's background photos into a test set: found by content, named in one line with a count and an
example, refused by ``fuzzyfire experiment`` (exit 2) before any pool is built; a test set taking the share the
pool holds out is disjoint from it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml
from factories_experiment import fire_free_photos, toy_dict

import curate.core.manifest as manifest
from curate.core.holdout import held_out
from fuzzyfire.cli import main
from fuzzyfire.datasets import Datasets
from fuzzyfire.experiment_config import SynthConfig
from fuzzyfire.leakage import LeakageError, check_leakage, pool_photos
from fuzzyfire.stages import folder_ref
from synth.method2 import Method2Config


def _photos_test_set(folder: Path, holdout: float = 0.0):
    return Datasets(("fire",)).get(folder_ref(folder, folder.parent, "auto", {}, (), None, holdout))


def test_a_renamed_copy_of_a_pool_photo_is_leakage(tmp_path: Path) -> None:
    photos = fire_free_photos(tmp_path / "photos", 4)
    test = fire_free_photos(tmp_path / "test", 3, seed=9)
    shutil.copy(photos / "photo02.png", test / "renamed.png")  # same bytes, another name
    with pytest.raises(LeakageError) as exc:
        check_leakage({"method2": sorted(photos.iterdir())}, {"fire-free": _photos_test_set(test)})
    message = str(exc.value)
    assert message.startswith("leakage: 1 images of test set 'fire-free' are background photos of the method2 pool")
    assert "renamed.png" in message and "photo02.png" in message and "\n" not in message
    check_leakage(
        {"method2": sorted(photos.iterdir())}, {"fire-free": _photos_test_set(fire_free_photos(tmp_path / "o", 3, 7))}
    )


def test_no_pool_photos_hashes_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(manifest, "file_sha256", lambda *a: pytest.fail("hashed"))
    check_leakage({}, {"fire-free": _photos_test_set(fire_free_photos(tmp_path / "p", 2))})
    assert pool_photos(SynthConfig(), ("method1", "method2"), tmp_path) == {}  # no backgrounds: no photos


def test_the_held_out_share_is_disjoint_from_the_pool(tmp_path: Path) -> None:
    photos = fire_free_photos(tmp_path / "photos", 12)
    synth = SynthConfig(method2=Method2Config(scenes=0, backgrounds=(Path("photos"),), background_holdout=0.5))
    pool = pool_photos(synth, ("method2",), tmp_path)["method2"]
    kept = {p.name for p in pool}
    assert kept == {p.name for p in photos.iterdir() if not held_out(p, 0.5)} and 0 < len(kept) < 12
    check_leakage({"method2": pool}, {"fire-free": _photos_test_set(photos, 0.5)})  # the held-out share: clean
    with pytest.raises(LeakageError, match=f"leakage: {len(kept)} images of test set 'fire-free'"):
        check_leakage({"method2": pool}, {"fire-free": _photos_test_set(photos)})  # every photo: the pool's leak


def test_the_experiment_refuses_leakage_before_building_a_pool(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    fire_free_photos(tmp_path / "photos", 5)
    doc = toy_dict(mixtures=["R6_S6"], table1=[])
    doc["synth"]["method2"] = {**doc["synth"]["method2"], "scenes": 0, "backgrounds": ["photos"]}
    doc["tests"] = {"fire-free": {"path": "photos"}}
    config = tmp_path / "leaky.yaml"
    config.write_text(yaml.safe_dump(doc), encoding="utf-8")
    assert main(["experiment", str(config), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: leakage: 5 images of test set 'fire-free' are background photos of the method2")
    assert err.count("\n") == 1 and not list((tmp_path / "out" / "data").glob("method2-*"))


def test_labelled_frames_are_pool_photos_too(tmp_path: Path) -> None:
    from factories import write_frames

    from curate.core.load import load_split

    frames = write_frames(tmp_path)
    synth = SynthConfig(method2=Method2Config(scenes=0, frames=(Path("frames"),)))
    pool = pool_photos(synth, ("method2",), tmp_path)["method2"]
    assert len(pool) == 3
    with pytest.raises(LeakageError, match="leakage: 3 images of test set 'cams' are background photos"):
        check_leakage({"method2": pool}, {"cams": load_split(frames)})

"""Leakage of a pool's background photos into a test set: found by content, named in one line with a count and an
example, refused by ``fuzzyfire experiment`` (exit 2) before any pool is built; a test set taking the share the
pool holds out is disjoint from it, and in an experiment the test set's ``holdout`` is that share."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml
from factories_experiment import fire_free_photos, toy_dict

import ground.data.manifest as manifest
from fuzzyfire.cli import main
from fuzzyfire.datasets import Datasets
from fuzzyfire.experiment_config import SynthConfig
from fuzzyfire.leakage import LeakageError, check_leakage, pool_photos
from fuzzyfire.stages import folder_ref
from ground.data.holdout import held_out
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


def test_in_an_experiment_the_test_sets_holdout_is_the_pools_held_out_share(tmp_path: Path) -> None:
    """One key: a test set's ``holdout`` on a folder of the pool's backgrounds makes the pool hold out that share."""
    from fuzzyfire.experiment_config import ExperimentConfig
    from ground.config.loader import build_config

    photos = fire_free_photos(tmp_path / "photos", 12)
    doc = toy_dict(mixtures=["R6_S6"], table1=[])
    doc["synth"]["method2"] = {**doc["synth"]["method2"], "scenes": 0, "backgrounds": ["photos"]}
    doc["tests"] = {"fire-free": {"path": str(photos), "holdout": 0.5}}  # the same folder, given another way
    cfg = build_config(doc, ExperimentConfig).resolved(tmp_path)
    assert cfg.synth.method2 is not None and cfg.synth.method2.background_holdout == 0.5
    pool = pool_photos(cfg.synth, ("method2",), tmp_path)["method2"]
    check_leakage({"method2": pool}, {"fire-free": _photos_test_set(photos, 0.5)})  # disjoint by construction


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

    from ground.data.load import load_split

    frames = write_frames(tmp_path)
    synth = SynthConfig(method2=Method2Config(scenes=0, labelled_frames=(Path("frames"),)))
    pool = pool_photos(synth, ("method2",), tmp_path)["method2"]
    assert len(pool) == 3
    with pytest.raises(LeakageError, match="leakage: 3 images of test set 'cams' are background photos"):
        check_leakage({"method2": pool}, {"cams": load_split(frames)})


def test_test_images_that_are_training_images_are_found_and_named(
    tmp_path: Path, tmp_path_factory: pytest.TempPathFactory
) -> None:
    """A copy and a near copy (cropped) of training images in a test set are its leaks, through a linked folder
    too; the real set's own test split is checked against its splits only, not the folders it was curated from."""
    from curate_helpers import save, scene, transformed, use_session_cache

    from curate.embed import load_embedder
    from curate.scan import scan_images
    from fuzzyfire.leakage import find_test_leaks, reference_images, write_leaks
    from ground.data.dataset import DatasetBuilder

    use_session_cache(tmp_path_factory)
    train = DatasetBuilder(tmp_path / "train", ["fire"])
    for i in range(5):
        save(scene(70 + i), tmp_path / "train" / f"t{i}.jpg")
        train.add_image(f"t{i}.jpg", 160, 120)
    save(scene(90), tmp_path / "sources" / "unused.jpg")  # curated away: in the sources, not in a split
    test = DatasetBuilder(tmp_path / "test", ["fire"])
    for name, img in (("q0.jpg", scene(80)), ("copy.jpg", scene(71)), ("near.jpg", transformed(scene(72), "crop")),
                      ("source.jpg", scene(90))):  # fmt: skip
        save(img, tmp_path / "test" / name)
        test.add_image(name, 160, 120)
    trained = [train.build()]
    tests = {"rare": (test.build(), reference_images(trained, [tmp_path / "sources"])),
             "common": (test.build(), reference_images(trained, []))}  # fmt: skip
    embedder = load_embedder()
    leaks = find_test_leaks(tests, 0.45, lambda paths: scan_images(paths, embedder))
    assert leaks["rare"].leaked == ("copy.jpg", "near.jpg", "source.jpg") and leaks["rare"].reference == 6
    assert leaks["common"].leaked == ("copy.jpg", "near.jpg") and leaks["common"].images == 4
    assert leaks["rare"].examples[0][2] == 0.0  # the exact copy first
    assert "3 of its 4 images are copies or near duplicates" in leaks["rare"].line("drop")
    write_leaks(tmp_path / "leakage.json", leaks, 0.45, "drop")
    assert "near.jpg" in (tmp_path / "leakage.json").read_text()


@pytest.mark.slow
def test_the_experiment_drops_leaked_test_images_or_refuses(tmp_path: Path) -> None:
    """A rare set holding a copy of a real training image: dropped from it (leakage.json, the report, and the
    scored image count), or the study refused before training under ``leakage.action: refuse``."""
    import json

    doc = toy_dict(mixtures=["R12_S0"], table1=[])
    doc["synth"]["method1"] = None
    out = tmp_path / "A"
    config = tmp_path / "toy.yaml"
    config.write_text(yaml.safe_dump(doc), encoding="utf-8")
    assert main(["experiment", str(config), "--out", str(out), "--report-only"]) == 0
    before = set(json.loads((out / "leakage.json").read_text())["sets"]["rare (stand-in)"]["leaked"])
    real = next((out / "data").glob("real-standin-*"))
    rare = next((out / "data").glob("rare-standin-*"))
    train = json.loads((real / "annotations.json").read_text())
    first = next(i for i in train["images"] if i.get("split") == "train")
    victim = next(i["file_name"] for i in json.loads((rare / "annotations.json").read_text())["images"]
                  if i["file_name"] not in before)  # fmt: skip
    shutil.copyfile(real / first["file_name"], rare / victim)  # a training image inside the rare set
    assert main(["experiment", str(config), "--out", str(out), "--report-only"]) == 0
    leaks = json.loads((out / "leakage.json").read_text())["sets"]
    assert set(leaks["rare (stand-in)"]["leaked"]) == before | {victim} and victim not in before
    assert leaks["common (stand-in)"]["leaked"] == []
    assert "were dropped before scoring" in (out / "answer.md").read_text()
    doc["leakage"] = {"action": "refuse"}
    config.write_text(yaml.safe_dump(doc), encoding="utf-8")
    assert main(["experiment", str(config), "--out", str(out)]) == 2

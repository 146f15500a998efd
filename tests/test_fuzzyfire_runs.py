"""Run specs: identities free of output paths, finished runs recognised by hash, test-set folder names; named
test sets out of the identity, scored on finished runs without training (with their alarm rate)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from eval.config import InferenceConfig
from eval.errors import ALARMS
from fuzzyfire.runs import (
    RESULTS_FILE,
    EvalSet,
    RunError,
    RunSpec,
    eval_key,
    execute_run,
    exported_model,
    finished,
    missing_evals,
    slug,
)
from fuzzyfire.stages import DataRef
from train.config import TrainConfig


def _spec(out: Path, seed: int = 0) -> RunSpec:
    data = DataRef(Path("/data/mix"), {"kind": "mixture", "mixture": "R2_S2"}, "coco")
    val = DataRef(Path("/data/real"), {"kind": "folder"}, "coco", "valid")
    tests = (EvalSet("common", val.with_split("test")),)
    return RunSpec(
        "R2_S2", "method2", data, val, tests, ("fire",), TrainConfig(epochs=1, seed=seed), InferenceConfig(), out
    )


def test_identity_ignores_the_output_folder_and_uses_the_run_seed(tmp_path: Path) -> None:
    a, b = _spec(tmp_path / "a"), _spec(tmp_path / "b")
    assert a.hash() == b.hash() and a.label == "R2_S2-method2"
    assert a.out == tmp_path / "a" / "runs" / "R2_S2-method2" / f"seed0-{a.hash()[:8]}"
    assert replace(a, tables=("table1",)).hash() == a.hash()  # which tables show a run is not what makes it
    assert _spec(tmp_path, seed=1).hash() != a.hash()
    assert a.identity()["train"]["seed"] == 0 and _spec(tmp_path, seed=3).identity()["train"]["seed"] == 3
    assert replace(a, method=None).label == "R2_S2"


def test_a_run_that_differs_only_in_select_starts_from_its_twins_training(tmp_path: Path) -> None:
    from fuzzyfire.runs import adopt_training

    best = _spec(tmp_path)
    last = replace(best, train=replace(best.train, select="last"))
    assert adopt_training(last) is None  # no twin trained yet
    twin = best.out / "train"
    twin.mkdir(parents=True)
    for name in ("last.pt", "best.pt", "metrics.jsonl", "best.onnx", "results.json"):
        (twin / name).write_text(name)
    assert adopt_training(last) == twin
    assert sorted(p.name for p in (last.out / "train").iterdir()) == ["best.pt", "last.pt", "metrics.jsonl"]
    (twin / "last.pt").write_text("trained further")
    assert adopt_training(last) is None and (last.out / "train" / "last.pt").read_text() == "last.pt"  # begun
    other = replace(last, train=replace(last.train, seed=1))
    assert adopt_training(other) is None  # another seed is another training


def test_finished_runs_are_skipped_only_with_the_same_spec(tmp_path: Path) -> None:
    spec = _spec(tmp_path)
    assert finished(spec) is None
    spec.out.mkdir(parents=True)
    (spec.out / RESULTS_FILE).write_text(json.dumps({"hash": "other", "tests": {}}))
    assert finished(spec) is None
    scored = {"common": {"data": eval_key(spec.tests[0])}}
    (spec.out / RESULTS_FILE).write_text(json.dumps({"hash": spec.hash(), "tests": scored}))
    result = execute_run(spec)  # no training: the data paths do not even exist
    assert result["skipped"] is True and result["tests"] == scored


def test_no_test_set_is_in_the_identity_and_a_redefined_one_is_scored_again(tmp_path: Path) -> None:
    """A test set does not change the model: dropping images from it (leakage) keeps the run, but the run's
    results on it are stale."""
    spec = _spec(tmp_path)
    narrowed = replace(spec, tests=(EvalSet("common", replace(spec.tests[0].data, exclude=("a.jpg",))),))
    assert narrowed.hash() == spec.hash() and eval_key(narrowed.tests[0]) != eval_key(spec.tests[0])
    done = {"hash": spec.hash(), "tests": {"common": {"data": eval_key(spec.tests[0])}}}
    assert missing_evals(spec, done) == [] and missing_evals(narrowed, done) == list(narrowed.tests)


def test_slug_makes_folder_names() -> None:
    assert slug("common (stand-in)") == "common_stand-in"
    assert slug("rare") == "rare" and slug("(((") == "test"


def _fake_yolo_run(tmp_path: Path) -> RunSpec:
    """A run of the fake ``yolo`` engine (its detector finds one box of half the image, score 0.5, in every
    image) scored on painted 64x64 images with fire boxes."""
    from factories_experiment import command_engine
    from factories_train import painted_dataset

    from fuzzyfire.engine import EngineConfig
    from ground.config.loader import build_config
    from ground.data.writer import write_dataset

    write_dataset(painted_dataset(tmp_path / "src", 5, seed=0, size=(64, 64)), tmp_path / "real", ("coco",))
    (tmp_path / "mix").mkdir()
    (tmp_path / "mix" / "data.yaml").write_text("train: images\nnames: {0: fire}\n")
    real = DataRef(tmp_path / "real", {"kind": "folder", "path": "real"}, "coco")
    mix = DataRef(tmp_path / "mix", {"kind": "mixture"}, "coco")
    engine = build_config(command_engine(), EngineConfig)
    train, tests = TrainConfig(epochs=1, imgsz=64), (EvalSet("common", real),)
    return RunSpec("R4_S0", None, mix, real, tests, ("fire",), train, InferenceConfig(), tmp_path / "out", engine)


def test_a_named_test_set_added_later_is_scored_without_training(tmp_path: Path) -> None:
    """Adding a named test set keeps the run's identity: the finished run's model is scored on it (alarms per 100
    fire-free photos from eval's error breakdown) and nothing is trained; the results equal a fresh run's."""
    from factories_experiment import fire_free_photos

    spec = _fake_yolo_run(tmp_path)
    first = execute_run(spec)
    assert first["skipped"] is False and set(first["tests"]) == {"common"} and first["tests"]["common"]["boxes"] > 0
    log = spec.out / "train" / "command.log"
    stamp = log.stat().st_mtime_ns
    photos = DataRef(fire_free_photos(tmp_path / "photos", 4), {"kind": "folder", "path": "photos"}, "auto")
    later = replace(spec, evals=(EvalSet("fire-free", photos),))
    assert later.hash() == spec.hash() and later.out == spec.out
    assert missing_evals(later, first) == list(later.evals)
    added = execute_run(later)
    assert added["skipped"] is True and added["scored"] == ["fire-free"] and log.stat().st_mtime_ns == stamp
    free = added["tests"]["fire-free"]
    assert free["AP"] is None and free["boxes"] == 0 and free["images"] == 4
    assert free[ALARMS] == 100.0  # one detection at score 0.5 >= 0.25 in each of the 4 photos
    breakdown = json.loads((spec.out / free["scores"] / "errors.json").read_text())
    assert breakdown["false_alarms_per_100_negatives"] == free[ALARMS] and breakdown["negatives"] == 4
    assert ALARMS not in added["tests"]["common"] and added["tests"]["common"] == first["tests"]["common"]
    again = execute_run(later)
    assert again["skipped"] is True and "scored" not in again
    fresh = replace(later, root=tmp_path / "fresh")
    execute_run(fresh)  # trained and scored on both sets at once: the same results.json bytes
    assert (fresh.out / RESULTS_FILE).read_bytes() == (later.out / RESULTS_FILE).read_bytes()


def test_a_redefined_named_test_set_is_scored_again(tmp_path: Path) -> None:
    from factories_experiment import fire_free_photos

    spec = _fake_yolo_run(tmp_path)
    folder = fire_free_photos(tmp_path / "photos", 6)
    every = DataRef(folder, {"kind": "folder", "path": "photos"}, "auto")
    done = execute_run(replace(spec, evals=(EvalSet("fire-free", every),)))
    assert done["tests"]["fire-free"]["images"] == 6
    held = replace(every, identity={**every.identity, "holdout": 0.5}, holdout=0.5)
    redefined = replace(spec, evals=(EvalSet("fire-free", held),))
    assert missing_evals(redefined, done) == list(redefined.evals)
    again = execute_run(redefined)
    assert again["scored"] == ["fire-free"] and 0 < again["tests"]["fire-free"]["images"] < 6


def test_a_finished_run_without_its_model_refuses_new_test_sets(tmp_path: Path) -> None:
    spec = _spec(tmp_path)
    spec.out.mkdir(parents=True)
    (spec.out / RESULTS_FILE).write_text(json.dumps({"hash": spec.hash(), "tests": {"common": {}}}))
    extra = replace(spec, evals=(EvalSet("more", spec.val_data),))
    with pytest.raises(RunError, match="exported model .* is gone"):
        exported_model(extra)


def test_every_train_key_enters_the_identity_and_the_version_its_hash(tmp_path: Path, monkeypatch) -> None:
    """No key is left out to keep an old hash (the identity version is bumped instead): ``select`` and
    ``real_finetune`` at their defaults are in it, another value is another run, and a new version another hash."""
    from fuzzyfire import stages

    a = _spec(tmp_path)
    assert a.identity()["train"]["select"] == "best" and a.identity()["train"]["real_finetune"] == 0
    assert replace(a, train=replace(a.train, select="last")).hash() != a.hash()
    assert replace(a, train=replace(a.train, real_finetune=1)).hash() != a.hash()
    before = a.hash()
    monkeypatch.setattr(stages, "IDENTITY", stages.IDENTITY + 1)
    assert _spec(tmp_path).hash() != before

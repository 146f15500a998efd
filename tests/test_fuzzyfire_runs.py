"""Run specs: identities free of output paths, finished runs recognised by hash, test-set folder names."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from eval.score import ScoreConfig
from fuzzyfire.runs import RESULTS_FILE, EvalSet, RunSpec, execute_run, finished, slug
from fuzzyfire.stages import DataRef
from train.config import TrainConfig


def _spec(out: Path, seed: int = 0) -> RunSpec:
    data = DataRef(Path("/data/mix"), {"kind": "mixture", "mixture": "R2_S2"}, "coco")
    val = DataRef(Path("/data/real"), {"kind": "folder"}, "coco", "valid")
    tests = (EvalSet("common", val.with_split("test")),)
    return RunSpec(
        "R2_S2", "method2", data, val, tests, ("fire",), TrainConfig(epochs=1, seed=seed), ScoreConfig(), out
    )


def test_identity_ignores_the_output_folder_and_uses_the_run_seed(tmp_path: Path) -> None:
    a, b = _spec(tmp_path / "a"), _spec(tmp_path / "b")
    assert a.hash() == b.hash() and a.label == "R2_S2-method2"
    assert a.out == tmp_path / "a" / "runs" / "R2_S2-method2" / f"seed0-{a.hash()[:8]}"
    assert replace(a, tables=("table1",)).hash() == a.hash()  # which tables show a run is not what makes it
    assert _spec(tmp_path, seed=1).hash() != a.hash()
    assert a.identity()["train"]["seed"] == 0 and _spec(tmp_path, seed=3).identity()["train"]["seed"] == 3
    assert replace(a, method=None).label == "R2_S2"


def test_finished_runs_are_skipped_only_with_the_same_spec(tmp_path: Path) -> None:
    spec = _spec(tmp_path)
    assert finished(spec) is None
    spec.out.mkdir(parents=True)
    (spec.out / RESULTS_FILE).write_text(json.dumps({"hash": "other", "tests": {}}))
    assert finished(spec) is None
    (spec.out / RESULTS_FILE).write_text(json.dumps({"hash": spec.hash(), "tests": {"common": {}}}))
    result = execute_run(spec)  # no training: the data paths do not even exist
    assert result["skipped"] is True and result["tests"] == {"common": {}}


def test_slug_makes_folder_names() -> None:
    assert slug("common (stand-in)") == "common_stand-in"
    assert slug("rare") == "rare" and slug("(((") == "test"

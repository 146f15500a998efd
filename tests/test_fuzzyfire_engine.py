"""External trainers in the grid: a fake ``yolo`` (tests/fake_trainer.py) trains and exports through the command
engine; its ONNX is scored like our runs (the same AP as ``fuzzyfire score``), logs are kept, a failing command
fails only its run, local and Ray executors give the same bytes, and bad templates are refused at load."""

from __future__ import annotations

import contextlib
import io
import json
from dataclasses import replace
from pathlib import Path

import pytest
from factories_experiment import TRAIN, command_engine, run_local_and_ray, toy_dict

from fuzzyfire.cli import main
from fuzzyfire.datasets import Datasets
from fuzzyfire.engine import EngineConfig, EngineError
from fuzzyfire.executors import LocalExecutor
from fuzzyfire.experiment import grid_entries, needed_methods, plan_runs, prepare_data, write_mixtures
from fuzzyfire.experiment_config import ExperimentConfig, ExperimentConfigError
from fuzzyfire.runs import RESULTS_FILE, execute_run
from ground.config.loader import build_config


def _config(**engine) -> ExperimentConfig:
    doc = toy_dict(mixtures=["R12_S0", "R6_S6"], table1=[])
    doc["engine"] = command_engine(**engine)
    return build_config(doc, ExperimentConfig)


@pytest.fixture(scope="module")
def grid(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("engine")
    cfg = _config()
    cfg.check()
    grid = grid_entries(cfg)
    data = prepare_data(cfg, out, out, needed_methods(grid))
    return cfg, plan_runs(cfg, grid, data, write_mixtures(cfg, grid, data, Datasets(cfg.classes), out), out), out


def test_command_runs_are_scored_like_ours_and_keep_their_logs(grid, tmp_path: Path) -> None:
    _, specs, _ = grid
    runs = [replace(s, root=tmp_path / s.label) for s in specs]
    outcomes = list(LocalExecutor().map(execute_run, runs))
    assert [o.error for o in outcomes] == [None, None]
    spec, result = runs[0], outcomes[0].result
    log = (spec.out / "train" / "command.log").read_text()
    assert "$ " in log and "training on" in log and "exported" in log
    assert result["best"] == {"engine": "command"} and set(result["tests"]) == {"common (stand-in)", "rare (stand-in)"}
    common = spec.tests[0].data
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        onnx = spec.out / "train" / "yolo" / "weights" / "best.onnx"
        assert main(["score", str(onnx), "--data", str(common.path), "--split", common.split, "--json"]) == 0
    scored = json.loads(out.getvalue())
    assert result["tests"]["common (stand-in)"]["AP50"] == pytest.approx(scored["AP50"])
    again = execute_run(spec)  # finished: skipped, nothing trained again
    assert again["skipped"] is True


def test_a_failing_command_fails_its_run_with_the_log_tail(grid, tmp_path: Path) -> None:
    _, specs, _ = grid
    failing = replace(specs[0].engine, train=TRAIN + " fail=1")
    runs = [replace(specs[0], engine=failing, root=tmp_path / "bad"), replace(specs[1], root=tmp_path / "good")]
    outcomes = list(LocalExecutor().map(execute_run, runs))
    assert outcomes[1].error is None
    assert "engine.train command exited with 3" in outcomes[0].error
    assert "CUDA out of memory (pretend)" in (runs[0].out / "train" / "command.log").read_text()
    assert not (runs[0].out / RESULTS_FILE).exists()


def test_engine_config_is_checked_when_loaded() -> None:
    with pytest.raises(ExperimentConfigError, match=r"unknown placeholder \{epoch\}"):
        _config(train="yolo train epochs={epoch}").check()
    with pytest.raises(ExperimentConfigError, match="engine.train .* is empty"):
        _config(train="").check()
    with pytest.raises(EngineError, match="choose fuzzyfire or command"):
        EngineConfig(name="other").check()  # type: ignore[arg-type]
    tuned = _config()
    with pytest.raises(ExperimentConfigError, match="real_finetune is fuzzyfire's trainer's"):
        replace(tuned, train=replace(tuned.train, real_finetune=1)).check()


@pytest.mark.slow
def test_ray_runs_the_command_engine_like_local(grid, tmp_path: Path) -> None:
    _, specs, _ = grid
    run_local_and_ray(specs, tmp_path, num_cpus=1)

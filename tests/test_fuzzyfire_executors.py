"""Executors: a registry that raises on unknown names; failures reported, not fatal; a local Ray gives the
same results.json bytes as the local executor for the same seeds."""

from __future__ import annotations

from pathlib import Path

import pytest
from factories_experiment import run_local_and_ray, toy_config

from fuzzyfire.datasets import Datasets
from fuzzyfire.executors import EXECUTORS, ExecutorError, LocalExecutor, build_executor
from fuzzyfire.experiment import grid_entries, needed_methods, plan_runs, prepare_data, write_mixtures


def _square_or_fail(x: int) -> int:
    if x == 2:
        raise ValueError("two is not allowed")
    return x * x


def test_registry_raises_on_unknown_names() -> None:
    assert set(EXECUTORS) == {"local", "ray"}
    with pytest.raises(ExecutorError, match="unknown executor 'dask'; choose one of local, ray"):
        build_executor("dask")
    assert isinstance(build_executor("local"), LocalExecutor)


def test_local_reports_a_failed_item_and_goes_on() -> None:
    outcomes = list(LocalExecutor().map(_square_or_fail, [1, 2, 3]))
    assert [(o.index, o.result) for o in outcomes] == [(0, 1), (1, None), (2, 9)]
    assert outcomes[1].error == "ValueError: two is not allowed"


@pytest.fixture(scope="module")
def toy_specs(tmp_path_factory: pytest.TempPathFactory):
    """Two runs of a toy grid (one real-only, one mixed) with their data prepared once."""
    out = tmp_path_factory.mktemp("grid")
    cfg = toy_config(mixtures=["R12_S0", "R6_S6"], table1=[])
    grid = grid_entries(cfg)
    data = prepare_data(cfg, out, out, needed_methods(grid))
    return plan_runs(cfg, grid, data, write_mixtures(cfg, grid, data, Datasets(cfg.classes), out), out), out


@pytest.mark.slow
def test_ray_gives_the_same_results_as_local(toy_specs, tmp_path: Path) -> None:
    specs, _ = toy_specs
    outcomes = run_local_and_ray(specs, tmp_path, num_cpus=2)
    assert sorted(o.index for o in outcomes) == [0, 1]
    assert all(o.result["skipped"] is False for o in outcomes)


def test_ray_refuses_gpus_the_cluster_does_not_have() -> None:
    import torch

    if torch.cuda.is_available():
        pytest.skip("this machine has a GPU")
    with pytest.raises(ExecutorError, match="num_gpus=1 but the Ray cluster has 0 GPU"):
        build_executor("ray", num_cpus=1, num_gpus=1, local_cpus=1)


@pytest.mark.slow
def test_a_real_ray_head_started_with_ray_start_runs_the_grid(tmp_path: Path, ray_head: str) -> None:
    """``ray start --head`` on loopback (token authentication by default since Ray 2.59), then ``fuzzyfire
    experiment --executor ray --address`` in a fresh process without RAY_AUTH_MODE, as a user runs it: the same
    results.json bytes as the local executor."""
    import os
    import subprocess
    import sys

    from factories_experiment import write_toy_config

    config = write_toy_config(tmp_path / "toy.yaml", mixtures=["R12_S0", "R6_S6"], table1=[])
    env = {k: v for k, v in os.environ.items() if k != "RAY_AUTH_MODE"}
    cli = [sys.executable, "-m", "fuzzyfire.cli", "experiment", str(config)]
    joined = subprocess.run(
        [*cli, "--out", str(tmp_path / "cluster"), "--executor", "ray", "--address", ray_head],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert joined.returncode == 0, joined.stderr[-2000:]
    assert "InvalidAuthToken" not in joined.stderr
    local = subprocess.run([*cli, "--out", str(tmp_path / "local")], capture_output=True, text=True, env=env)
    assert local.returncode == 0, local.stderr[-2000:]
    results = {
        name: {p.parent.parent.name: p.read_bytes() for p in (tmp_path / name / "runs").glob("*/*/results.json")}
        for name in ("cluster", "local")
    }
    assert len(results["local"]) == 2 and results["cluster"] == results["local"]


def test_an_unreachable_cluster_is_one_clear_error(monkeypatch) -> None:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]  # nothing listens there
    monkeypatch.setenv("RAY_AUTH_MODE", "token")
    with pytest.raises(ExecutorError, match=f"cannot join the Ray cluster at 127.0.0.1:{port}"):
        build_executor("ray", address=f"127.0.0.1:{port}", num_cpus=1)

"""Wall time of the demo study (``make experiment`` = ``fuzzyfire experiment configs/demo.yaml``), target
<= 20 min on 2 idle cores, from nothing: every stage built and every run trained in a fresh folder.

- ``experiment_demo_data``: stand-in real and rare sets, Method 1 and Method 2 pools, mixtures;
- ``experiment_demo_runs``: training and scoring every mixture x seed (local executor);
- ``experiment_demo_wall``: the whole command including tables, figures and report.html.

.venv/bin/python experiments/experiment.py [--executor ray]
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path

import fuzzyfire.experiment as experiment
from fuzzyfire.executors import build_executor
from fuzzyfire.experiment_config import ExperimentConfig
from ground.config.loader import load_config

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "demo.yaml"


def main() -> None:
    name = sys.argv[sys.argv.index("--executor") + 1] if "--executor" in sys.argv else "local"
    cfg = load_config(CONFIG, ExperimentConfig, [f"executor.name={name}"])
    e = cfg.executor
    options = {"num_cpus": e.num_cpus, "local_cpus": e.local_cpus} if name == "ray" else {}
    marks: dict[str, float] = {}
    run_grid = experiment.run_grid

    def timed_grid(specs, datasets, executor):
        marks["runs_start"] = time.perf_counter()
        results = run_grid(specs, datasets, executor)
        marks["runs_end"] = time.perf_counter()
        return results

    experiment.run_grid = timed_grid
    executor = build_executor(name, **options)
    log = io.StringIO()
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(log):
        start = time.perf_counter()
        try:
            result = experiment.run_experiment(cfg, CONFIG.parent, Path(tmp) / "demo", executor)
        finally:
            executor.close()
        wall = time.perf_counter() - start
    runs = len({r["run"] for r in result.rows})
    print(f"experiment_demo_data: {marks['runs_start'] - start:.0f} s")
    print(f"experiment_demo_runs: {marks['runs_end'] - marks['runs_start']:.0f} s ({runs} runs, {name} executor)")
    print(f"experiment_demo_wall: {wall:.0f} s (target <= 1200 s on 2 idle cores)")


if __name__ == "__main__":
    main()

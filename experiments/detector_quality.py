"""Detector quality on real data for the same wall-clock budget: the study's default detector (pretrained
EfficientNet-Lite0, frozen early stages, cached views) against the from-scratch YOLOv5n (cspdarknet), each
trained on the real-only mixture R400_S0 of configs/shared-data.yaml (common = curated fire-cctv-416, rare =
fire-smoke-608 `Fire`) over 3 seeds, scored with `fuzzyfire score`'s code on both test sets.

The scratch detector gets as many epochs as fit in the default detector's mean training time (measured from
a 2-epoch probe on this machine), so the comparison is AP per CPU-minute. Runs go through the experiment
pipeline (cached by config hash): rerunning resumes. Skips cleanly without ../shared/data.

Lines printed (AP in %, mean and std over seeds): ``detector_<name>_<test>_AP50_mean``, ``..._AP50_std``,
``..._AP_mean``, ``..._AP_std``, ``detector_<name>_minutes_per_run``, ``detector_<name>_train_images_per_s``,
``detector_<name>_epochs``, ``detector_<name>_reused_runs`` (runs finished before, e.g. by an interrupted
bench), ``detector_pretrained_peak_rss`` (when the pretrained runs trained here).

.venv/bin/python experiments/detector_quality.py [--out out/bench-detector-quality] [--seeds 0,1,2]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import resource
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "shared-data.yaml"
SHARED = ROOT.parent / "shared" / "data"
MIXTURE = "R400_S0"


def _config(seeds: list[int], train_overrides: list[str]):
    from fuzzyfire.experiment_config import ExperimentConfig
    from ground.config.loader import load_config

    grid = [f"grid.mixtures=[{MIXTURE}]", "grid.table1=[]", f"grid.seeds=[{','.join(map(str, seeds))}]"]
    return load_config(CONFIG, ExperimentConfig, [*grid, "report.samples=false", *train_overrides])


def _run(cfg, out: Path) -> list[dict]:
    """Every run of ``cfg`` (trained unless already finished): its results and timing."""
    from fuzzyfire.executors import LocalExecutor
    from fuzzyfire.experiment import run_experiment

    start = time.time()
    with contextlib.redirect_stdout(sys.stderr):
        result = run_experiment(cfg, CONFIG.parent, out, LocalExecutor())
    if result.failed:
        raise SystemExit(f"{len(result.failed)} runs failed; see {out}")
    runs = []
    for run in sorted({r["run"] for r in result.rows}):
        folder = out / run
        results = json.loads((folder / "results.json").read_text())
        timing = json.loads((folder / "timing.json").read_text())
        metrics = [json.loads(line) for line in (folder / "train" / "metrics.jsonl").read_text().splitlines()]
        reused = (folder / "results.json").stat().st_mtime < start  # finished before this bench started
        runs.append({**results, "train_s": timing["train_s"], "epochs": len(metrics), "reused": reused,
                     "images_per_s": float(np.mean([m["train_images_per_s"] for m in metrics]))})  # fmt: skip
    return runs


def _scratch_epochs(budget_s: float, cfg, out: Path) -> int:
    """Epochs of the scratch detector that fit in ``budget_s`` seconds, from a 2-epoch probe run."""
    from fuzzyfire.datasets import Datasets
    from fuzzyfire.experiment import grid_entries, needed_methods, plan_runs, prepare_data, write_mixtures
    from fuzzyfire.runs import train_run

    probe = replace(cfg, train=replace(cfg.train, epochs=2))
    with contextlib.redirect_stdout(sys.stderr), tempfile.TemporaryDirectory() as tmp:
        grid = grid_entries(probe)
        data = prepare_data(probe, CONFIG.parent, out, needed_methods(grid))
        datasets = Datasets(probe.classes)
        spec = plan_runs(probe, grid, data, write_mixtures(probe, grid, data, datasets, out), out)[0]
        start = time.perf_counter()
        train_run(replace(spec, root=Path(tmp)), datasets.get(spec.val_data))
        per_epoch = (time.perf_counter() - start) / 2
    return max(1, round(budget_s / per_epoch))


def _print(name: str, runs: list[dict]) -> None:
    tests = runs[0]["tests"]
    for test in tests:
        for metric in ("AP50", "AP"):
            values = 100 * np.array([r["tests"][test][metric] for r in runs])
            tag = f"detector_{name}_{test}_{metric}"
            print(f"{tag}_mean: {values.mean():.1f} % ({len(runs)} seeds: {', '.join(f'{v:.1f}' for v in values)})")
            print(f"{tag}_std: {values.std(ddof=1) if len(values) > 1 else 0.0:.1f} points")
    print(f"detector_{name}_minutes_per_run: {np.mean([r['train_s'] for r in runs]) / 60:.1f} min (training)")
    print(f"detector_{name}_train_images_per_s: {np.mean([r['images_per_s'] for r in runs]):.1f} img/s")
    print(f"detector_{name}_epochs: {runs[0]['epochs']} epochs")
    reused = sum(r["reused"] for r in runs)
    if reused:
        print(f"detector_{name}_reused_runs: {reused} runs (finished before this bench; times are from then)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench-detector-quality")
    parser.add_argument("--seeds", default="0,1,2")
    args = parser.parse_args()
    if not (SHARED / "fire-cctv-416").is_dir() or not (SHARED / "fire-smoke-608").is_dir():
        print(f"detector_quality_skipped: {SHARED} not found", file=sys.stderr)
        return 0
    seeds = [int(s) for s in args.seeds.split(",")]
    pretrained = _run(_config(seeds, []), args.out / "pretrained")
    _print("pretrained", pretrained)
    if not all(r["reused"] for r in pretrained):
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
        print(f"detector_pretrained_peak_rss: {peak:.1f} GB (this process, views cached in RAM)")
    budget = float(np.mean([r["train_s"] for r in pretrained]))
    scratch_overrides = ["train.model.backbone=cspdarknet", "train.model.freeze=0"]
    epochs = _scratch_epochs(budget, _config(seeds[:1], scratch_overrides), args.out / "scratch")
    scratch = _run(_config(seeds, [*scratch_overrides, f"train.epochs={epochs}"]), args.out / "scratch")
    _print("scratch", scratch)
    return 0


if __name__ == "__main__":
    sys.exit(main())

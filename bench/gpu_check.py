"""Every CUDA path of fuzzyfire run once, each against the CPU: training, scoring, embedding, Ray on a GPU.

docs/scaling.md ("GPUs") lists the CUDA branches; none had run when this script was written. On a machine with a
CUDA GPU (a CUDA build of torch and ``onnxruntime-gpu``) it runs four checks in a few minutes, each printing
``name: value unit`` lines and one ``CHECK: passed|failed|skipped (why)`` line:

``gpu_train``  the mixture R400_S0 of configs/shared-data.yaml (its 400 real training images, curated and
               mixed as ``fuzzyfire experiment`` does: the same stages, cached under ``--out``), trained for
               ``--epochs`` with ``device: cuda`` (mixed precision) and with ``device: cpu``, same seed, through
               :func:`fuzzyfire.runs.train_run`. Passes when every per-epoch loss (box, obj, cls of
               metrics.jsonl) of the two runs agrees within :data:`LOSS_RTOL` (relative) and the GPU run's
               results.json names the GPU. Prints both curves, the largest relative gap and img/s of each.
``gpu_score``  the model the GPU run exported (best.onnx, as the pipeline exports it) scored on the common test
               split (the curated fire-cctv-416 test split) with onnxruntime's CUDA provider and with the CPU's.
               Passes when the session runs on the provider asked for and AP and AP50 agree within
               :data:`METRIC_ATOL`. Prints img/s of each (decode, inference, NMS and COCO evaluation).
``gpu_embed``  the first ``--embed-images`` sorted images of fire-cctv-416 embedded by the built-in embedder
               on CUDA and on the CPU, each through :func:`curate.dedupjob.run_dedup` without a cache. Passes
               when the CUDA session really runs on CUDA (``OnnxEmbedder.on_gpu``) and the kept lists are
               equal. Prints img/s of each and the largest absolute gap between the two runs' unit vectors.
``gpu_ray``    the same images embedded on a local Ray (``--ray-cpus`` CPUs, the machine's GPUs) by an
               embedder made with the GPU device: each task reserves a GPU share
               (:func:`curate.embedremote.task_gpus`). Passes when the share is > 0 and the vectors equal the
               local GPU run's within :data:`RAY_ATOL`. ``--skip-ray`` leaves it out.

The last line is ``gpu_check: passed|failed|skipped (...)``; the exit status is 1 when a check failed.

**The CPU side trains as long as the GPU side** (the same epochs on the same images). A shorter CPU run does
not give a prefix of the longer run's curve: the learning-rate schedule spans ``train.epochs`` (warm-up, then a
linear decay to the last epoch), and fewer images change every batch. Its cost is small enough: on the 2
shared cores where this script was written, a CPU fit of 200 images for 1 epoch took 17 s (18.6 img/s: frozen
features through onnxruntime, the trainable part, validation, export), so 3 epochs of 400 images take about
2 min there and less on a GPU machine's CPU cores. ``--epochs`` shortens both sides together.

Lines name the GPU side ``cuda`` and the CPU side ``cpu``: ``gpu_train_cuda_throughput``,
``gpu_train_cpu_epoch1``, ``gpu_score_cuda_AP``, ``gpu_embed_max_abs_diff``, ``gpu_ray_task_gpus``, ...

**Without a GPU** (torch sees no CUDA device, or onnxruntime has no CUDA provider) each check says in one line
what it skipped and why, and the script exits 0 within seconds (CI runs it that way). Without the data folder
(``--data``, default ../shared/data) the data-dependent checks, i.e. all four, are skipped and say so.
``--device-under-test cpu`` (hidden) runs everything with the CPU standing in for the GPU: every line except
the device choice is executed, which is how this script was tried where no GPU was available.

.venv/bin/python bench/gpu_check.py [--epochs 3] [--images 400] [--embed-images 2000] [--data DIR] [--out DIR]
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
CONFIG = REPO / "configs" / "shared-data.yaml"
DATA = REPO.parent / "shared" / "data"
REAL = "fire-cctv-416"  # the real set of configs/shared-data.yaml, also the embedding images

CHECKS = ("gpu_train", "gpu_score", "gpu_embed", "gpu_ray")
LOSSES = ("loss_box", "loss_obj", "loss_cls")  # metrics.jsonl keys compared epoch by epoch
LOSS_RTOL = 0.10  # largest relative gap of a GPU epoch loss to the CPU's (AMP, other kernels, other frozen runner)
METRIC_ATOL = 1e-4  # AP and AP50, GPU vs CPU onnxruntime
RAY_ATOL = 1e-5  # unit vectors, Ray GPU tasks vs the local GPU run
WARMUP_IMAGES = 8  # embedded before timing: session start and kernel choice are not throughput


@dataclass(frozen=True)
class Outcome:
    status: str  # passed | failed | skipped
    reason: str

    def line(self, name: str) -> str:
        return f"{name}: {self.status} ({self.reason})"


# --- pure helpers -------------------------------------------------------------------------------------------


def relative_gap(a: float, b: float) -> float:
    """``|a - b| / max(|a|, |b|)``: 0 when both are 0, infinite when either is not finite."""
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    scale = max(abs(a), abs(b))
    return 0.0 if scale == 0 else abs(a - b) / scale


def curve_gap(
    device: Sequence[Mapping[str, Any]], cpu: Sequence[Mapping[str, Any]], keys: Sequence[str] = LOSSES
) -> tuple[float, int]:
    """The largest :func:`relative_gap` of the losses ``keys`` between two per-epoch curves (metrics.jsonl rows)
    over the epochs both have: (gap, epochs compared). ValueError when they share no epoch or their epochs are
    numbered differently."""
    n = min(len(device), len(cpu))
    if n == 0:
        raise ValueError("the two loss curves share no epoch")
    rows = list(zip(device[:n], cpu[:n]))
    if any(d.get("epoch") != c.get("epoch") for d, c in rows):
        raise ValueError("the two loss curves number their epochs differently")
    return max(relative_gap(float(d[k]), float(c[k])) for d, c in rows for k in keys), n


def overall_rate(rates: Sequence[float]) -> float:
    """The rate of a run whose equal-sized parts ran at ``rates`` (their harmonic mean)."""
    if not rates or min(rates) <= 0:
        raise ValueError(f"rates must be positive, got {list(rates)}")
    return len(rates) / sum(1.0 / r for r in rates)


def metric_gap(a: float | None, b: float | None) -> float:
    """``|a - b|``; 0 when both are undefined (None), infinite when only one is."""
    if a is None or b is None:
        return 0.0 if a is None and b is None else math.inf
    return abs(a - b)


def skip_reasons(
    torch_gpu: str | None, ort_gpu: str | None, data: str | None, ray: str | None = None
) -> dict[str, str | None]:
    """Why each check of :data:`CHECKS` cannot run (None: it runs), from why torch has no GPU, why onnxruntime
    has none, why the data is missing and why Ray is left out."""

    def why(*reasons: str | None) -> str | None:
        return "; ".join(r for r in reasons if r) or None

    return {
        "gpu_train": why(torch_gpu, data),
        "gpu_score": why(ort_gpu, data),
        "gpu_embed": why(ort_gpu, data),
        "gpu_ray": why(ort_gpu, data, ray),
    }


def verdict(outcomes: Mapping[str, Outcome]) -> tuple[str, int]:
    """The final line and exit status: failed (1) when a check failed, passed when one passed and none failed,
    else skipped (0)."""
    names = {s: [n for n, o in outcomes.items() if o.status == s] for s in ("passed", "failed", "skipped")}
    if names["failed"]:
        return f"gpu_check: failed ({', '.join(names['failed'])})", 1
    if names["passed"]:
        skipped = f"; skipped: {', '.join(names['skipped'])}" if names["skipped"] else ""
        return f"gpu_check: passed ({', '.join(names['passed'])}{skipped})", 0
    return "gpu_check: skipped (no check could run on this machine)", 0


# --- what this machine has ----------------------------------------------------------------------------------


def torch_gpu_reason(device: str) -> str | None:
    """Why torch cannot train on ``device`` here (None: it can)."""
    from train.device import DeviceError, resolve_device

    try:
        resolve_device(device)
    except DeviceError as exc:
        return str(exc)
    return None


def ort_gpu_reason(device: str) -> str | None:
    """Why onnxruntime cannot run on ``device`` here (None: it can, or ``device`` is the CPU)."""
    import onnxruntime as ort

    from ground.run.device import onnx_providers

    _, notice = onnx_providers(device)
    if notice is None:
        return None
    return f"onnxruntime {ort.__version__} has no CUDA provider: pip install onnxruntime-gpu"


def data_reason(data: Path) -> str | None:
    if (data / REAL).is_dir():
        return None
    return f"{data / REAL} not found (--data names the folder of the shared datasets)"


def expected_provider(device: str) -> str:
    from ground.run.device import parse_device

    return "CPUExecutionProvider" if parse_device(device)[0] == "cpu" else "CUDAExecutionProvider"


# --- the study's run R{images}_S0 ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Study:
    """The run of the mixture R<images>_S0 as ``fuzzyfire experiment`` plans it, its validation and test sets."""

    spec: Any  # fuzzyfire.runs.RunSpec
    val: Any  # ground.data.dataset.Dataset
    test: Any
    out: Path

    def spec_on(self, device: str, role: str) -> Any:
        """The run on ``device`` in its own folder ``out/<role>`` (CPU and GPU runs never share a folder)."""
        s = self.spec
        return replace(
            s, root=self.out / role, train=replace(s.train, device=device), score=replace(s.score, device=device)
        )


def prepare_study(data: Path, out: Path, images: int, epochs: int, seed: int) -> Study:
    """Curate fire-cctv-416 and write the mixture R<images>_S0 as configs/shared-data.yaml does (both cached in
    ``out``), then plan its run (the rare and named test sets and the synthetic runs left out)."""
    from fuzzyfire.datasets import Datasets
    from fuzzyfire.experiment import grid_entries, plan_runs, prepare_data, write_mixtures
    from fuzzyfire.experiment_config import ExperimentConfig
    from ground.config.loader import load_config

    overrides = [
        f"real.path={(data / REAL).resolve().as_posix()}",
        f"grid.mixtures=[R{images}_S0]",
        "grid.table1=[]",
        "grid.control=false",
        f"grid.seeds=[{seed}]",
        "rare=null",
        "tests={}",
        f"train.epochs={epochs}",
        f"executor.num_cpus={os.cpu_count() or 2}",  # the run's torch and onnxruntime threads
    ]
    cfg = load_config(CONFIG, ExperimentConfig, overrides)
    cfg.check()
    datasets = Datasets(cfg.classes)
    prepared = prepare_data(cfg, CONFIG.parent, out, ())
    grid = grid_entries(cfg)
    (spec,) = plan_runs(cfg, grid, prepared, write_mixtures(cfg, grid, prepared, datasets, out), out)
    return Study(spec, datasets.get(spec.val_data), datasets.get(spec.tests[0].data), out)


@dataclass(frozen=True)
class TrainedRun:
    metrics: list[dict[str, Any]]  # metrics.jsonl rows
    onnx: Path
    seconds: float  # the whole fit: caching, training, validation, export
    device: str  # as results.json names it


def train_on(study: Study, device: str, role: str) -> TrainedRun:
    """A fresh run (its folder removed first: never a resume) of the study on ``device``."""
    from fuzzyfire.runs import train_run
    from train.plots import read_metrics

    spec = study.spec_on(device, role)
    shutil.rmtree(spec.out, ignore_errors=True)  # our own run folder under --out
    start = time.perf_counter()
    results = train_run(spec, study.val)
    seconds = time.perf_counter() - start
    folder = spec.out / "train"
    if not results.get("onnx"):
        raise RuntimeError(f"{folder}: training exported no model")
    return TrainedRun(read_metrics(folder / "metrics.jsonl"), folder / results["onnx"], seconds, results["device"])


# --- the checks ---------------------------------------------------------------------------------------------


def check_train(study: Study, device: str, trained: dict[str, TrainedRun]) -> Outcome:
    """Train on ``device`` and on the CPU (module docstring); fills ``trained`` by role (cuda, cpu)."""
    from train.device import resolve_device

    trained["cuda"] = train_on(study, device, "cuda")
    trained["cpu"] = train_on(study, "cpu", "cpu")
    for role, run in trained.items():
        for row in run.metrics:
            print(
                f"gpu_train_{role}_epoch{row['epoch']}: box {row['loss_box']:.5f} obj {row['loss_obj']:.5f} "
                f"cls {row['loss_cls']:.5f} (AP50 {row['AP50']:.4f}, AP {row['AP']:.4f})"
            )
        rate = overall_rate([row["train_images_per_s"] for row in run.metrics])
        print(f"gpu_train_{role}_throughput: {rate:.1f} img/s ({run.device}, training epochs incl. frozen features)")
        print(f"gpu_train_{role}_seconds: {run.seconds:.1f} s (fit: decode, train, validate, export)")
    gap, epochs = curve_gap(trained["cuda"].metrics, trained["cpu"].metrics)
    print(f"gpu_train_loss_max_rel_diff: {100 * gap:.2f} % (box/obj/cls, epochs 1-{epochs}; limit {LOSS_RTOL:.0%})")
    problems = []
    want = str(resolve_device(device))
    if trained["cuda"].device != want:
        problems.append(f"the {device} run trained on {trained['gpu'].device}, not {want}")
    if gap > LOSS_RTOL:
        problems.append(f"losses differ by {gap:.1%} > {LOSS_RTOL:.0%}")
    if problems:
        return Outcome("failed", "; ".join(problems))
    return Outcome("passed", f"{device} and cpu loss curves within {gap:.1%} over {epochs} epochs")


def _warm_detector(detector, batch: int) -> None:
    """One batch of the scoring size through the session before timing (provider start, kernel choice)."""
    import numpy as np

    spec = detector.spec
    detector(np.zeros((spec.batch or batch, 3, spec.input_height, spec.input_width), np.float32))


def check_score(study: Study, device: str, model: Path) -> Outcome:
    """Score ``model`` on the common test split with ``device`` and with the CPU (module docstring)."""
    from eval.score import score

    summaries, problems = {}, []
    for role, dev in (("cuda", device), ("cpu", "cpu")):
        cfg = replace(study.spec.score, device=dev)
        detector = cfg.detector(model)
        provider = detector.session.get_providers()[0]
        if detector.device_notice or provider != expected_provider(dev):
            problems.append(f"{dev}: onnxruntime runs on {provider} ({detector.device_notice or 'no notice'})")
        _warm_detector(detector, cfg.batch)
        start = time.perf_counter()
        result = score(detector, study.test, cfg)
        seconds = time.perf_counter() - start
        summaries[role] = result.metrics.summary
        n = len(study.test.images)
        print(f"gpu_score_{role}_throughput: {n / seconds:.1f} img/s ({provider}, {n} images, decode to COCO metrics)")
        print(f"gpu_score_{role}_AP: {_fmt(summaries[role]['AP'])} (AP50 {_fmt(summaries[role]['AP50'])})")
    gaps = {k: metric_gap(summaries["cuda"][k], summaries["cpu"][k]) for k in ("AP", "AP50")}
    print(f"gpu_score_max_abs_diff: {max(gaps.values()):.2e} (AP, AP50; limit {METRIC_ATOL:g})")
    problems += [f"{k} differs by {g:.2e} > {METRIC_ATOL:g}" for k, g in gaps.items() if g > METRIC_ATOL]
    if problems:
        return Outcome("failed", "; ".join(problems))
    return Outcome("passed", f"AP and AP50 of {model.name} on {device} == cpu within {METRIC_ATOL:g}")


def _fmt(value: float | None) -> str:
    return "undefined" if value is None else f"{value:.5f}"


def embed_paths(data: Path, n: int) -> list[Path]:
    """The first ``n`` image files of fire-cctv-416 in sorted path order."""
    from curate.scan import list_image_files

    return list_image_files([data / REAL])[:n]


def _embedder(device: str):
    """The built-in embedder on ``device``, warmed up; raises when it is not on the provider asked for."""
    from curate.embed import load_embedder

    embedder = load_embedder(device=device)
    if embedder.on_gpu() != (expected_provider(device) == "CUDAExecutionProvider"):
        raise RuntimeError(
            f"device {device!r}: the embedder runs on {embedder.session.get_providers()} ({embedder.notice})"
        )
    return embedder


def check_embed(paths: Sequence[Path], device: str, runs: dict[str, Any]) -> Outcome:
    """Dedup ``paths`` with the embedder on ``device`` and on the CPU (module docstring); fills ``runs`` by role
    with each :class:`curate.dedupjob.DedupRun`."""
    import numpy as np

    from curate.dedupjob import dedup_options, run_dedup
    from curate.scan import scan_images

    for role, dev in (("cuda", device), ("cpu", "cpu")):
        embedder = _embedder(dev)
        scan_images(paths[:WARMUP_IMAGES], embedder)
        start = time.perf_counter()
        runs[role] = run_dedup(paths, embedder, None, dedup_options())
        seconds = time.perf_counter() - start
        provider = embedder.session.get_providers()[0]
        print(f"gpu_embed_{role}_throughput: {len(paths) / seconds:.1f} img/s ({provider}, decode, embed, dedup)")
    gpu, cpu = runs["cuda"], runs["cpu"]
    if [i.path for i in gpu.scan.images] != [i.path for i in cpu.scan.images]:
        return Outcome("failed", "the two runs read different images")
    diff = float(max(np.abs(gpu.scan.vectors - cpu.scan.vectors).max(), np.abs(gpu.scan.crops - cpu.scan.crops).max()))
    kept = [[run.scan.images[i].path for i in run.result.kept] for run in (gpu, cpu)]
    print(f"gpu_embed_max_abs_diff: {diff:.2e} (unit vectors, whole and centre views)")
    print(f"gpu_embed_kept: {len(kept[0])} vs {len(kept[1])} images (of {len(paths)})")
    if kept[0] != kept[1]:
        only = len(set(kept[0]) ^ set(kept[1]))
        return Outcome("failed", f"kept lists differ ({only} images kept by one run only)")
    return Outcome("passed", f"the same {len(kept[0])} images kept on {device} and cpu")


def check_ray(paths: Sequence[Path], device: str, local: Any, cpus: int) -> Outcome:
    """Embed ``paths`` on a local Ray with ``device`` (module docstring); ``local``: the local run's scan on
    ``device`` (None: made here)."""
    import numpy as np

    from curate.embedremote import task_gpus
    from curate.scan import scan_images
    from ground.run.cluster import Cluster

    embedder = _embedder(device)
    local = local if local is not None else scan_images(paths, embedder)
    with Cluster(local_cpus=cpus) as cluster:
        share = task_gpus(cluster, device)  # refuses a cuda device on a Ray without GPUs
        print(f"gpu_ray_cluster: {cluster.cpus()} CPUs, {cluster.gpus():g} GPUs")
        print(f"gpu_ray_task_gpus: {share:g} GPU per embedding task")
        scan_images(paths[:WARMUP_IMAGES], embedder, cluster=cluster)  # workers started, model sent
        start = time.perf_counter()
        scan = scan_images(paths, embedder, cluster=cluster)
        seconds = time.perf_counter() - start
    print(f"gpu_ray_throughput: {len(paths) / seconds:.1f} img/s (decode and embed as Ray tasks)")
    if [i.path for i in scan.images] != [i.path for i in local.images]:
        return Outcome("failed", "Ray and the local run read different images")
    diff = float(max(np.abs(scan.vectors - local.vectors).max(), np.abs(scan.crops - local.crops).max()))
    print(f"gpu_ray_max_abs_diff: {diff:.2e} (vs the local {device} run; limit {RAY_ATOL:g})")
    problems = [f"vectors differ by {diff:.2e} > {RAY_ATOL:g}"] if diff > RAY_ATOL else []
    if share == 0 and expected_provider(device) == "CUDAExecutionProvider":
        problems.append("embedding tasks reserved no GPU")
    if problems:
        return Outcome("failed", "; ".join(problems))
    return Outcome("passed", f"Ray tasks with {share:g} GPU each == local {device} within {RAY_ATOL:g}")


# --- wiring -------------------------------------------------------------------------------------------------


def guarded(check: Callable[[], Outcome]) -> Outcome:
    """``check()``; an exception fails the check (traceback on stderr), the others still run."""
    try:
        return check()
    except Exception as exc:  # reported as the check's failure, with its traceback
        traceback.print_exc()
        return Outcome("failed", f"{type(exc).__name__}: {exc}")


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--epochs", type=int, default=3, help="training epochs of each side (default 3)")
    parser.add_argument("--images", type=int, default=400, help="real training images: mixture R<N>_S0 (400)")
    parser.add_argument("--embed-images", type=int, default=2000, help="images embedded (default 2000)")
    parser.add_argument("--data", type=Path, default=DATA, help=f"the shared datasets (default {DATA})")
    parser.add_argument("--out", type=Path, help="work folder (default: a new temporary folder, kept)")
    parser.add_argument("--seed", type=int, default=0, help="training seed of both sides")
    parser.add_argument("--skip-ray", action="store_true", help="leave out the Ray check")
    parser.add_argument("--ray-cpus", type=int, default=0, help="CPUs of the local Ray (0 = all)")
    parser.add_argument("--device-under-test", default="cuda", help=argparse.SUPPRESS)  # cpu: stand-in run
    args = parser.parse_args(argv)
    if args.epochs < 1 or args.images < 1 or args.embed_images < WARMUP_IMAGES:
        parser.error(f"--epochs and --images must be >= 1, --embed-images >= {WARMUP_IMAGES}")
    return args


def run_checks(args: argparse.Namespace, reasons: Mapping[str, str | None]) -> dict[str, Outcome]:
    """Every check that can run (``reasons[name]`` None), in :data:`CHECKS` order, each line printed as it ends."""
    device, outcomes = args.device_under_test, {}
    study: dict[str, Study] = {}
    trained: dict[str, TrainedRun] = {}
    embedded: dict[str, Any] = {}

    def get_study() -> Study:
        if "study" not in study:
            out = args.out or Path(tempfile.mkdtemp(prefix="fuzzyfire-gpu-check-"))
            print(f"gpu_check_out: {out} (curated set, mixture, training runs)", flush=True)
            study["study"] = prepare_study(args.data, out, args.images, args.epochs, args.seed)
        return study["study"]

    def score() -> Outcome:
        run = trained.get("cuda")
        if run is None and reasons["gpu_train"] is None:
            raise RuntimeError("no model to score: gpu_train failed")
        run = run or train_on(get_study(), "cpu", "cpu")  # torch sees no GPU: a CPU-trained model
        return check_score(get_study(), device, run.onnx)

    def paths() -> list[Path]:
        if "paths" not in embedded:
            embedded["paths"] = embed_paths(args.data, args.embed_images)
        return embedded["paths"]

    steps = {
        "gpu_train": lambda: check_train(get_study(), device, trained),
        "gpu_score": score,
        "gpu_embed": lambda: check_embed(paths(), device, embedded),
        "gpu_ray": lambda: check_ray(
            paths(),
            device,
            embedded["cuda"].scan if "cuda" in embedded else None,
            args.ray_cpus or os.cpu_count() or 2,
        ),
    }
    for name in CHECKS:
        outcome = Outcome("skipped", reasons[name]) if reasons[name] else guarded(steps[name])
        outcomes[name] = outcome
        print(outcome.line(name), flush=True)
    return outcomes


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    start = time.perf_counter()
    device = args.device_under_test
    if expected_provider(device) == "CPUExecutionProvider":
        print("gpu_check_device_under_test: cpu (stand-in: the CPU plays the GPU; no CUDA path is tested)")
    ray = "--skip-ray" if args.skip_ray else None
    reasons = skip_reasons(torch_gpu_reason(device), ort_gpu_reason(device), data_reason(args.data), ray)
    outcomes = run_checks(args, reasons)
    line, status = verdict(outcomes)
    print(f"gpu_check_seconds: {time.perf_counter() - start:.1f} s")
    print(line)
    return status


if __name__ == "__main__":
    sys.exit(main())

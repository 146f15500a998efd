"""The training loop: one epoch at a time, validation of the EMA model, fitness-based best checkpoint.

A run folder holds ``last.pt`` (everything needed to resume, written after every epoch), ``best.pt`` (EMA
weights of the epoch with the best fitness = 0.1 AP50 + 0.9 AP), ``metrics.jsonl`` (one JSON line per
epoch; epochs are counted from 1 in every output, as the console counts them), ``best.onnx`` (see :mod:`train.export`), ``curves.png`` and ``results.json`` (the resolved config, seed, versions,
anchors, best epoch and its metrics). Calling :func:`fit` again on the same folder resumes after the last
finished epoch and gives the same weights as an uninterrupted run.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from ground.data.dataset import Dataset
from ground.data.manifest import git_commit, versions
from ground.run.lock import lock_status
from ground.run.progress import progress
from train.anchors import check_anchors, label_sizes
from train.config import DEFAULT_ANCHORS, DetectorConfig, TrainConfig
from train.data import CachedImage, TrainBatches, cache_images, letterboxed_images, real_indices
from train.device import resolve_device, uses_amp
from train.ema import ModelEMA
from train.export import export_onnx
from train.features import FeatureBatches, FrozenRunner, ValidationInputs
from train.loss import DetectionLoss
from train.model import STRIDES, Detector, build_model
from train.optim import Schedule, build_optimizer
from train.plots import plot_curves, read_metrics
from train.validate import evaluate

#: Data-loading worker processes on a GPU when ``workers`` is not set.
GPU_WORKERS = 8

GRAD_CLIP = 10.0  # max gradient norm before each optimizer step


class ResumeError(ValueError):
    """A run folder whose checkpoint does not match the requested run."""


@dataclass
class Trainer:
    """The live objects of a run (built by :func:`build_trainer`)."""

    cfg: TrainConfig
    model: Detector
    ema: ModelEMA
    optimizer: torch.optim.Optimizer
    loss_fn: DetectionLoss
    schedule: Schedule
    batches: FeatureBatches
    class_names: list[str]
    anchors: tuple
    device: torch.device
    runner: FrozenRunner
    scaler: torch.amp.GradScaler


def train_one_epoch(t: Trainer, epoch: int) -> dict[str, float]:
    """One pass over the training batches; returns mean losses, learning rate and images/second."""
    t.model.train()
    nb = t.batches.count(epoch)
    sums = {"box": 0.0, "obj": 0.0, "cls": 0.0}
    seen, pending, start = 0, 0, time.perf_counter()
    t.optimizer.zero_grad(set_to_none=True)
    batches = progress(t.batches.epoch(epoch), total=nb, desc=f"epoch {epoch + 1}", unit="batch", min_items=10)
    amp = uses_amp(t.device)
    for i, (feats, targets) in enumerate(batches):
        iteration = epoch * len(t.batches) + i  # the schedule counts full epochs (real_finetune ones are shorter)
        t.schedule.apply(t.optimizer, iteration, epoch)
        with torch.autocast(t.device.type, enabled=amp):
            raw = t.model.forward_frozen(channels_last(feats))
        loss, parts = t.loss_fn([r.float() for r in raw], targets)
        t.scaler.scale(loss).backward()
        pending += 1
        if pending >= t.schedule.accumulate(iteration) or i == nb - 1:
            _step(t)
            pending = 0
        for key in sums:
            sums[key] += parts[key]
        seen += feats[0].shape[0]
    elapsed = time.perf_counter() - start
    return {
        **{f"loss_{k}": v / nb for k, v in sums.items()},
        "lr": float(t.optimizer.param_groups[0]["lr"]),
        "train_images_per_s": seen / elapsed,
    }


def channels_last(feats: tuple[torch.Tensor, ...]) -> tuple[torch.Tensor, ...]:
    """4-D tensors in channels-last memory order (values unchanged)."""
    return tuple(f.contiguous(memory_format=torch.channels_last) if f.ndim == 4 else f for f in feats)


def _step(t: Trainer) -> None:
    t.scaler.unscale_(t.optimizer)
    torch.nn.utils.clip_grad_norm_(t.model.parameters(), max_norm=GRAD_CLIP)
    t.scaler.step(t.optimizer)
    t.scaler.update()
    t.optimizer.zero_grad(set_to_none=True)
    t.ema.update(t.model)


def build_trainer(cfg: TrainConfig, train_ds: Dataset) -> Trainer:
    """Cache the training images, fit anchors, build model, EMA, optimizer, loss and schedule (seeded), all on
    the configured device."""
    device = resolve_device(cfg.device)
    torch.manual_seed(cfg.seed)
    cache = cache_images(train_ds, cfg.imgsz, desc="decoding training images")
    anchors = np.asarray(cfg.model.anchors or DEFAULT_ANCHORS, dtype=np.float64)
    report = {"refitted": 0.0}
    if cfg.model.autoanchor:
        wh = label_sizes(train_ds, cfg.imgsz)
        anchors, report = check_anchors(wh, anchors, np.random.default_rng(cfg.seed), cfg.loss.anchor_t)
    model_cfg = replace(cfg.model, anchors=_nested(anchors), autoanchor=False)
    names = train_ds.category_names
    # channels-last: torch's CPU (oneDNN) and GPU convolutions run 1.2-2x faster on it (bench_train_throughput)
    model = build_model(len(names), model_cfg, cfg.imgsz).to(device, memory_format=torch.channels_last)
    workers = cfg.workers if cfg.workers is not None else (GPU_WORKERS if device.type == "cuda" else 0)
    samples = TrainBatches(cache, cfg.imgsz, cfg.batch, cfg.augment, cfg.seed, workers, real_from(cfg, cache))
    runner = FrozenRunner(model, cfg.imgsz, device, cfg.threads)
    batches = FeatureBatches(samples, runner, cfg.feature_views, cfg.feature_cache_gb)
    schedule = Schedule(cfg.optim, cfg.epochs, len(batches), cfg.batch)
    loss_fn = DetectionLoss(model.head.anchors, STRIDES, len(names), cfg.imgsz, cfg.loss)
    ema = ModelEMA(model, cfg.ema_decay, cfg.ema_tau)
    if report.get("refitted"):
        print(f"anchors re-fitted by k-means: best possible recall {report['bpr_before']:.3f} -> {report['bpr']:.3f}")
    scaler = torch.amp.GradScaler(device.type, enabled=uses_amp(device))
    optimizer = build_optimizer(model, cfg.optim, cfg.batch)
    return Trainer(
        cfg, model, ema, optimizer, loss_fn, schedule, batches, names, _nested(anchors), device, runner, scaler
    )


def real_from(cfg: TrainConfig, cache: list[CachedImage]) -> int | None:
    """The first epoch of ``cfg.real_finetune``'s real-only epochs, or None when there are none: the setting is 0,
    or the training set has no real or no synthetic images (said on stdout)."""
    if cfg.real_finetune <= 0:
        return None
    real = len(real_indices(cache))
    if real == 0 or real == len(cache):
        kind = "no real" if real == 0 else "no synthetic"
        print(f"real_finetune {cfg.real_finetune}: the training set has {kind} images; every epoch trains on all")
        return None
    return cfg.epochs - cfg.real_finetune


def _nested(anchors: Any) -> tuple:
    return tuple(tuple(tuple(float(v) for v in a) for a in level) for level in np.asarray(anchors))


def _save(path: Path, state: dict[str, Any]) -> None:
    tmp = path.with_suffix(".tmp")
    torch.save(state, tmp)
    os.replace(tmp, path)


#: ``last.pt`` key saying its ``best`` epoch is counted from 1 (files without it count from 0).
EPOCHS_FROM = "epochs_counted_from"


def _checkpoint(t: Trainer, epoch: int, best: dict[str, Any]) -> dict[str, Any]:
    """``last.pt`` after the epoch of 0-based index ``epoch`` (the loop's); ``best`` names its epoch from 1."""
    return {
        "epoch": epoch,
        EPOCHS_FROM: 1,
        "config": asdict(t.cfg),
        "class_names": t.class_names,
        "anchors": t.anchors,
        "model": t.model.state_dict(),
        "ema": t.ema.state_dict(),
        "optimizer": t.optimizer.state_dict(),
        "scaler": t.scaler.state_dict(),
        "best": best,
    }


def _trained_by(config: dict[str, Any]) -> dict[str, Any]:
    """A config without what only chooses the exported weights (``select``: a finished run resumed with another
    ``select`` exports those weights without training again)."""
    return {k: v for k, v in config.items() if k != "select"}


def _resume(t: Trainer, out: Path) -> tuple[int, dict[str, Any]]:
    """Load ``out/last.pt`` when present: returns (0-based index of the first epoch to run, best-so-far record
    with its epoch counted from 1)."""
    last = out / "last.pt"
    if not last.is_file():
        return 0, {"fitness": -1.0, "epoch": 0}
    state = torch.load(last, map_location=t.device, weights_only=False)
    if _trained_by(state["config"]) != _trained_by(asdict(t.cfg)) or state["class_names"] != t.class_names:
        raise ResumeError(f"{last}: the run there used another config or classes; choose another --out")
    t.model.load_state_dict(state["model"])
    t.ema.load_state_dict(state["ema"])
    t.optimizer.load_state_dict(state["optimizer"])
    t.scaler.load_state_dict(state.get("scaler", {}))
    if EPOCHS_FROM not in state:  # a run begun by a version that counted epochs from 0
        _count_from_one(out, state["best"])
    return int(state["epoch"]) + 1, state["best"]


def _count_from_one(out: Path, best: dict[str, Any]) -> None:
    """Renumber a run folder written with epochs counted from 0: ``best`` and ``metrics.jsonl``."""
    best["epoch"] = int(best["epoch"]) + 1
    path = out / "metrics.jsonl"
    if path.is_file():
        rows = [json.loads(ln) for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip()]
        path.write_text("".join(json.dumps({**r, "epoch": r["epoch"] + 1}, sort_keys=True) + "\n" for r in rows))


def _log_epoch(out: Path, record: dict[str, Any]) -> None:
    with open(out / "metrics.jsonl", "a", encoding="utf-8") as fh:
        fh.write(json.dumps(record, sort_keys=True) + "\n")


def _truncate_metrics(out: Path, done: int) -> None:
    """Keep the lines of ``metrics.jsonl`` of the first ``done`` epochs (counted from 1)."""
    path = out / "metrics.jsonl"
    if path.is_file():
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip()]
        kept = [ln for ln in lines if json.loads(ln)["epoch"] <= done]
        path.write_text("".join(ln + "\n" for ln in kept), encoding="utf-8")


def fit(cfg: TrainConfig, train_ds: Dataset, val_ds: Dataset, out: Path | str) -> dict[str, Any]:
    """Train ``cfg.epochs`` epochs on ``train_ds``, validate on ``val_ds`` each epoch, write the run folder.

    ``val_ds`` classes must be a subset of ``train_ds`` classes (matched by name). Returns ``results.json``.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    torch.set_flush_denormal(True)
    keep_freed_memory()
    if cfg.threads > 0:
        torch.set_num_threads(cfg.threads)
    val_ds = val_ds.with_categories(train_ds.category_names)
    t = build_trainer(cfg, train_ds)
    val_images = letterboxed_images(val_ds, cfg.imgsz, desc="decoding validation images")
    val_inputs = ValidationInputs(val_images, t.runner, cfg.batch)
    first, best = _resume(t, out)
    _truncate_metrics(out, first)
    for epoch in range(first, cfg.epochs):
        record = {"epoch": epoch + 1, **train_one_epoch(t, epoch)}  # outputs count epochs from 1
        start = time.perf_counter()
        record.update(evaluate(t.ema.ema, val_inputs, val_ds, t.class_names, cfg.imgsz, cfg.postprocess))
        record["val_seconds"] = time.perf_counter() - start
        if record["fitness"] > best["fitness"]:
            best = _record_of(record)
            _save(out / "best.pt", _best_weights(t))
        _log_epoch(out, record)
        _save(out / "last.pt", _checkpoint(t, epoch, best))
        print(_epoch_line(record, cfg.epochs))
    return _finish(t, out, best)


def keep_freed_memory() -> None:
    """Ask glibc to keep freed blocks instead of unmapping them: every batch allocates and frees the same large
    activations, and returning them to the kernel costs page faults on each step (~9 % of a CPU step). A no-op
    where the C library is not glibc."""
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name) if name else None
        if libc is not None and hasattr(libc, "mallopt"):
            libc.mallopt(-3, 1 << 30)  # M_MMAP_THRESHOLD: allocations below 1 GiB come from the heap
            libc.mallopt(-1, 1 << 30)  # M_TRIM_THRESHOLD: keep up to 1 GiB of free heap
    except OSError:
        pass


def _best_weights(t: Trainer) -> dict[str, Any]:
    return {
        "model": {k: v.detach().cpu() for k, v in t.ema.ema.state_dict().items()},
        "class_names": t.class_names,
        "anchors": t.anchors,
        "config": asdict(t.cfg),
    }


def load_detector(path: Path | str) -> tuple[Detector, list[str], int]:
    """A ``best.pt``/``last.pt`` file -> (detector in eval mode with its EMA weights, class names, imgsz)."""
    state = torch.load(path, map_location="cpu", weights_only=False)
    saved = {**state["config"]["model"], "anchors": state["anchors"], "autoanchor": False, "pretrained": False}
    saved["freeze"] = 0  # the weights are all in the file
    imgsz = int(state["config"]["imgsz"])
    model = build_model(len(state["class_names"]), DetectorConfig(**saved), imgsz)
    model.load_state_dict(state["model"] if "ema" not in state else state["ema"]["weights"])
    return model.eval(), list(state["class_names"]), imgsz


def _epoch_line(record: dict[str, Any], epochs: int) -> str:
    return (
        f"epoch {record['epoch']}/{epochs}  loss box {record['loss_box']:.4f} obj {record['loss_obj']:.4f} "
        f"cls {record['loss_cls']:.4f}  AP50 {record['AP50']:.4f}  AP {record['AP']:.4f}  "
        f"fitness {record['fitness']:.4f}  {record['train_images_per_s']:.1f} img/s"
    )


def _record_of(metrics: dict[str, Any]) -> dict[str, Any]:
    """An epoch's metrics as ``results.json`` names its best and selected epochs: epoch, fitness, AP, AP50."""
    return {k: metrics[k] for k in ("epoch", "fitness", "AP", "AP50") if k in metrics}


def _finish(t: Trainer, out: Path, best: dict[str, Any]) -> dict[str, Any]:
    """Export the selected EMA weights (``cfg.select``: ``best.onnx`` from the best epoch's, or ``last.onnx`` from
    the last epoch's) and write ``results.json`` (``best`` and ``selected``: epoch, fitness, AP, AP50)."""
    chosen = out / f"{t.cfg.select}.pt"  # best.pt or last.pt (EMA weights in both)
    onnx = out / f"{t.cfg.select}.onnx"
    if chosen.is_file():
        model, names, imgsz = load_detector(chosen)
        export_onnx(model, onnx, imgsz, names)
    metrics = read_metrics(out / "metrics.jsonl")
    plot_curves(metrics, out / "curves.png", title=out.name)
    results = {
        "best": best,
        "selected": best if t.cfg.select == "best" else _record_of(metrics[-1] if metrics else {}),
        "config": asdict(t.cfg),
        "class_names": t.class_names,
        "anchors": t.anchors,
        "onnx": onnx.name if onnx.is_file() else None,
        "device": str(t.device),
        "versions": versions(),
        "lock": lock_status(),
        "git_commit": git_commit(),
    }
    (out / "results.json").write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    return results

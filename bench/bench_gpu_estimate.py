"""How long configs/paper.yaml takes on one GPU: an ESTIMATE from measured CPU figures, since no GPU is here.

Measured on this machine: the study detector's forward FLOPs per image at the config's size (frozen part and
trainable part, counted by ``torch.utils.flop_counter.FlopCounterMode``) and the augmentation rate of one CPU
core at that size (mosaic, affine, HSV, flip; images of ../shared/data/fire-cctv-416). Assumed: a training step
costs the frozen forward plus 3x the trainable forward (backward ~2x forward); validation every epoch on the
config's validation split; the GPU sustains ``--tflops`` (default 10 TFLOP/s, mixed precision; depthwise
convolutions keep small detectors far below a GPU's peak); ``workers`` augmentation processes (8, the config's
default on a GPU) feed it.

Lines: ``gpu_estimate_frozen_gflop_per_image``, ``gpu_estimate_trainable_gflop_per_image``,
``gpu_estimate_augment_images_per_s_per_core``, ``gpu_estimate_runs``, ``gpu_estimate_compute_hours``,
``gpu_estimate_loading_hours``, ``gpu_estimate_hours`` (the larger of the two: they overlap).

.venv/bin/python bench/bench_gpu_estimate.py [--tflops 10] [--workers 8]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import torch
from torch.utils.flop_counter import FlopCounterMode

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "paper.yaml"
DATA = ROOT.parent / "shared" / "data" / "fire-cctv-416"


def gflop(fn, *args) -> float:
    """Forward GFLOP of ``fn(*args)`` for one image (args batch 1)."""
    counter = FlopCounterMode(display=False)
    with counter, torch.no_grad():
        fn(*args)
    return counter.get_total_flops() / 1e9


def augment_rate(imgsz: int, images: int = 64) -> float:
    """Augmented training samples per second on one core at ``imgsz``."""
    from ground.data.formats.registry import read_dataset
    from train.augment import AugmentConfig
    from train.data import TrainBatches, cache_images

    ds = read_dataset(DATA).dataset.select_split("train")
    keep = {img.id for img in ds.images[:images]}
    cache = cache_images(ds.filter_images(lambda img: img.id in keep), imgsz, workers=1)
    batches = TrainBatches(cache, imgsz, 16, AugmentConfig(), seed=0)
    start = time.perf_counter()
    for i in range(len(cache)):
        batches.sample(0, i)
    return len(cache) / (time.perf_counter() - start)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tflops", type=float, default=10.0, help="sustained GPU TFLOP/s (assumed)")
    parser.add_argument("--workers", type=int, default=8, help="augmentation processes feeding the GPU")
    args = parser.parse_args()
    if not DATA.is_dir():
        print(f"gpu_estimate_skipped: {DATA} not found", file=sys.stderr)
        return 0
    from curate.mix import parse_mixture
    from fuzzyfire.experiment_config import ExperimentConfig
    from ground.config.loader import load_config
    from train.model import build_model

    torch.set_num_threads(1)
    cfg = load_config(CONFIG, ExperimentConfig)
    size, epochs = cfg.train.imgsz, cfg.train.epochs
    model = build_model(1, replace(cfg.train.model, autoanchor=False), size).eval()
    x = torch.rand(1, 3, size, size)
    frozen = gflop(model.frozen_features, x)
    feats = model.frozen_features(x)
    trainable = gflop(model.forward_frozen, feats)
    rate = augment_rate(size)
    seeds = len(cfg.grid.seeds)
    table2 = [parse_mixture(m) for m in cfg.grid.mixtures]
    table1 = [parse_mixture(m) for m in cfg.grid.table1]  # trained again with the other method
    runs = seeds * (len(table2) + len(table1))
    train_images = seeds * epochs * (sum(m.real + m.synth for m in table2) + sum(m.real + m.synth for m in table1))
    val_images = runs * epochs * cfg.real.curate_config().split.sizes.get("valid", 200)
    flop = train_images * (frozen + 3 * trainable) * 1e9 + val_images * (frozen + trainable) * 1e9
    compute_h = flop / (args.tflops * 1e12) / 3600
    loading_h = train_images / (rate * args.workers) / 3600
    print(f"gpu_estimate_frozen_gflop_per_image: {frozen:.2f} GFLOP ({size} px, forward)")
    print(f"gpu_estimate_trainable_gflop_per_image: {trainable:.2f} GFLOP ({size} px, forward)")
    print(f"gpu_estimate_augment_images_per_s_per_core: {rate:.1f} img/s ({size} px)")
    print(
        f"gpu_estimate_runs: {runs} runs, {train_images / 1e6:.1f} M training images, {val_images / 1e6:.1f} M validation"
    )
    print(f"gpu_estimate_compute_hours: {compute_h:.1f} h at {args.tflops:g} TFLOP/s sustained (ESTIMATE)")
    print(f"gpu_estimate_loading_hours: {loading_h:.1f} h with {args.workers} augmentation workers (ESTIMATE)")
    print(f"gpu_estimate_hours: {max(compute_h, loading_h):.1f} h on one GPU (ESTIMATE, not measured)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

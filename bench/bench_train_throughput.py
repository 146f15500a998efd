"""Training throughput end to end (decoded-image cache -> mosaic/affine/HSV/flip -> forward, loss, backward,
SGD step, EMA) at 320 px, YOLOv5n-shaped model, batch 16, on the first 256 training images of
../shared/data/fire-cctv-416. Target >= 12 img/s on 2 idle cores. Also prints the augmentation-only and
forward/backward-only rates so a regression can be placed.

.venv/bin/python bench/bench_train_throughput.py [DATASET] [--imgsz 320] [--images 256] [--batches 12]
.venv/bin/python bench/bench_train_throughput.py --backbone efficientnet-lite0 --batches 4   # the GPU option
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import torch

from ground.data.formats.registry import read_dataset
from train.config import TrainConfig
from train.loop import build_trainer, train_one_epoch

DEFAULT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "fire-cctv-416"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("dataset", nargs="?", default=str(DEFAULT))
    parser.add_argument("--imgsz", type=int, default=320)
    parser.add_argument("--images", type=int, default=256)
    parser.add_argument("--batches", type=int, default=12)
    parser.add_argument("--backbone", default="cspdarknet", help="cspdarknet or efficientnet-lite0")
    args = parser.parse_args()
    if not Path(args.dataset).is_dir():
        print(f"train_throughput_skipped: {args.dataset} not found", file=sys.stderr)
        return 0
    ds = read_dataset(args.dataset).dataset
    ds = ds.select_split("train") if "train" in ds.splits else ds
    keep = {img.id for img in ds.images[: args.images]}
    ds = ds.filter_images(lambda img: img.id in keep)
    torch.set_flush_denormal(True)
    cfg = TrainConfig(epochs=10, imgsz=args.imgsz, batch=16, seed=0)
    t = build_trainer(replace(cfg, model=replace(cfg.model, autoanchor=False, backbone=args.backbone)), ds)
    t.model.train()

    start = time.perf_counter()
    batches = [b for _, b in zip(range(args.batches), t.batches.epoch(0))]
    aug = sum(b[0].shape[0] for b in batches) / (time.perf_counter() - start)

    t.loss_fn(t.model(batches[0][0]), batches[0][1])[0].backward()  # warm-up (allocator, kernels)
    t.optimizer.zero_grad()
    start = time.perf_counter()
    for images, targets in batches:
        t.loss_fn(t.model(images), targets)[0].backward()
    fwd_bwd = sum(b[0].shape[0] for b in batches) / (time.perf_counter() - start)
    t.optimizer.zero_grad()

    small = replace(t, batches=_Limited(t.batches, args.batches))
    record = train_one_epoch(small, 1)
    tag = f"{args.imgsz}" if args.backbone == "cspdarknet" else f"{args.imgsz}_{args.backbone}"
    threads = torch.get_num_threads()
    print(f"train_augment_only_{tag}: {aug:.1f} img/s")
    print(f"train_forward_backward_only_{tag}: {fwd_bwd:.1f} img/s")
    print(f"train_throughput_{tag}: {record['train_images_per_s']:.1f} img/s (target >= 12, {threads} threads)")
    return 0


class _Limited:
    """The first ``n`` batches of each epoch of a :class:`train.data.TrainBatches`."""

    def __init__(self, batches, n: int) -> None:
        self.inner, self.n = batches, n

    def __len__(self) -> int:
        return min(self.n, len(self.inner))

    def epoch(self, epoch: int, start: int = 0):
        for i, batch in enumerate(self.inner.epoch(epoch, start)):
            if i >= len(self):
                return
            yield batch


if __name__ == "__main__":
    sys.exit(main())

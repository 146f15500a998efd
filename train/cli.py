"""``fuzzyfire train``: train the detector on a dataset, validate every epoch, export ``RUN/best.onnx``."""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from curate.core.commands import add_command
from curate.core.formats.registry import FORMATS

_EXAMPLE = """example:
  fuzzyfire train --train out/mixtures/seed0/R500_S500 --val ../shared/data/fire-cctv-416 \\
      --out runs/R500_S500-seed0 --epochs 30 --imgsz 320 --seed 0
  fuzzyfire train --train ../shared/data/fire-smoke-608 --val ../shared/data/fire-smoke-608 \\
      --drop-class default --out runs/fs608 --epochs 3 --imgsz 160

A folder with splits trains on its 'train' split and validates on 'valid' (or 'val'); --train-split and
--val-split choose others. The run folder gets last.pt (resumable: run the same command again), best.pt
(EMA weights of the best epoch by fitness = 0.1 AP50 + 0.9 AP), metrics.jsonl (one line per epoch),
results.json and best.onnx (input 'images' N x 3 x H x W RGB in [0, 1], letterboxed; output N x A x (5 + C):
cx, cy, w, h in input pixels, objectness, class probabilities)."""

TRAIN_SPLITS = ("train",)
VAL_SPLITS = ("valid", "val", "validation")


def _read(path: str, fmt: str):  # -> curate.core.formats.common.ReadResult
    """The dataset at ``path``; the reader's errors go to stderr."""
    from curate.core.commands import print_problems
    from curate.core.formats.registry import read_dataset

    result = read_dataset(path, fmt)
    errors = [p for p in result.problems if p.level == "error"]
    if errors:
        print_problems(errors, sys.stderr, limit=20)
    return result


def _datasets(args: argparse.Namespace):  # -> (train, val) curate.core.dataset.Dataset
    """The training and validation splits (default: the first of :data:`TRAIN_SPLITS` / :data:`VAL_SPLITS`
    each has, else every image) without the ``--drop-class`` boxes, the training set with the ``--classes``
    list. Every class named must be a class of one of the two sets (:class:`~curate.core.names.UnknownNameError`)."""
    from curate.core.classes import canonical_class
    from curate.core.load import pick_split
    from curate.core.names import check_names, split_names

    reads = [_read(args.train, args.train_format), _read(args.val, args.val_format)]
    known = list(dict.fromkeys(n for r in reads for n in r.dataset.category_names))
    where = f"{args.train} and {args.val}"
    check_names(
        "class", [canonical_class(n) for n in split_names(args.drop_class)], known, where, "classes", "--drop-class"
    )
    train_read, val_read = (r.drop_classes(args.drop_class, missing_ok=True) for r in reads)
    train_ds = pick_split(train_read.dataset, args.train_split, args.train, TRAIN_SPLITS)
    val_ds = pick_split(val_read.dataset, args.val_split, args.val, VAL_SPLITS)
    if args.classes:
        classes = split_names([args.classes])
        kept = [*train_ds.category_names, *val_ds.category_names]
        check_names("class", classes, list(dict.fromkeys(kept)), where, "classes", "--classes")
        train_ds = train_ds.with_categories(classes)
    return train_ds, val_ds


def build_config(args: argparse.Namespace):
    """The run's TrainConfig: the defaults (the study's detector) with the flags given on the command line."""
    from train.config import TrainConfig
    from train.device import resolve_device

    cfg = TrainConfig()
    given = {
        k: getattr(args, k)
        for k in ("epochs", "imgsz", "batch", "seed", "threads", "device", "workers", "select", "real_finetune")
    }
    cfg = replace(cfg, **{k: v for k, v in given.items() if v is not None})
    if args.views is not None:
        cfg = replace(cfg, feature_views=args.views)
    model = {k: getattr(args, k) for k in ("size", "backbone", "freeze")}
    model = {k: v for k, v in model.items() if v is not None}
    if args.no_autoanchor:
        model["autoanchor"] = False
    cfg = replace(cfg, model=replace(cfg.model, **model))
    if args.optimizer is not None or args.lr0 is not None:
        optim = {"optimizer": args.optimizer, "lr0": args.lr0}
        cfg = replace(cfg, optim=replace(cfg.optim, **{k: v for k, v in optim.items() if v is not None}))
    if cfg.imgsz % 32:
        raise ValueError(f"--imgsz must be a multiple of 32, got {cfg.imgsz}")
    resolve_device(cfg.device)  # a device this machine lacks fails here, before any data is read
    return cfg


def cmd_train(args: argparse.Namespace) -> int:
    from train.loop import ResumeError, fit

    cfg = build_config(args)
    train_ds, val_ds = _datasets(args)
    same = Path(args.train).resolve() == Path(args.val).resolve()
    if same and {i.split for i in train_ds.images} & {i.split for i in val_ds.images}:
        raise ValueError(f"{args.train}: training and validation images are the same split; pass --val-split")
    print(f"train {len(train_ds.images)} images, val {len(val_ds.images)} images, classes {train_ds.category_names}")
    try:
        results = fit(cfg, train_ds, val_ds, args.out)
    except ResumeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    chosen = results["selected"]
    print(
        f"{cfg.select} epoch {chosen['epoch']}: AP {chosen['AP']:.4f}  AP50 {chosen['AP50']:.4f}  "
        f"fitness {chosen['fitness']:.4f}  -> {Path(args.out) / str(results['onnx'])}"
    )
    return 0


def _defaults():
    from train.config import TrainConfig

    return TrainConfig()


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``train`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "train",
        help="train the YOLOv5-style detector (CPU-first), validate each epoch, export best.onnx",
        description="Train a detector with the YOLOv5 recipe (mosaic, affine, HSV, flip; SGD; EMA; best epoch by\n"
        "fitness on the validation set).\n\n" + _EXAMPLE,
    )
    p.add_argument("--train", required=True, help="training dataset folder or COCO .json")
    p.add_argument("--val", required=True, help="validation dataset folder or COCO .json")
    p.add_argument("--out", required=True, type=Path, help="run folder (an existing run there is resumed)")
    defaults = _defaults()
    p.add_argument("--epochs", type=int, help=f"epochs (default {defaults.epochs})")
    p.add_argument("--imgsz", type=int, help=f"square input size, multiple of 32 (default {defaults.imgsz})")
    p.add_argument("--batch", type=int, help=f"images per forward/backward pass (default {defaults.batch})")
    p.add_argument("--seed", type=int, help="seed of weights, shuffles and augmentations (default 0)")
    p.add_argument("--size", choices=("n", "s", "m"), help=f"neck/head width and depth (default {defaults.model.size})")
    p.add_argument(
        "--backbone",
        choices=("cspdarknet", "efficientnet-lite0"),
        help="efficientnet-lite0 (ImageNet weights from the installed package) or cspdarknet (YOLOv5, from "
        f"scratch); default {defaults.model.backbone}",
    )
    p.add_argument(
        "--freeze",
        type=int,
        help="efficientnet-lite0 stages kept at their ImageNet weights, 0..7 (default: all 7)",
    )
    p.add_argument(
        "--views",
        type=int,
        help="augmented views per image whose frozen features are computed once (default "
        f"{defaults.feature_views}; 0 = fresh augmentation every epoch)",
    )
    p.add_argument("--optimizer", choices=("sgd", "adamw"), help=f"default {defaults.optim.optimizer}")
    p.add_argument("--lr0", type=float, help=f"initial learning rate (default {defaults.optim.lr0:g})")
    p.add_argument("--device", help="auto | cpu | cuda | cuda:N (default auto: the first GPU, else the CPU)")
    p.add_argument("--workers", type=int, help="data-loading processes (default: none on the CPU, 8 on a GPU)")
    p.add_argument("--threads", type=int, help="torch threads (default: torch's choice)")
    p.add_argument(
        "--select",
        choices=("best", "last"),
        help="weights exported: best (validation fitness, YOLOv5's rule; the default) or last (the last epoch's "
        "EMA: steadier when the validation set has only a few dozen images)",
    )
    p.add_argument(
        "--real-finetune",
        type=int,
        metavar="N",
        help="the last N epochs train only on the real images of a fuzzyfire mixture (sources not synth:); a "
        "real image's mosaic partners are real in every epoch (default 0: never)",
    )
    p.add_argument("--train-split", help="split of --train to use (default: train when present, else all)")
    p.add_argument("--val-split", help="split of --val to use (default: valid/val when present, else all)")
    formats = ("auto", *FORMATS)
    p.add_argument("--train-format", default="auto", choices=formats, help="format of --train (default: detect)")
    p.add_argument("--val-format", default="auto", choices=formats, help="format of --val (default: detect)")
    p.add_argument("--classes", help="training class names in output order, e.g. fire,smoke")
    p.add_argument(
        "--drop-class",
        action="append",
        default=[],
        metavar="NAME",
        help="drop a class in both sets (repeatable or a,b)",
    )
    p.add_argument("--no-autoanchor", action="store_true", help="keep the default anchors even when they fit badly")
    p.set_defaults(func=cmd_train)

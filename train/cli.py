"""``fuzzyfire train``: train the detector on a dataset, validate every epoch, export ``RUN/best.onnx``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings
from ground.data.formats.registry import FORMATS

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


def _read(path: str, fmt: str | None):  # -> ground.data.formats.common.ReadResult
    """The dataset at ``path``."""
    from ground.data.formats.registry import read_dataset

    return read_dataset(path, fmt)


def _per_folder(reads: dict[str, object], keep) -> dict[Path, tuple[str, list]]:
    """The problems ``keep`` picks of each dataset of ``reads`` (path -> ReadResult) that has any, by resolved
    folder (a folder read twice, as training and validation set, counts once): ``{folder: (path, problems)}``."""
    found: dict[Path, tuple[str, list]] = {}
    for path, read in reads.items():
        picked = [p for p in read.problems if keep(p)]  # type: ignore[attr-defined]
        if picked:
            found.setdefault(Path(path).resolve(), (path, picked))
    return found


def data_errors(reads: dict[str, object]) -> str:
    """``N validation error(s) in PATH (first error)`` of the datasets ``reads`` (path -> ReadResult; a folder
    read twice, as training and validation set, counts once); "" when none has an error."""
    found = _per_folder(reads, lambda p: p.level == "error")
    if not found:
        return ""
    count = sum(len(errors) for _, errors in found.values())
    where = " and ".join(f"{path} ({len(e)})" if len(found) > 1 else path for path, e in found.values())
    first_path, first_errors = next(iter(found.values()))
    listed = f"; fuzzyfire validate {first_path} lists them" if count > 1 else ""
    return f"{count} validation error{'s' if count > 1 else ''} in {where} ({first_errors[0]}{listed})"


def clipped_boxes(reads: dict[str, object]) -> str:
    """``; N boxes in PATH reached outside their image and were clipped to it`` for the datasets ``reads`` (a
    folder read twice counts once); "" when no box was clipped."""
    from ground.data.formats.common import CLIPPED

    counts = {path: len(found) for path, found in _per_folder(reads, lambda p: p.code == CLIPPED).values()}
    return "".join(f"; {n} box{'es' if n > 1 else ''} in {path} reached outside {'their' if n > 1 else 'its'} image "
                   f"and {'were' if n > 1 else 'was'} clipped to it" for path, n in counts.items())  # fmt: skip


def _datasets(args: argparse.Namespace, allow_errors: bool = False):  # -> (train, val, note)
    """The training and validation splits (default: the first of :data:`TRAIN_SPLITS` / :data:`VAL_SPLITS`
    each has, else every image) without the ``--drop-class`` boxes, the training set with the ``--classes``
    list, and a note for the summary line (boxes clipped to their image). Every class named must be a class of
    one of the two sets (:class:`~ground.data.names.UnknownNameError`). Data whose reading found errors raises
    ValueError naming the first, unless ``allow_errors`` (then one line says so on stderr)."""
    from ground.data.classes import canonical_class
    from ground.data.load import pick_split
    from ground.data.names import check_names, split_names

    reads = [_read(args.train, args.train_format), _read(args.val, args.val_format)]
    by_path = {args.train: reads[0], args.val: reads[1]} if args.train != args.val else {args.train: reads[0]}
    errors = data_errors(by_path)
    if errors and not allow_errors:
        raise ValueError(
            f"train: {errors}; fix the data or pass --allow-errors (train key allow_errors) to train anyway"
        )
    if errors:
        print(f"train: {errors}: training anyway (allow_errors)", file=sys.stderr)
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
    return train_ds, val_ds, clipped_boxes(by_path)


#: Flags of ``fuzzyfire train``: aliases of TrainConfig keys (their defaults are the keys').
ALIASES: tuple[Alias, ...] = (
    Alias("--epochs", ("epochs",), "training epochs", {"type": int}),
    Alias("--imgsz", ("imgsz",), "square input size, multiple of 32", {"type": int}),
    Alias("--batch", ("batch",), "images per forward/backward pass", {"type": int}),
    Alias("--seed", ("seed",), "seed of weights, shuffles and augmentations", {"type": int}),
    Alias("--size", ("model.size",), "neck/head width and depth", {"choices": ("n", "s", "m")}),
    Alias("--backbone", ("model.backbone",), "ImageNet Lite0, or YOLOv5's CSPDarknet from scratch",
          {"choices": ("cspdarknet", "efficientnet-lite0")}),
    Alias("--freeze", ("model.freeze",), "Lite0 stages kept at their ImageNet weights, 0..7", {"type": int}),
    Alias("--views", ("feature_views",), "augmented views per image of the frozen features", {"type": int}),
    Alias("--optimizer", ("optim.optimizer",), "optimizer", {"choices": ("sgd", "adamw")}),
    Alias("--lr0", ("optim.lr0",), "initial learning rate", {"type": float}),
    Alias("--device", ("device",), "auto | cpu | cuda | cuda:N", {}),
    Alias("--workers", ("workers",), "data-loading processes", {"type": int}),
    Alias("--threads", ("threads",), "torch threads; 0 = torch's choice", {"type": int}),
    Alias("--select", ("select",), "exported weights: best validation fitness, or the last epoch",
          {"choices": ("best", "last")}),
    Alias("--real-finetune", ("real_finetune",), "the last N epochs train on a mixture's real images only",
          {"type": int, "metavar": "N"}),
    Alias("--no-autoanchor", ("model.autoanchor",), "keep the default anchors even when they fit badly",
          {"action": "store_true"}, lambda _: {"model.autoanchor": False}),
    Alias("--allow-errors", ("allow_errors",), "train on data whose reading found errors (they are left out)",
          {"action": "store_true"}),
)  # fmt: skip


def build_config(args: argparse.Namespace):
    """The run's TrainConfig: CONFIG.yaml (or the defaults: the study's detector), the flags given, ``--set``."""
    from ground.cli.options import config_from_args
    from train.config import TrainConfig
    from train.device import resolve_device

    cfg = config_from_args(args, TrainConfig, ALIASES)
    resolve_device(cfg.device)  # a device this machine lacks fails here, before any data is read
    return cfg


def cmd_train(args: argparse.Namespace) -> int:
    from ground.cli.options import print_config
    from train.loop import ResumeError, fit

    cfg = build_config(args)
    if args.print_config:
        print_config(cfg)
        return 0
    if args.train is None or args.val is None or args.out is None:
        raise ValueError("--train, --val and --out are required (unless --print-config)")
    train_ds, val_ds, clipped = _datasets(args, cfg.allow_errors)
    same = Path(args.train).resolve() == Path(args.val).resolve()
    if same and {i.split for i in train_ds.images} & {i.split for i in val_ds.images}:
        from ground.data.load import splits_found

        raise ValueError(
            f"{args.train}: training and validation images are the same split ({splits_found(val_ds)}); "
            "pass --val-split"
        )
    print(
        f"train {len(train_ds.images)} images, val {len(val_ds.images)} images, classes {train_ds.category_names}"
        + clipped
    )
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


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``train`` to the ``fuzzyfire`` parser."""
    from train.config import TrainConfig

    p = add_command(
        sub,
        "train",
        help="train the YOLOv5-style detector (CPU-first), validate each epoch, export best.onnx",
        description="Train the study's detector (ImageNet EfficientNet-Lite0 + a YOLOv5-style head; mosaic, affine,\n"
        "HSV, flip; AdamW; EMA; best epoch by fitness on the validation set). Settings: CONFIG.yaml (a train\n"
        "section: docs/config.md#train), the options below, then --set KEY=VALUE.\n\n" + _EXAMPLE,
    )
    p.add_argument("--train", help="training dataset folder or COCO .json")
    p.add_argument("--val", help="validation dataset folder or COCO .json")
    p.add_argument("--out", type=Path, help="run folder (an existing run there is resumed)")
    p.add_argument("--train-split", help="split of --train to use (default: train when present, else all)")
    p.add_argument("--val-split", help="split of --val to use (default: valid/val when present, else all)")
    formats = ("auto", *FORMATS)
    p.add_argument("--train-format", choices=formats, help="format of --train (default: detect)")
    p.add_argument("--val-format", choices=formats, help="format of --val (default: detect)")
    p.add_argument("--classes", help="training class names in output order, e.g. fire,smoke")
    p.add_argument(
        "--drop-class",
        action="append",
        default=[],
        metavar="NAME",
        help="drop a class in both sets (repeatable or a,b)",
    )
    add_settings(p, TrainConfig, ALIASES, cmd_train)

"""``fuzzyfire mix``: write R(m)_S(n) training mixtures of a real and a synthetic dataset."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from curate.core.commands import add_command
from curate.core.load import SplitError, pick_split
from curate.core.writer import OutputError
from curate.mix import (
    MixError,
    check_available,
    paper_grid,
    parse_mixtures,
    parse_seeds,
    write_mixture,
)

_EXAMPLE = """example:
  fuzzyfire mix --real ../shared/data/fire-cctv-416 --synth out/method2 \\
      --mixtures R1000_S0,R750_S250,R500_S500 --seeds 0-4 --out out/mixtures
  fuzzyfire mix --real out/real --synth out/method2 --mixtures R500_S500 --val out/real --out out/mixtures
  fuzzyfire mix --real out/real --synth out/method2 --paper-grid --seed 0 --out out/mixtures

Writes OUT/seed<S>/R<m>_S<n>/ per mixture and seed: annotations.json (COCO), labels/ + data.yaml (YOLO),
manifest.json and mixture.json (which output file came from which source file). For one seed the draws are
nested: the real images of R250_S750 are inside those of R500_S500."""


def cmd_mix(args: argparse.Namespace) -> int:
    from curate.core.commands import command_args, print_problems
    from curate.core.formats.registry import read_dataset

    try:
        mixtures = paper_grid(args.total, args.step) if args.paper_grid else parse_mixtures(args.mixtures or "")
        seeds = parse_seeds(args.seeds)
        real_read = read_dataset(args.real, args.real_format)
        synth_read = read_dataset(args.synth, args.synth_format)
        real = pick_split(real_read.dataset, args.split, args.real, defaults=("train",))
        synth = pick_split(synth_read.dataset, args.split, args.synth, defaults=("train",))
        check_available(real, synth, mixtures)
        val = None
        if args.val:
            val = pick_split(
                read_dataset(args.val, args.val_format).dataset, args.val_split, args.val, defaults=("val",)
            )
    except (MixError, SplitError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print_problems([p for p in real_read.problems + synth_read.problems if p.level == "error"], sys.stderr, limit=20)
    classes = [c for c in (args.classes or "").split(",") if c]
    for seed in seeds:
        for mix in mixtures:
            try:
                folder = write_mixture(
                    real, synth, mix, seed, args.out, args.images, classes, command_args(args), args.overwrite, val
                )
            except (MixError, OutputError) as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 2
            print(f"wrote {folder}: {mix.real} real + {mix.synth} synthetic images (seed {seed})")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``mix`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "mix",
        help="write R(m)_S(n) mixtures of real and synthetic images (nested seeded draws)",
        description="Draw training mixtures of m real and n synthetic images with a seed.\n\n" + _EXAMPLE,
    )
    p.add_argument("--real", required=True, help="real dataset folder or COCO .json")
    p.add_argument("--synth", required=True, help="synthetic dataset folder or COCO .json")
    group = p.add_mutually_exclusive_group(required=True)
    group.add_argument("--mixtures", help="comma-separated names, e.g. R1000_S0,R750_S250,R500_S500")
    group.add_argument(
        "--paper-grid",
        action="store_true",
        help="the paper's strategies: R250..R1000_S0, R750_S250, R500_S500, R250_S750, R0_S250..R0_S1000",
    )
    p.add_argument("--total", type=int, default=1000, help="--paper-grid: images per mixture (default 1000)")
    p.add_argument("--step", type=int, default=250, help="--paper-grid: step between sizes (default 250)")
    p.add_argument("--seeds", "--seed", dest="seeds", default="0", help="seed(s): 0, 0-4 or 0,3,7 (default 0)")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument("--split", help="split to draw from in both sources (default: train when present, else all)")
    p.add_argument("--classes", help="class names in YOLO id order (default: real's classes, then synthetic's)")
    p.add_argument(
        "--images",
        default="symlink",
        choices=("symlink", "hardlink", "copy"),
        help="how images reach the mixture (default symlink: referenced, not copied)",
    )
    p.add_argument(
        "--val",
        help="YOLO validation set whose images data.yaml's val names (default: the training images), "
        "e.g. the real set's valid split; its class ids must be the mixture's",
    )
    p.add_argument("--val-split", help="split of --val (default: val or valid when present, else all)")
    p.add_argument("--val-format", default="auto", help="format of --val (default: detect)")
    p.add_argument("--real-format", default="auto", help="format of --real (default: detect)")
    p.add_argument("--synth-format", default="auto", help="format of --synth (default: detect)")
    p.add_argument("--overwrite", action="store_true", help="replace mixtures already at --out")
    p.set_defaults(func=cmd_mix)

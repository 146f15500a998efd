"""``fuzzyfire mix``: write R(m)_S(n) training mixtures of a real and a synthetic dataset."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from curate.core.commands import add_command
from curate.core.dataset import Dataset
from curate.core.formats.registry import FORMATS
from curate.core.load import SplitError, pick_split
from curate.core.names import check_names, split_names
from curate.core.problems import Problem
from curate.core.writer import OutputError, check_output_folder
from curate.mix import (
    MixError,
    Mixture,
    build_mixture,
    check_available,
    mixture_dir,
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


def _sources(args: argparse.Namespace) -> tuple[Dataset, Dataset, list[Problem]]:
    """The real and synthetic pools: each its own split (``--real-split`` / ``--synth-split``, else the shared
    ``--split``, else ``train`` when present, else every image) and the reader's errors."""
    from curate.core.formats.registry import read_dataset

    real_read = read_dataset(args.real, args.real_format)
    synth_read = read_dataset(args.synth, args.synth_format)
    real_split = args.split if args.real_split is None else args.real_split
    synth_split = args.split if args.synth_split is None else args.synth_split
    real = pick_split(real_read.dataset, real_split, args.real, defaults=("train",))
    synth = pick_split(synth_read.dataset, synth_split, args.synth, defaults=("train",))
    errors = [p for p in real_read.problems + synth_read.problems if p.level == "error"]
    return real, synth, errors


def _validation(args: argparse.Namespace) -> Dataset | None:
    """The ``--val`` set's split, or None; ``--val-split`` / ``--val-format`` without ``--val`` are refused."""
    from curate.core.formats.registry import read_dataset

    if args.val is None:
        given = [o for o, v in (("--val-split", args.val_split), ("--val-format", args.val_format)) if v is not None]
        if given:
            raise MixError(f"{' and '.join(given)} describe --val, which is not given")
        return None
    where = Path(args.val).resolve()  # data.yaml names its image folders by this path: no '..' in it
    return pick_split(read_dataset(where, args.val_format or "auto").dataset, args.val_split, args.val, ("val",))


def _grid(args: argparse.Namespace) -> list[Mixture]:
    """The mixtures asked for; ``--total`` / ``--step`` only with ``--paper-grid``."""
    if args.paper_grid:
        return paper_grid(1000 if args.total is None else args.total, 250 if args.step is None else args.step)
    given = [o for o, v in (("--total", args.total), ("--step", args.step)) if v is not None]
    if given:
        raise MixError(f"{' and '.join(given)} size the --paper-grid; --mixtures names its sizes itself")
    return parse_mixtures(args.mixtures or "")


def _check_outputs(
    real: Dataset, synth: Dataset, plan: list[tuple[int, Mixture]], args: argparse.Namespace, classes: list[str]
) -> None:
    """Every mixture folder checked before the first is written (:func:`curate.core.writer.check_output_folder`)."""
    for seed, mix in plan:
        folder = mixture_dir(args.out, mix, seed)
        check_output_folder(folder, build_mixture(real, synth, mix, seed, folder, classes), args.overwrite)


def cmd_mix(args: argparse.Namespace) -> int:
    from curate.core.commands import command_args, print_problems

    try:
        mixtures, seeds = _grid(args), parse_seeds(args.seeds)
        real, synth, errors = _sources(args)
        check_available(real, synth, mixtures)
        classes = split_names([args.classes or ""])
        known = list(dict.fromkeys(real.category_names + synth.category_names))
        check_names("class", classes, known, f"{args.real} and {args.synth}", "classes", "--classes")
        val = _validation(args)
        plan = [(seed, mix) for seed in seeds for mix in mixtures]
        _check_outputs(real, synth, plan, args, classes)
    except (MixError, SplitError, OutputError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if errors:
        print_problems(errors, sys.stderr, limit=20)
    for seed, mix in plan:
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
    p.add_argument("--total", type=int, help="--paper-grid: images per mixture (default 1000)")
    p.add_argument("--step", type=int, help="--paper-grid: step between sizes (default 250)")
    p.add_argument("--seeds", "--seed", dest="seeds", default="0", help="seed(s): 0, 0-4 or 0,3,7 (default 0)")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--split",
        help="split to draw from in both sources, unless --real-split / --synth-split say otherwise (default: "
        "train when present, else every image)",
    )
    p.add_argument("--real-split", help="split of --real to draw from (default: --split)")
    p.add_argument("--synth-split", help="split of --synth to draw from (default: --split)")
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
    formats = ("auto", *FORMATS)
    p.add_argument("--val-format", choices=formats, help="format of --val (default: detect)")
    p.add_argument("--real-format", default="auto", choices=formats, help="format of --real (default: detect)")
    p.add_argument("--synth-format", default="auto", choices=formats, help="format of --synth (default: detect)")
    p.add_argument("--overwrite", action="store_true", help="replace mixtures already at --out")
    p.set_defaults(func=cmd_mix)

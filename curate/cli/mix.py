"""``fuzzyfire mix``: write R(m)_S(n) training mixtures of a real and a synthetic dataset."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from curate.mix import (
    MixConfig,
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
from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings, one_of
from ground.data.dataset import Dataset
from ground.data.formats.registry import FORMATS
from ground.data.load import pick_split
from ground.data.names import check_names, split_names
from ground.data.problems import Problem
from ground.data.writer import check_output_folder

_EXAMPLE = """example:
  fuzzyfire mix --real ../shared/data/fire-cctv-416 --synth out/method2 \\
      --mixtures R1000_S0,R750_S250,R500_S500 --seeds 0-4 --out out/mixtures
  fuzzyfire mix --real out/real --synth out/method2 --mixtures R500_S500 --val out/real --out out/mixtures
  fuzzyfire mix --real out/real --synth out/method2 --paper-grid --seed 0 --out out/mixtures

Writes OUT/seed<S>/R<m>_S<n>/ per mixture and seed: annotations.json (COCO), labels/ + data.yaml (YOLO),
manifest.json and mixture.json (which output file came from which source file). For one seed the draws are
nested: the real images of R250_S750 are inside those of R500_S500."""


def _seeds(text: str) -> list[int]:
    try:
        return parse_seeds(text)
    except MixError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


#: Flags of ``fuzzyfire mix``: aliases of :class:`curate.mix.MixConfig` keys (their defaults are the keys').
ALIASES: tuple[Alias, ...] = (
    Alias("--mixtures", ("mixtures",), "comma-separated names, e.g. R1000_S0,R750_S250,R500_S500",
          {"type": lambda text: split_names([text])}),
    Alias("--paper-grid", ("paper_grid",), "the paper's strategies: R250..R1000_S0, R750_S250, R500_S500, R250_S750, "
          "R0_S250..R0_S1000", {"action": "store_true"}),
    Alias("--total", ("total",), "--paper-grid: images per mixture", {"type": int}),
    Alias("--step", ("step",), "--paper-grid: step between sizes", {"type": int}),
    Alias("--seeds", ("seeds",), "seed(s): 0, 0-4 or 0,3,7", {"type": _seeds}),
    Alias("--seed", ("seeds",), "the same as --seeds", {"type": _seeds, "metavar": "SEEDS"}),
    Alias("--split", ("split",), "split to draw from in both sources, unless --real-split / --synth-split say "
          "otherwise (null: train when present, else every image)", {}),
    Alias("--real-split", ("real_split",), "split of --real to draw from (null: --split)", {}),
    Alias("--synth-split", ("synth_split",), "split of --synth to draw from (null: --split)", {}),
    Alias("--real-format", ("real_format",), "format of --real", one_of(("auto", *FORMATS))),
    Alias("--synth-format", ("synth_format",), "format of --synth", one_of(("auto", *FORMATS))),
    Alias("--val-split", ("val_split",), "split of --val (null: val or valid when present, else all)", {}),
    Alias("--val-format", ("val_format",), "format of --val", one_of(("auto", *FORMATS))),
    Alias("--classes", ("classes",), "class names in YOLO id order (empty: real's classes, then synthetic's)",
          {"type": lambda text: split_names([text])}),
    Alias("--images", ("images",), "how images reach the mixture (symlink: referenced, not copied)",
          one_of(("symlink", "hardlink", "copy"))),
)  # fmt: skip


def _sources(args: argparse.Namespace, cfg: MixConfig) -> tuple[Dataset, Dataset, list[Problem]]:
    """The real and synthetic pools: each its own split (``real_split`` / ``synth_split``, else the shared
    ``split``, else ``train`` when present, else every image) and the reader's errors."""
    from ground.data.formats.registry import read_dataset

    real_read = read_dataset(args.real, cfg.real_format)
    synth_read = read_dataset(args.synth, cfg.synth_format)
    real_split = cfg.split if cfg.real_split is None else cfg.real_split
    synth_split = cfg.split if cfg.synth_split is None else cfg.synth_split
    real = pick_split(real_read.dataset, real_split, args.real, defaults=("train",))
    synth = pick_split(synth_read.dataset, synth_split, args.synth, defaults=("train",))
    errors = [p for p in real_read.problems + synth_read.problems if p.level == "error"]
    return real, synth, errors


def _changed(cfg: MixConfig, keys: dict[str, str]) -> list[str]:
    """The flags of ``keys`` ({flag: key}) whose keys ``cfg`` holds at other values than their defaults."""
    default = MixConfig()
    return [flag for flag, key in keys.items() if getattr(cfg, key) != getattr(default, key)]


def _validation(args: argparse.Namespace, cfg: MixConfig) -> Dataset | None:
    """The ``--val`` set's split, or None; ``val_split`` / ``val_format`` without ``--val`` are refused."""
    from ground.data.formats.registry import read_dataset

    if args.val is None:
        given = _changed(cfg, {"--val-split": "val_split", "--val-format": "val_format"})
        if given:
            raise MixError(f"{' and '.join(given)} describe --val, which is not given")
        return None
    where = Path(args.val).resolve()  # data.yaml names its image folders by this path: no '..' in it
    return pick_split(read_dataset(where, cfg.val_format).dataset, cfg.val_split, args.val, ("val",))


def _grid(cfg: MixConfig) -> list[Mixture]:
    """The mixtures asked for: the names, or the paper's grid (``total`` / ``step`` size only that)."""
    if cfg.paper_grid and cfg.mixtures:
        raise MixError("--mixtures and --paper-grid both name the mixtures: give one")
    if cfg.paper_grid:
        return paper_grid(cfg.total, cfg.step)
    given = _changed(cfg, {"--total": "total", "--step": "step"})
    if given:
        raise MixError(f"{' and '.join(given)} size the --paper-grid; --mixtures names its sizes itself")
    if not cfg.mixtures:
        raise MixError("--mixtures or --paper-grid is required (keys mixtures, paper_grid)")
    return parse_mixtures(",".join(cfg.mixtures))


def _check_outputs(real: Dataset, synth: Dataset, plan: list[tuple[int, Mixture]], args: argparse.Namespace,
                   classes: list[str]) -> None:  # fmt: skip
    """Every mixture folder checked before the first is written (:func:`ground.data.writer.check_output_folder`)."""
    for seed, mix in plan:
        folder = mixture_dir(args.out, mix, seed)
        check_output_folder(folder, build_mixture(real, synth, mix, seed, folder, classes), args.overwrite)


def cmd_mix(args: argparse.Namespace) -> int:
    from ground.cli.commands import print_problems, settings_args
    from ground.cli.options import command_config

    cfg = command_config(args, MixConfig, ALIASES, {"--real": args.real, "--synth": args.synth, "--out": args.out})
    if cfg is None:
        return 0
    mixtures, seeds = _grid(cfg), list(cfg.seeds)
    real, synth, errors = _sources(args, cfg)
    check_available(real, synth, mixtures)
    classes = list(cfg.classes)
    known = list(dict.fromkeys(real.category_names + synth.category_names))
    check_names("class", classes, known, f"{args.real} and {args.synth}", "classes", "--classes")
    val = _validation(args, cfg)
    plan = [(seed, mix) for seed in seeds for mix in mixtures]
    _check_outputs(real, synth, plan, args, classes)
    if errors:
        print_problems(errors, sys.stderr, limit=20)
    provenance = settings_args(args, cfg, ALIASES)
    for seed, mix in plan:
        folder = write_mixture(real, synth, mix, seed, args.out, cfg.images, classes, provenance, args.overwrite, val)
        print(f"wrote {folder}: {mix.real} real + {mix.synth} synthetic images (seed {seed})")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``mix`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "mix",
        help="write R(m)_S(n) mixtures of real and synthetic images (nested seeded draws)",
        description="Draw training mixtures of m real and n synthetic images with a seed. Settings: CONFIG.yaml\n"
        "(docs/config.md#mix), the options below, then --set KEY=VALUE.\n\n" + _EXAMPLE,
    )
    p.add_argument("--real", help="real dataset folder or COCO .json")
    p.add_argument("--synth", help="synthetic dataset folder or COCO .json")
    p.add_argument("--out", type=Path, help="output folder")
    p.add_argument(
        "--val",
        help="YOLO validation set whose images data.yaml's val names (default: the training images), "
        "e.g. the real set's valid split; its class ids must be the mixture's",
    )
    p.add_argument("--overwrite", action="store_true", help="replace mixtures already at --out")
    add_settings(p, MixConfig, ALIASES, cmd_mix)

"""The ``fuzzyfire`` console script: subcommands gathered from each package's ``cli.register``."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from pathlib import Path

from fuzzyfire import __version__

#: Modules whose ``register(subparsers)`` adds commands, in help order (imported when the parser is built).
COMMAND_MODULES: tuple[str, ...] = (
    "curate.cli",
    "curate.cli_mix",
    "curate.cli_curation",
    "synth.cli",
    "train.cli",
    "eval.cli",
    "fuzzyfire.cmd_curate",
    "fuzzyfire.cmd_experiment",
)


def cmd_merge(args: argparse.Namespace) -> int:
    from curate.cli import print_problems
    from curate.core.config import ConfigError, load_config, to_dict
    from curate.core.writer import OutputError, write_dataset
    from curate.sources import MergeConfig, merge_sources

    try:
        cfg = load_config(args.config, MergeConfig, args.set)
    except ConfigError as exc:
        print(f"error: {args.config}: {exc}", file=sys.stderr)
        return 2
    ds, problems = merge_sources(cfg, Path(args.config).resolve().parent, args.out)
    try:
        written = write_dataset(
            ds,
            args.out,
            ("coco", "yolo"),
            args.images,
            command="merge",
            args={"config": to_dict(cfg), "set": args.set},
            sources=[Path(args.config)],
            overwrite=args.overwrite,
        )
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print_problems([p for p in problems + written.problems if p.level != "info"], sys.stderr, limit=50)
    print(f"wrote {args.out}: {len(ds.images)} images, {len(ds.annotations)} boxes from {len(cfg.sources)} sources")
    return 0


def _register_merge(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "merge",
        help="merge labelled sources listed in a YAML config into one dataset",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Merge datasets of any format into one COCO + YOLO folder with a fixed class list.\n\n"
        "example:\n  fuzzyfire merge configs/merge-shared.yaml --out out/merged --set classes=[fire]",
    )
    p.add_argument("config", help="YAML file (see configs/merge-shared.yaml)")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="override a config key, e.g. classes=[fire]"
    )
    p.add_argument("--images", default="copy", choices=("copy", "hardlink", "symlink"))
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    p.set_defaults(func=cmd_merge)


def build_parser() -> argparse.ArgumentParser:

    parser = argparse.ArgumentParser(
        prog="fuzzyfire",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Build and judge detectors of fuzzy objects (fire, smoke) from real and synthetic images.\n\n"
        "example:\n  fuzzyfire convert ../shared/data/fire-smoke-608 --to coco --out out/fs608\n"
        "  fuzzyfire validate out/fs608",
    )
    parser.add_argument("--version", action="version", version=f"fuzzyfire {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    _register_merge(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args))
    except (FileNotFoundError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

"""Helpers for every package's commands (``<package>/cli.py``): the options of a command that reads a dataset,
its arguments for the manifest, problems printed one per line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import TextIO

from curate.core.formats.registry import FORMATS
from curate.core.problems import Problem, count_levels


def add_reader_args(p: argparse.ArgumentParser) -> None:
    """Options every command that reads a dataset accepts."""
    p.add_argument(
        "--from", dest="fmt", default="auto", choices=("auto", *FORMATS), help="source format (default: detect)"
    )
    p.add_argument(
        "--names",
        type=lambda s: [n.strip() for n in s.split(",") if n.strip()],
        help="YOLO class names in id order, e.g. fire,smoke",
    )
    p.add_argument(
        "--alias",
        action="append",
        default=[],
        metavar="NAME=CLASS",
        help="map a source class to a class, e.g. --alias flame_big=fire (repeatable)",
    )
    p.add_argument(
        "--drop-class",
        action="append",
        default=[],
        metavar="NAME",
        help="remove the boxes of a class (its images stay, possibly as negatives); repeatable or comma-separated",
    )
    p.add_argument("--source", help="source tag for every image (default: real:<folder name>)")


def parse_aliases(items: Sequence[str]) -> dict[str, str]:
    """``--alias NAME=CLASS`` values (see :func:`add_reader_args`) -> ``{NAME: CLASS}``."""
    out = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"--alias {item!r}: expected NAME=CLASS")
        key, _, value = item.partition("=")
        out[key.strip()] = value.strip()
    return out


def command_args(args: argparse.Namespace) -> dict:
    """The user's arguments of a command, for its manifest (no internal parser fields)."""
    return {k: v for k, v in vars(args).items() if k not in ("func", "command")}


def print_problems(problems: Sequence[Problem], stream: TextIO | None = None, limit: int | None = None) -> None:
    """One ``path: reason`` line per problem on ``stream`` (stdout), then the counts on stderr."""
    stream = stream or sys.stdout
    shown = problems if limit is None else problems[:limit]
    for p in shown:
        print(p, file=stream)
    if limit is not None and len(problems) > limit:
        print(f"... and {len(problems) - limit} more (see --json)", file=stream)
    stream.flush()
    counts = count_levels(problems)
    print(f"{counts['error']} errors, {counts['warning']} warnings, {counts['info']} info", file=sys.stderr)

"""``fuzzyfire convert | validate | stats``: dataset commands. Each ``cmd_*`` returns an exit code."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

from curate.core.formats.registry import FORMATS, read_dataset
from curate.core.problems import Problem, count_levels, has_errors
from curate.core.writer import IMAGE_MODES, OUTPUT_FORMATS, OutputError, write_dataset
from curate.stats import dataset_stats, plot_box_sizes
from curate.validate import validate


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


def _aliases(items: Sequence[str]) -> dict[str, str]:
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


def cmd_convert(args: argparse.Namespace) -> int:
    result = read_dataset(args.src, args.fmt, names=args.names, source=args.source, aliases=_aliases(args.alias))
    result = result.drop_classes(args.drop_class)
    ds = result.dataset
    formats = list(OUTPUT_FORMATS) if args.to == "all" else [args.to]
    try:
        written = write_dataset(
            ds, args.out, formats, args.images, command="convert", args=command_args(args), overwrite=args.overwrite
        )
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    problems = result.problems + written.problems
    shown = [p for p in problems if p.level != "info"]
    print_problems(shown, sys.stderr, limit=50)
    print(
        f"wrote {args.out}: {len(ds.images)} images, {len(ds.annotations)} boxes, "
        f"{ds.num_negatives()} negatives, classes {ds.category_names} ({', '.join(written.files.values())})"
    )
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    result = validate(args.src, args.fmt, names=args.names, aliases=_aliases(args.alias), decode=not args.no_decode)
    ds, problems = result.dataset, result.problems
    stats = dataset_stats(ds, result.unlabelled)
    if args.json:
        doc = {
            "images": len(ds.images),
            "boxes": len(ds.annotations),
            "negatives": stats["negatives"],
            "negatives_by_origin": stats["negatives_by_origin"],
            "counts": count_levels(problems),
            "problems": [p.to_dict() for p in problems],
        }
        print(json.dumps(doc, indent=1, ensure_ascii=False))
    else:
        print_problems(problems)
        origin = stats["negatives_by_origin"]
        print(
            f"{len(ds.images)} images, {len(ds.annotations)} boxes, {stats['negatives']} negatives "
            f"({origin['no_label_file']} without a label file, {origin['empty_labels']} with an empty one)",
            file=sys.stderr,
        )
    return 1 if has_errors(problems) else 0


def cmd_stats(args: argparse.Namespace) -> int:
    result = read_dataset(args.src, args.fmt, names=args.names, source=args.source, aliases=_aliases(args.alias))
    result = result.drop_classes(args.drop_class)
    ds = result.dataset
    stats = dataset_stats(ds, result.unlabelled)
    png = Path(args.png) if args.png else None
    if png is not None:
        plot_box_sizes(ds, png, title=f"{Path(args.src).name}: {stats['images']} images, {stats['boxes']} boxes")
        stats["histogram_png"] = str(png)
    if args.json:
        print(json.dumps(stats, indent=1, ensure_ascii=False))
        return 0
    origin = stats["negatives_by_origin"]
    print(
        f"images     {stats['images']}  (negatives {stats['negatives']}: {origin['no_label_file']} without a label "
        f"file, {origin['empty_labels']} with an empty one)"
    )
    print(f"boxes      {stats['boxes']}  " + "  ".join(f"{k} {v}" for k, v in stats["boxes_per_class"].items()))
    print("sizes      " + "  ".join(f"{k} {v}" for k, v in stats["box_sizes"].items()) + "  (COCO area buckets)")
    for split, entry in stats["per_split"].items():
        print(f"split {split:<8} " + "  ".join(f"{k} {v}" for k, v in entry.items()))
    if png is not None:
        print(f"histogram  {png}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the dataset commands to the ``fuzzyfire`` parser."""
    fmt = argparse.RawDescriptionHelpFormatter
    p = sub.add_parser(
        "convert",
        help="convert a dataset (YOLO, D-Fire, VOC, COCO) to COCO and/or YOLO",
        formatter_class=fmt,
        description="Convert a dataset to a self-describing folder (images/, annotations.json and/or labels/ + data.yaml,\n"
        "manifest.json). The source folder is never modified.\n\n"
        "example:\n  fuzzyfire convert ../shared/data/fire-smoke-608 --to coco --out out/fire-smoke-coco\n"
        "  fuzzyfire convert DFireDataset --from dfire --to all --out out/dfire --images hardlink",
    )
    p.add_argument("src", help="dataset folder or COCO .json")
    p.add_argument("--to", required=True, choices=(*OUTPUT_FORMATS, "all"), help="output format (all = COCO + YOLO)")
    p.add_argument("--out", required=True, type=Path, help="output folder (must not be inside the source)")
    p.add_argument(
        "--images",
        default="copy",
        choices=IMAGE_MODES,
        help="how images reach the output (reference = absolute paths, COCO only)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    add_reader_args(p)
    p.set_defaults(func=cmd_convert)

    p = sub.add_parser(
        "validate",
        help="report every problem in a dataset, one 'path: reason' line each",
        formatter_class=fmt,
        description="Check a dataset: unreadable images, labels without images, negatives, class ids out of range,\n"
        "boxes outside the image, zero area, NaN, duplicate stems. Exit code 1 when there are errors.\n\n"
        "example:\n  fuzzyfire validate ../shared/data/fire-cctv-416\n  fuzzyfire validate my_voc_folder --json > problems.json",
    )
    p.add_argument("src", help="dataset folder or COCO .json")
    p.add_argument("--json", action="store_true", help="print a JSON document instead of lines")
    p.add_argument("--no-decode", action="store_true", help="check headers only (faster, misses truncated images)")
    add_reader_args(p)
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser(
        "stats",
        help="counts per split and class, negatives, box sizes, histogram PNG",
        formatter_class=fmt,
        description="Summarise a dataset.\n\nexample:\n  fuzzyfire stats ../shared/data/fire-smoke-608 --png sizes.png",
    )
    p.add_argument("src", help="dataset folder or COCO .json")
    p.add_argument("--png", help="write a box-size histogram to this PNG file")
    p.add_argument("--json", action="store_true", help="print JSON")
    add_reader_args(p)
    p.set_defaults(func=cmd_stats)

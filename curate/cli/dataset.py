"""``fuzzyfire convert | validate | stats | merge``: dataset commands. Each ``cmd_*`` returns an exit code."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from curate.sources import MergeConfig
from curate.stats import dataset_stats, plot_box_sizes
from curate.validate import validate
from ground.cli.commands import (
    add_command,
    add_reader_args,
    parse_aliases,
    print_problems,
    read_from_args,
    write_dataset_or_report,
)
from ground.cli.options import Alias, add_settings, one_of
from ground.data.formats.images import NEGATIVES_ONLY
from ground.data.problems import count_levels, has_errors
from ground.data.writer import DEFAULT_IMAGE_MODE, IMAGE_MODES, OUTPUT_FORMATS


def cmd_convert(args: argparse.Namespace) -> int:
    result = read_from_args(args)
    ds = result.dataset
    formats = list(OUTPUT_FORMATS) if args.to == "all" else [args.to]
    written = write_dataset_or_report(ds, args, "convert", formats, args.images or DEFAULT_IMAGE_MODE)
    if written is None:
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
    aliases = parse_aliases(args.alias)
    result = validate(
        args.src, args.fmt, names=args.names, aliases=aliases, decode=not args.no_decode, alias_option="--alias"
    )
    result = result.drop_classes(args.drop_class)
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
    result = read_from_args(args)
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
    crowd = "  ".join(f"{k} {v}" for k, v in stats["boxes_by_crowding"].items())
    print(f"crowding   {crowd}  (boxes in images that hold 1, 2, 3-4, 5+ boxes)")
    for split, entry in stats["per_split"].items():
        print(f"split {split:<8} " + "  ".join(f"{k} {v}" for k, v in entry.items()))
    for note in (p for p in result.problems if p.code == NEGATIVES_ONLY):
        print(f"set        {note.reason}")
    if png is not None:
        print(f"histogram  {png}")
    return 0


#: ``images`` of merge and curate (:class:`curate.sources.MergeConfig`).
IMAGES_ALIAS = Alias("--images", ("images",), "how images reach --out", one_of(("copy", "hardlink", "symlink")))
#: Flags of ``fuzzyfire merge``: aliases of :class:`curate.sources.MergeConfig` keys (their defaults are the keys').
MERGE_ALIASES: tuple[Alias, ...] = (IMAGES_ALIAS,)


def cmd_merge(args: argparse.Namespace) -> int:
    from curate.sources import merge_sources
    from ground.cli.options import command_config

    cfg = command_config(args, MergeConfig, MERGE_ALIASES, {"--out": args.out})
    if cfg is None:
        return 0
    ds, problems = merge_sources(cfg, Path(args.config).resolve().parent, args.out)
    written = write_dataset_or_report(ds, args, "merge", ("coco", "yolo"), cfg.images, cfg)
    if written is None:
        return 2
    print_problems([p for p in problems + written.problems if p.level != "info"], sys.stderr, limit=50)
    print(f"wrote {args.out}: {len(ds.images)} images, {len(ds.annotations)} boxes from {len(cfg.sources)} sources")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``convert``, ``validate``, ``stats`` and ``merge`` to the ``fuzzyfire`` parser."""
    _register_convert(sub)
    _register_inspect(sub)
    _register_merge(sub)


def _register_convert(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "convert",
        help="convert a dataset (YOLO, D-Fire, VOC, COCO) to COCO and/or YOLO",
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
        choices=IMAGE_MODES,
        help=f"how images reach the output (reference = absolute paths, COCO only; default: {DEFAULT_IMAGE_MODE})",
    )
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    add_reader_args(p)
    p.set_defaults(func=cmd_convert)


def _register_inspect(sub: argparse._SubParsersAction) -> None:
    """``validate`` and ``stats``: commands that read a dataset and write nothing but a report."""
    p = add_command(
        sub,
        "validate",
        help="report every problem in a dataset, one 'path: reason' line each",
        description="Check a dataset: unreadable images, labels without images, negatives, class ids out of range,\n"
        "boxes outside the image, zero area, NaN, duplicate stems. Exit code 1 when there are errors.\n\n"
        "example:\n  fuzzyfire validate ../shared/data/fire-cctv-416\n  fuzzyfire validate my_voc_folder --json > problems.json",
    )
    p.add_argument("src", help="dataset folder or COCO .json")
    p.add_argument("--json", action="store_true", help="print a JSON document instead of lines")
    p.add_argument("--no-decode", action="store_true", help="check headers only (faster, misses truncated images)")
    add_reader_args(p, source=False)
    p.set_defaults(func=cmd_validate)

    p = add_command(
        sub,
        "stats",
        help="counts per split and class, negatives, box sizes, histogram PNG",
        description="Summarise a dataset.\n\nexample:\n  fuzzyfire stats ../shared/data/fire-smoke-608 --png sizes.png",
    )
    p.add_argument("src", help="dataset folder or COCO .json")
    p.add_argument("--png", help="write a box-size histogram to this PNG file")
    p.add_argument("--json", action="store_true", help="print JSON")
    add_reader_args(p)
    p.set_defaults(func=cmd_stats)


def _register_merge(sub: argparse._SubParsersAction) -> None:
    p = add_command(
        sub,
        "merge",
        help="merge labelled sources listed in a YAML config into one dataset",
        description="Merge datasets of any format into one COCO + YOLO folder with a fixed class list. Settings:\n"
        "CONFIG.yaml (docs/config.md#merge; source paths relative to its folder), the options below, then\n"
        "--set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire merge configs/merge-shared.yaml --out out/merged --set classes=[fire]",
    )
    p.add_argument("--out", type=Path, help="output folder")
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    add_settings(p, MergeConfig, MERGE_ALIASES, cmd_merge, required=True)

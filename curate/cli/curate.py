"""``fuzzyfire curate CONFIG``: the FiIW-style curation of labelled sources into a leakage-free dataset."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from curate.core.commands import add_command


def cmd_curate(args: argparse.Namespace) -> int:
    from curate.core.commands import config_provenance, load_config_or_report, print_problems
    from curate.core.dataset import Dataset
    from curate.core.writer import OutputError, check_output_folder
    from curate.curation import CurateConfig, curate_dataset
    from curate.embed import embedding_cache_path

    cfg = load_config_or_report(args.config, CurateConfig, args.set)
    if cfg is None:
        return 2
    base = Path(args.config).resolve().parent
    roots = [str((s.path if s.path.is_absolute() else base / s.path).resolve()) for s in cfg.sources]
    provenance = config_provenance("curate", args, cfg)
    try:
        check_output_folder(args.out, Dataset(args.out, info={"source_roots": roots}), args.overwrite)  # fail now
        cache = None if args.no_cache else args.cache or embedding_cache_path()
        result, files = curate_dataset(cfg, base, args.out, cache, provenance, args.overwrite)
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print_problems([p for p in result.problems if p.level != "info"], sys.stderr, limit=50)
    c, splits = result.document["counts"], result.document["splits"]
    print(
        f"{c['images']} images: {c['removed_exact']} exact + {c['removed_near']} near duplicates removed, "
        f"{len(result.dataset.images)} selected -> " + ", ".join(f"{k} {v}" for k, v in splits.items())
    )
    print(f"wrote {args.out} (COCO + YOLO + manifest), {files['json'].name}, {files['report'].name}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``curate`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "curate",
        help="merge labelled sources, remove duplicates, keep the most diverse, split without leakage",
        description="FiIW-style curation: merge sources -> exact and near duplicates -> diversity ranking -> top N ->\n"
        "seeded split where no group of near duplicates straddles two splits. Writes a COCO + YOLO dataset with\n"
        "manifest.json, curation.json, report.html and distances.png. Sources are never modified.\n\n"
        "example:\n  fuzzyfire curate configs/curate-shared.yaml --out out/curated\n"
        "  fuzzyfire curate configs/curate-shared.yaml --out out/fiiw --set rank.top=1400 "
        "--set 'split.sizes={train: 1000, valid: 200, test: 200}'",
    )
    p.add_argument("config", help="YAML file (see configs/curate-shared.yaml)")
    p.add_argument("--out", required=True, type=Path, help="output dataset folder")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a config key")
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    p.add_argument("--cache", type=Path, help="embedding cache file (default: user cache dir)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the embedding cache")
    p.set_defaults(func=cmd_curate)

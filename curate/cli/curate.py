"""``fuzzyfire curate CONFIG``: the FiIW-style curation of labelled sources into a leakage-free dataset."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from curate.cli.dataset import IMAGES_ALIAS
from curate.cli.dedup import EXECUTOR_ALIASES, SEARCH_ALIASES, add_cache_args, embedding_run_aliases
from curate.curation import CurateConfig
from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings

#: Flags of ``fuzzyfire curate``: aliases of :class:`curate.curation.CurateConfig` keys (their defaults are the keys').
ALIASES: tuple[Alias, ...] = (
    *SEARCH_ALIASES,
    Alias("--seed", ("split.seed",), "seed of the split", {"type": int}),
    IMAGES_ALIAS,
    *embedding_run_aliases(),
    *EXECUTOR_ALIASES,
)


def cmd_curate(args: argparse.Namespace) -> int:
    from curate.curation import curate_dataset
    from curate.embed import embedding_cache_path
    from ground.cli.commands import config_provenance, print_problems
    from ground.cli.options import command_config
    from ground.data.dataset import Dataset
    from ground.data.writer import check_output_folder

    cfg = command_config(args, CurateConfig, ALIASES, {"--out": args.out})
    if cfg is None:
        return 0
    base = Path(args.config).resolve().parent
    roots = [str((s.path if s.path.is_absolute() else base / s.path).resolve()) for s in cfg.sources]
    check_output_folder(args.out, Dataset(args.out, info={"source_roots": roots}), args.overwrite)  # fail now
    cache = None if args.no_cache else args.cache or embedding_cache_path()
    provenance = config_provenance("curate", args, cfg)
    result, files = curate_dataset(cfg, base, args.out, cache, provenance, args.overwrite)
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
        "manifest.json, curation.json, report.html and distances.png. Sources are never modified. Settings:\n"
        "CONFIG.yaml (docs/config.md#curate; source paths relative to its folder), the options below, then\n"
        "--set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire curate configs/curate-shared.yaml --out out/curated\n"
        "  fuzzyfire curate configs/curate-shared.yaml --out out/fiiw --top 1400 "
        "--set 'split.sizes={train: 1000, valid: 200, test: 200}'",
    )
    p.add_argument("--out", type=Path, help="output dataset folder")
    p.add_argument("--overwrite", action="store_true", help="replace a fuzzyfire dataset already at --out")
    add_cache_args(p)
    add_settings(p, CurateConfig, ALIASES, cmd_curate, required=True)

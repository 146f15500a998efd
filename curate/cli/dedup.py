"""``fuzzyfire dedup`` and ``fuzzyfire leakage``: duplicate finding on image folders. Each ``cmd_*``
returns an exit code. Also the flags ``curate`` and ``synth gap`` share with them: the embedding model's, where it
runs, the duplicate search's (each an alias of a key of :mod:`curate.settings`)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from curate.dedupjob import APPLY_MODES
from curate.partition import PARTITION
from curate.rank import RANK_METHODS
from curate.search import BACKENDS
from curate.settings import PREPROCESSING, DedupJobConfig, EmbedderConfig, LeakageJobConfig
from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings, one_of
from ground.run.cluster import EXECUTOR_CHOICES, Cluster, open_cluster
from ground.run.device import parse_device


def _floats3(text: str) -> tuple[float, float, float]:
    values = tuple(float(v) for v in text.split(","))
    if len(values) != 3:
        raise argparse.ArgumentTypeError(f"expected three comma-separated numbers, got {text!r}")
    return values  # type: ignore[return-value]


def model_aliases(prefix: str = "model.") -> tuple[Alias, ...]:
    """Flags of the embedding model and its preprocessing: aliases of :class:`curate.settings.EmbedderConfig` keys
    under ``prefix`` (its section in a command's settings; "" for the EmbedderConfig itself)."""
    return (
        Alias("--model", (f"{prefix}path",), "ONNX file of your own CNN (embedding = its first output); null: the "
              "built-in ImageNet EfficientNet-Lite0", {"type": Path, "metavar": "ONNX"}),
        Alias("--input-size", (f"{prefix}input_size",), "your model's input side S in pixels", {"type": int}),
        Alias("--mean", (f"{prefix}mean",), "your model's per-channel mean (0..255)",
              {"type": _floats3, "metavar": "R,G,B"}),
        Alias("--std", (f"{prefix}std",), "your model's per-channel std (0..255)",
              {"type": _floats3, "metavar": "R,G,B"}),
        Alias("--bgr", (f"{prefix}bgr",), "your model expects BGR channel order", {"action": "store_true"}),
        Alias("--nhwc", (f"{prefix}layout",), "your model's input is (N, S, S, 3)", {"action": "store_true"},
              lambda _: {f"{prefix}layout": "nhwc"}),
        Alias("--blur", (f"{prefix}blur",), "Gaussian sigma in input pixels after resizing", {"type": float}),
        Alias("--output", (f"{prefix}output",), "name of your model's output to use as the embedding", {}),
    )  # fmt: skip


def embedding_run_aliases(prefix: str = "model.") -> tuple[Alias, ...]:
    """Flags of how the embedding runs (speed only: any value gives the same vectors)."""
    return (
        Alias("--workers", (f"{prefix}workers",), "decode + embed threads; 0 = one per core", {"type": int}),
        Alias("--batch-size", (f"{prefix}batch_size",), "images per onnxruntime call", {"type": int}),
        Alias("--device", (f"{prefix}device",), "auto | cpu | cuda | cuda:N: onnxruntime's CUDA provider when "
              "installed (auto: if present)", {}),
    )  # fmt: skip


#: Where hashing, decoding and embedding run: aliases of :class:`curate.settings.ExecutorConfig` keys.
EXECUTOR_ALIASES: tuple[Alias, ...] = (
    Alias("--executor", ("executor.name",), "local (a thread per core) or ray (Ray workers decode and embed; the "
          "same results; docs/scaling.md)", one_of(EXECUTOR_CHOICES)),
    Alias("--address", ("executor.address",), "with --executor ray: a running cluster (HOST:6379); null: a local Ray",
          {}),
)  # fmt: skip

#: Which images are duplicates and how the kept ones are ranked: ``dedup`` and ``curate`` alike.
SEARCH_ALIASES: tuple[Alias, ...] = (
    Alias("--threshold", ("dedup.threshold",), "near-duplicate distance", {"type": float}),
    Alias("--exact-only", ("dedup.near",), "remove exact duplicates only", {"action": "store_true"},
          lambda _: {"dedup.near": False}),
    Alias("--backend", ("dedup.backend",), "search backend", one_of(("auto", *BACKENDS, PARTITION))),
    Alias("--rank", ("rank.method",), "diversity ranking", one_of(RANK_METHODS)),
    Alias("--k", ("rank.k",), "neighbours in the diversity score", {"type": int}),
    Alias("--top", ("rank.top",), "select only the N most diverse kept images", {"type": int, "metavar": "N"}),
)  # fmt: skip

#: Flags of ``fuzzyfire dedup``: aliases of :class:`curate.settings.DedupJobConfig` keys.
DEDUP_ALIASES: tuple[Alias, ...] = (
    *SEARCH_ALIASES,
    Alias("--calibrate", ("calibrate",), "pick the threshold from augmented copies of your images",
          {"action": "store_true"}),
    Alias("--precision", ("precision",), "target (balanced) pair precision for --calibrate", {"type": float}),
    Alias("--seed", ("seed",), "seed for --calibrate", {"type": int}),
    *model_aliases(),
    *embedding_run_aliases(),
    *EXECUTOR_ALIASES,
)  # fmt: skip

#: Flags of ``fuzzyfire leakage``: aliases of :class:`curate.settings.LeakageJobConfig` keys.
LEAKAGE_ALIASES: tuple[Alias, ...] = (
    Alias("--threshold", ("threshold",), "near-duplicate distance", {"type": float}),
    Alias("--backend", ("backend",), "search backend", one_of(("auto", *BACKENDS))),
    Alias("--show", ("show",), "pairs printed", {"type": int, "metavar": "N"}),
    *model_aliases(),
    *embedding_run_aliases(),
    *EXECUTOR_ALIASES,
)  # fmt: skip

_USER_MODEL = (
    "A user ONNX model (--model) gets the image resized to S x S (stretched), blurred (--blur), RGB (or --bgr),\n"
    "scaled (pixel - mean) / std with pixel in 0..255, NCHW (or --nhwc); each image is embedded whole and as its\n"
    "centre 80 percent; VGG16/ResNet exports: --mean 123.675,116.28,103.53 --std 58.395,57.12,57.375."
)


def add_cache_args(p: argparse.ArgumentParser) -> None:
    """The embedding cache's options (a file of this machine, no setting of the results)."""
    p.add_argument("--cache", type=Path, help="embedding cache file (default: user cache dir)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the embedding cache")


def load_model(cfg: EmbedderConfig, args: argparse.Namespace):  # noqa: ANN201 - (OnnxEmbedder, EmbeddingCache | None)
    """The embedder of ``cfg`` (its notice on stderr) and the embedding cache of ``--cache`` / ``--no-cache``
    (None with ``--no-cache``). Preprocessing keys describe a user model: set without one, they are refused."""
    from curate.curation import build_embedder
    from curate.embed import embedding_cache_path
    from curate.embedcache import EmbeddingCache

    default = EmbedderConfig()
    custom = [k for k in PREPROCESSING if getattr(cfg, k) != getattr(default, k)]
    if cfg.path is None and custom:
        raise ValueError(
            f"preprocessing keys ({', '.join(custom)}; flags --input-size --mean --std --bgr --nhwc --output "
            "--blur) describe a user model: they need --model (model.path)"
        )
    embedder = build_embedder(cfg)
    if embedder.notice:
        print(embedder.notice, file=sys.stderr)
    cache = None if args.no_cache else EmbeddingCache(args.cache or embedding_cache_path())
    return embedder, cache


@contextmanager
def embedding_session(
    cfg: DedupJobConfig | LeakageJobConfig, args: argparse.Namespace
) -> Iterator[tuple[Any, Any, Cluster | None]]:
    """(embedder, cache or None, cluster or None) of the settings ``cfg`` (its ``model`` and ``executor``) and the
    cache options of ``args``: a bad device or address fails before anything starts; the cache and the cluster are
    closed on exit."""
    parse_device(cfg.model.device)
    cluster = open_cluster(cfg.executor.name, cfg.executor.address)
    try:
        embedder, cache = load_model(cfg.model, args)
        try:
            yield embedder, cache, cluster
        finally:
            if cache is not None:
                cache.close()
    finally:
        if cluster is not None:
            cluster.close()


def cmd_dedup(args: argparse.Namespace) -> int:
    from curate.dedupjob import check_apply_target
    from curate.scan import list_images_or_fail, scan_images
    from ground.cli.options import command_config

    cfg = command_config(args, DedupJobConfig, DEDUP_ALIASES, {"DIR": args.dirs, "--out": args.out})
    if cfg is None:
        return 0
    if args.apply and not args.to:
        raise ValueError("--apply needs --to DIR")
    paths = list_images_or_fail(args.dirs)
    if args.apply:
        check_apply_target(args.dirs, args.to, args.apply)
    with embedding_session(cfg, args) as (embedder, cache, cluster):
        scan = scan_images(paths, embedder, cache, cfg.model.workers, cfg.model.batch_size, cluster)
        return _dedup_scanned(args, cfg, paths, embedder, scan, cluster)


def _dedup_scanned(args: argparse.Namespace, cfg: DedupJobConfig, paths: list[Path], embedder, scan, cluster) -> int:  # noqa: ANN001
    """Duplicates, ranking, outputs and ``--apply`` of a finished scan (``cluster``: a partitioned search's)."""
    from dataclasses import asdict, replace

    from curate.dedupjob import (
        apply_selection,
        dedup_document,
        dedup_options,
        run_dedup,
        unreadable_summary,
        write_outputs,
    )

    if not scan.images:
        for problem in scan.problems:
            print(problem, file=sys.stderr)
        raise ValueError(f"none of the {len(paths)} image files in {', '.join(map(str, args.dirs))} can be read")
    search, calib = cfg.dedup, None
    if cfg.calibrate:
        from curate.calibrate import calibrate_threshold

        readable = [Path(im.path) for im in scan.images]
        calib = calibrate_threshold(readable, embedder, cfg.precision, cfg.seed)
        search = replace(search, threshold=calib.threshold)
        print(calib.summary())
    opts = dedup_options(search, cfg.rank, cfg.model, tuple(args.protect))
    run = run_dedup(paths, embedder, None, opts, scan, cluster)
    doc = dedup_document(run, opts, [str(Path(d).resolve()) for d in args.dirs])
    if calib is not None:
        doc["calibration"] = asdict(calib)
    files = write_outputs(run, doc, args.out)
    for problem in run.scan.problems:
        print(problem, file=sys.stderr)
    c = doc["counts"]
    print(
        f"{c['images']} images: kept {c['kept']}, removed {c['removed_exact']} exact + {c['removed_near']} near "
        f"({c['groups']} groups), {unreadable_summary(run.scan.problems)}; threshold {opts.threshold:.3f}"
    )
    print(f"wrote {files['json']}, {files['report']}, {files['histogram']}")
    if args.apply:
        n = apply_selection(doc["selected"], [Path(d) for d in args.dirs], args.to, args.apply)
        print(f"{args.apply} {n} images to {args.to}")
    return 0


def cmd_leakage(args: argparse.Namespace) -> int:
    import json

    from curate.leakage import find_leaks, leak_summary
    from curate.scan import list_images_or_fail, scan_images
    from ground.cli.options import command_config

    cfg = command_config(args, LeakageJobConfig, LEAKAGE_ALIASES, {"A": args.a, "B": args.b})
    if cfg is None:
        return 0
    listed = [list_images_or_fail([d]) for d in (args.a, args.b)]
    with embedding_session(cfg, args) as (embedder, cache, cluster):
        scans = [scan_images(p, embedder, cache, cfg.model.workers, cfg.model.batch_size, cluster) for p in listed]
    leaks = find_leaks(scans[0], scans[1], cfg.threshold, cfg.backend)
    summary = leak_summary(scans[0], scans[1], leaks)
    for problem in scans[0].problems + scans[1].problems:
        print(problem, file=sys.stderr)
    for leak in leaks[: cfg.show]:
        print(f"{leak.kind} {leak.distance:.3f}  {leak.a}  {leak.b}")
    if len(leaks) > cfg.show:
        print(
            f"... and {len(leaks) - cfg.show} more"
            + (f" (see {args.json})" if args.json else " (--json FILE writes every pair)")
        )
    print(
        f"{summary['pairs']} duplicate pairs ({summary['exact_pairs']} exact): {summary['a_with_leak']} of "
        f"{summary['images_a']} images in A have a duplicate among the {summary['images_b']} in B "
        f"(threshold {cfg.threshold:.3f})"
    )
    if args.json:
        doc = {
            "a": str(args.a.resolve()),
            "b": str(args.b.resolve()),
            "model": scans[0].model_id,
            "threshold": cfg.threshold,
            "summary": summary,
            "leaks": [{"a": x.a, "b": x.b, "kind": x.kind, "distance": round(x.distance, 5)} for x in leaks],
            "problems": [p.to_dict() for p in scans[0].problems + scans[1].problems],
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return 1 if leaks else 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``dedup`` and ``leakage`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "dedup",
        help="find exact and near-duplicate images in folders, rank the rest by diversity",
        description="Find exact duplicates (same bytes or same pixels) and near duplicates (CNN embeddings closer\n"
        "than --threshold), keep the best copy of each (protected > resolution > sharpness > file size > path),\n"
        "rank the kept images by diversity. Writes OUT/dedup.json, OUT/report.html, OUT/distances.png.\n"
        "Originals are never moved or deleted; --apply copies or links the kept (or --top) images elsewhere.\n"
        "Settings: --config CONFIG.yaml (docs/config.md#dedup), the options below, then --set KEY=VALUE.\n"
        + _USER_MODEL
        + "\n\n"
        "example:\n  fuzzyfire dedup ../shared/data/fire-cctv-416 --out out/dedup-cctv\n"
        "  fuzzyfire dedup photos/ web/ --protect photos/ --top 1400 --apply copy --to out/kept\n"
        "  fuzzyfire dedup imgs/ --out out/d --model vgg16.onnx --mean 123.675,116.28,103.53 --std 58.395,57.12,57.375",
    )
    p.add_argument("dirs", nargs="*", type=Path, metavar="DIR", help="image folders (searched recursively) or files")
    p.add_argument("--out", type=Path, help="folder for dedup.json, report.html, distances.png")
    p.add_argument("--protect", action="append", default=[], type=Path, metavar="DIR", help="never remove images here")
    p.add_argument("--apply", choices=APPLY_MODES, help="materialise the selected images in --to")
    p.add_argument("--to", type=Path, help="target folder for --apply (new or empty)")
    add_cache_args(p)
    add_settings(p, DedupJobConfig, DEDUP_ALIASES, cmd_dedup, flag="--config")

    p = add_command(
        sub,
        "leakage",
        help="report exact and near-duplicate images shared by two sets (e.g. train vs test)",
        description="List every pair (image in A, image in B) that is an exact copy (same bytes or pixels) or a near\n"
        "duplicate (embeddings closer than --threshold). Exit code 1 when any pair is found (use it in CI).\n"
        "Settings: --config CONFIG.yaml (docs/config.md#leakage), the options below, then --set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire leakage ../shared/data/fire-smoke-608/train ../shared/data/fire-smoke-608/test\n"
        "  fuzzyfire leakage out/curated/images/train out/curated/images/test --json out/leaks.json",
    )
    p.add_argument("a", type=Path, nargs="?", metavar="A", help="first image folder (e.g. the training images)")
    p.add_argument("b", type=Path, nargs="?", metavar="B", help="second image folder (e.g. the test images)")
    p.add_argument("--json", type=Path, help="write every pair to this JSON file")
    add_cache_args(p)
    add_settings(p, LeakageJobConfig, LEAKAGE_ALIASES, cmd_leakage, flag="--config")

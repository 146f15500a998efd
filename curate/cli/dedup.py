"""``fuzzyfire dedup`` and ``fuzzyfire leakage``: duplicate finding on image folders. Each ``cmd_*``
returns an exit code."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from curate.core.cluster import EXECUTOR_CHOICES, Cluster, open_cluster
from curate.core.commands import add_command
from curate.core.device import parse_device
from curate.dedup import DEFAULT_THRESHOLD
from curate.partition import PARTITION
from curate.rank import RANK_METHODS
from curate.search import BACKENDS


def _floats3(text: str) -> tuple[float, float, float]:
    values = tuple(float(v) for v in text.split(","))
    if len(values) != 3:
        raise argparse.ArgumentTypeError(f"expected three comma-separated numbers, got {text!r}")
    return values  # type: ignore[return-value]


def add_model_args(p: argparse.ArgumentParser) -> None:
    """Embedding model, its preprocessing, and the embedding cache."""
    g = p.add_argument_group(
        "embedding model",
        "default: the built-in ImageNet EfficientNet-Lite0. A user ONNX model gets the image resized to "
        "SIZE x SIZE (stretched), blurred (--blur), RGB (or --bgr), scaled (pixel - mean) / std with pixel in "
        "0..255, NCHW (or --nhwc); each image is embedded whole and as its centre 80 percent; VGG16/ResNet exports: --mean 123.675,116.28,103.53 --std 58.395,57.12,57.375",
    )
    g.add_argument("--model", type=Path, help="ONNX file of your own CNN (embedding = its first output)")
    g.add_argument("--input-size", type=int, default=224, help="model input side S in pixels (default 224)")
    g.add_argument("--mean", type=_floats3, default=(127.0, 127.0, 127.0), help="per-channel mean (0..255)")
    g.add_argument("--std", type=_floats3, default=(128.0, 128.0, 128.0), help="per-channel std (0..255)")
    g.add_argument("--bgr", action="store_true", help="the model expects BGR channel order")
    g.add_argument("--nhwc", action="store_true", help="the model input is (N, S, S, 3)")
    g.add_argument("--blur", type=float, default=0.0, help="Gaussian sigma in input pixels after resizing (default 0)")
    g.add_argument("--output", help="name of the model output to use as the embedding")
    g.add_argument("--cache", type=Path, help="embedding cache file (default: user cache dir)")
    g.add_argument("--no-cache", action="store_true", help="do not read or write the embedding cache")
    g.add_argument("--workers", type=int, default=0, help="decode + embed threads (default 0 = one per core)")
    g.add_argument("--batch-size", type=int, default=4, help="images per onnxruntime call (default 4)")
    g.add_argument(
        "--device",
        default="auto",
        help="auto | cpu | cuda | cuda:N: onnxruntime's CUDA provider when installed (default auto: if present)",
    )


def add_executor_args(p: argparse.ArgumentParser) -> None:
    """Where hashing, decoding and embedding run (:func:`embedding_session`)."""
    g = p.add_argument_group("where it runs", "docs/scaling.md: decoding and embedding on a Ray cluster")
    g.add_argument(
        "--executor",
        default="local",
        choices=EXECUTOR_CHOICES,
        help="local (default: a thread per core) or ray (Ray workers decode and embed; same results)",
    )
    g.add_argument("--address", help="with --executor ray: a running cluster (HOST:6379); default a local Ray")


def load_model_from_args(args: argparse.Namespace):  # noqa: ANN201 - (OnnxEmbedder, EmbeddingCache | None)
    from curate.embed import Preprocess, embedding_cache_path, load_embedder
    from curate.embedcache import EmbeddingCache

    if args.model is None:
        custom = (args.input_size, args.mean, args.std, args.bgr, args.nhwc, args.output, args.blur)
        if custom != (224, (127.0, 127.0, 127.0), (128.0, 128.0, 128.0), False, False, None, 0.0):
            raise ValueError(
                "preprocessing flags (--input-size --mean --std --bgr --nhwc --output --blur) need --model"
            )
        embedder = load_embedder(device=args.device)
    else:
        pre = Preprocess(args.input_size, args.mean, args.std, args.bgr, "nhwc" if args.nhwc else "nchw", args.blur)
        embedder = load_embedder(args.model, pre, output=args.output, device=args.device)
    if embedder.notice:
        print(embedder.notice, file=sys.stderr)
    cache = None if args.no_cache else EmbeddingCache(args.cache or embedding_cache_path())
    return embedder, cache


@contextmanager
def embedding_session(args: argparse.Namespace) -> Iterator[tuple[Any, Any, Cluster | None]]:
    """(embedder, cache or None, cluster or None) of :func:`add_model_args` and :func:`add_executor_args`: a bad
    device or address fails before anything starts; the cache and the cluster are closed on exit."""
    parse_device(args.device)
    cluster = open_cluster(args.executor, args.address)
    try:
        embedder, cache = load_model_from_args(args)
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

    if args.apply and not args.to:
        raise ValueError("--apply needs --to DIR")
    paths = list_images_or_fail(args.dirs)
    if args.apply:
        check_apply_target(args.dirs, args.to, args.apply)
    with embedding_session(args) as (embedder, cache, cluster):
        scan = scan_images(paths, embedder, cache, args.workers, args.batch_size, cluster)
        return _dedup_scanned(args, paths, embedder, scan, cluster)


def _dedup_scanned(args: argparse.Namespace, paths: list[Path], embedder, scan, cluster) -> int:  # noqa: ANN001
    """Duplicates, ranking, outputs and ``--apply`` of a finished scan (``cluster``: a partitioned search's)."""
    from dataclasses import asdict

    from curate.dedupjob import (
        DedupOptions,
        apply_selection,
        dedup_document,
        run_dedup,
        unreadable_summary,
        write_outputs,
    )

    if not scan.images:
        for problem in scan.problems:
            print(problem, file=sys.stderr)
        raise ValueError(f"none of the {len(paths)} image files in {', '.join(map(str, args.dirs))} can be read")
    threshold, calib = args.threshold, None
    if args.calibrate:
        from curate.calibrate import calibrate_threshold

        readable = [Path(im.path) for im in scan.images]
        calib = calibrate_threshold(readable, embedder, args.precision, args.seed)
        threshold = calib.threshold
        print(calib.summary())
    opts = DedupOptions(
        threshold,
        not args.exact_only,
        args.backend,
        tuple(args.protect),
        args.rank,
        args.k,
        args.top,
        args.workers,
        args.batch_size,
    )
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
        f"({c['groups']} groups), {unreadable_summary(run.scan.problems)}; threshold {threshold:.3f}"
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

    listed = [list_images_or_fail([d]) for d in (args.a, args.b)]
    with embedding_session(args) as (embedder, cache, cluster):
        scans = [scan_images(paths, embedder, cache, args.workers, args.batch_size, cluster) for paths in listed]
    leaks = find_leaks(scans[0], scans[1], args.threshold, args.backend)
    summary = leak_summary(scans[0], scans[1], leaks)
    for problem in scans[0].problems + scans[1].problems:
        print(problem, file=sys.stderr)
    for leak in leaks[: args.show]:
        print(f"{leak.kind} {leak.distance:.3f}  {leak.a}  {leak.b}")
    if len(leaks) > args.show:
        print(
            f"... and {len(leaks) - args.show} more"
            + (f" (see {args.json})" if args.json else " (--json FILE writes every pair)")
        )
    print(
        f"{summary['pairs']} duplicate pairs ({summary['exact_pairs']} exact): {summary['a_with_leak']} of "
        f"{summary['images_a']} images in A have a duplicate among the {summary['images_b']} in B "
        f"(threshold {args.threshold:.3f})"
    )
    if args.json:
        doc = {
            "a": str(args.a.resolve()),
            "b": str(args.b.resolve()),
            "model": scans[0].model_id,
            "threshold": args.threshold,
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
        "Originals are never moved or deleted; --apply copies or links the kept (or --top) images elsewhere.\n\n"
        "example:\n  fuzzyfire dedup ../shared/data/fire-cctv-416 --out out/dedup-cctv\n"
        "  fuzzyfire dedup photos/ web/ --protect photos/ --top 1400 --apply copy --to out/kept\n"
        "  fuzzyfire dedup imgs/ --out out/d --model vgg16.onnx --mean 123.675,116.28,103.53 --std 58.395,57.12,57.375",
    )
    p.add_argument("dirs", nargs="+", type=Path, help="image folders (searched recursively) or files")
    p.add_argument("--out", required=True, type=Path, help="folder for dedup.json, report.html, distances.png")
    p.add_argument(
        "--threshold",
        type=float,
        default=DEFAULT_THRESHOLD,
        help=f"near-duplicate distance (default {DEFAULT_THRESHOLD})",
    )
    p.add_argument("--calibrate", action="store_true", help="pick the threshold from augmented copies of your images")
    p.add_argument(
        "--precision", type=float, default=0.99, help="target (balanced) pair precision for --calibrate (default 0.99)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed for --calibrate")
    p.add_argument("--exact-only", action="store_true", help="remove exact duplicates only")
    p.add_argument("--protect", action="append", default=[], type=Path, metavar="DIR", help="never remove images here")
    p.add_argument(
        "--backend", default="auto", choices=("auto", *BACKENDS, PARTITION), help="search backend (default auto)"
    )
    p.add_argument("--rank", default="score", choices=RANK_METHODS, help="diversity ranking (default score)")
    p.add_argument("--k", type=int, default=10, help="neighbours in the diversity score (default 10)")
    p.add_argument("--top", type=int, help="select only the N most diverse kept images")
    p.add_argument("--apply", choices=("copy", "link"), help="materialise the selected images in --to")
    p.add_argument("--to", type=Path, help="target folder for --apply (new or empty)")
    add_model_args(p)
    add_executor_args(p)
    p.set_defaults(func=cmd_dedup)

    p = add_command(
        sub,
        "leakage",
        help="report exact and near-duplicate images shared by two sets (e.g. train vs test)",
        description="List every pair (image in A, image in B) that is an exact copy (same bytes or pixels) or a near\n"
        "duplicate (embeddings closer than --threshold). Exit code 1 when any pair is found (use it in CI).\n\n"
        "example:\n  fuzzyfire leakage ../shared/data/fire-smoke-608/train ../shared/data/fire-smoke-608/test\n"
        "  fuzzyfire leakage out/curated/images/train out/curated/images/test --json out/leaks.json",
    )
    p.add_argument("a", type=Path, help="first image folder (e.g. the training images)")
    p.add_argument("b", type=Path, help="second image folder (e.g. the test images)")
    p.add_argument(
        "--threshold",
        type=float,
        default=DEFAULT_THRESHOLD,
        help=f"near-duplicate distance (default {DEFAULT_THRESHOLD})",
    )
    p.add_argument("--backend", default="auto", choices=("auto", *BACKENDS), help="search backend (default auto)")
    p.add_argument("--json", type=Path, help="write every pair to this JSON file")
    p.add_argument("--show", type=int, default=20, help="pairs printed (default 20)")
    add_model_args(p)
    add_executor_args(p)
    p.set_defaults(func=cmd_leakage)

"""The ``fuzzyfire dedup`` job: scan -> exact/near duplicates -> diversity ranking -> ``dedup.json``,
``report.html``, ``distances.png`` and, on request, a copy (or links) of the kept images.

Originals are only ever read.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from curate.dedup import DedupResult, find_duplicates
from curate.embed import OnnxEmbedder
from curate.embedcache import EmbeddingCache
from curate.rank import rank_order
from curate.report import make_thumbs, write_histogram, write_html
from curate.scan import ScannedImage, ScanResult, scan_images
from curate.search import build_index
from curate.settings import DuplicateSearchConfig, EmbedderConfig, RankConfig
from ground.data.problems import Problem
from ground.run.cluster import Cluster

APPLY_MODES: tuple[str, ...] = ("copy", "link")
REPORT_GROUPS = 100  # groups shown in report.html
REPORT_GROUP_IMAGES = 12  # images shown per group (its kept ones first), with the group's counts
REPORT_TOP = 60  # top-ranked images shown
UNREADABLE_SHOWN = 3  # unreadable files named in the summary line (all of them in dedup.json and report.html)


@dataclass(frozen=True)
class DedupOptions:
    """What a job does, in plain values (:func:`dedup_options` makes them from the settings sections)."""

    threshold: float  # Euclidean distance between unit embeddings, 0..2
    near: bool  # False: exact duplicates only
    backend: str  # search backend (curate.search.BACKENDS, or partition)
    protect: tuple[Path, ...]  # folders whose images are never removed
    rank: str  # score | kcenter
    k: int  # neighbours in the diversity score
    top: int | None  # keep only the N most diverse kept images
    workers: int  # decode + embed threads; 0 = one per CPU core
    batch_size: int  # images per onnxruntime call


def dedup_options(
    search: DuplicateSearchConfig | None = None,
    rank: RankConfig | None = None,
    model: EmbedderConfig | None = None,
    protect: tuple[Path, ...] = (),
) -> DedupOptions:
    """The options of a job with these settings (each section's defaults when not given): duplicates ``search``,
    the ``rank`` of the kept images (its ``top`` included), ``model``'s workers and batch size, the ``protect``
    folders."""
    search, rank, model = search or DuplicateSearchConfig(), rank or RankConfig(), model or EmbedderConfig()
    return DedupOptions(
        search.threshold,
        search.near,
        search.backend,
        protect,
        rank.method,
        rank.k,
        rank.top,
        model.workers,
        model.batch_size,
    )


@dataclass
class DedupRun:
    scan: ScanResult
    result: DedupResult
    ranking: list[int]  # kept image indices, most diverse first
    scores: dict[int, float]  # kept image index -> diversity score
    nn_dist: NDArray[np.float32]  # (N,) distance of each image to its nearest other image
    selected: list[int] = field(default_factory=list)  # the --top set (or all kept), ascending


def tie_key(image: ScannedImage) -> str:
    """Ranking tie-break: the file's content (sha256), then its path."""
    return f"{image.facts.sha256}:{image.path}"


def run_dedup(
    paths: Sequence[Path],
    embedder: OnnxEmbedder,
    cache: EmbeddingCache | None,
    opts: DedupOptions,
    scan: ScanResult | None = None,
    cluster: Cluster | None = None,
) -> DedupRun:
    """The whole job on ``paths`` (or on an existing ``scan`` of them). With a Ray ``cluster``, decoding and
    embedding run on its workers (:mod:`curate.embedremote`), and so does a partitioned search
    (:mod:`curate.partition`); grouping, keepers and ranking run here, as in a local run."""
    if scan is None:
        scan = scan_images(paths, embedder, cache, opts.workers, opts.batch_size, cluster)
    result = find_duplicates(
        scan.images, scan.vectors, opts.threshold, opts.backend, opts.protect, opts.near, scan.crops, cluster
    )
    kept = result.kept
    order, scores = rank_order(
        scan.vectors[kept], [tie_key(scan.images[i]) for i in kept], opts.rank, opts.k, opts.backend, opts.top
    )
    ranking = [kept[i] for i in order]
    nn = np.zeros(len(scan.images), np.float32)
    if len(scan.images) > 1:
        nn = build_index(scan.vectors, opts.backend).knn(scan.vectors, 2)[0][:, 1]
    selected = sorted(ranking[: opts.top] if opts.top is not None else ranking)
    return DedupRun(scan, result, ranking, {kept[i]: float(s) for i, s in enumerate(scores)}, nn, selected)


def dedup_document(run: DedupRun, opts: DedupOptions, inputs: Sequence[str]) -> dict[str, Any]:
    """The ``dedup.json`` content (absolute paths)."""
    path = [im.path for im in run.scan.images]
    res = run.result
    return {
        "tool": "fuzzyfire dedup",
        "inputs": list(inputs),
        "model": run.scan.model_id,
        "threshold": opts.threshold,
        "backend": opts.backend,
        "keeper_policy": "protected > resolution > sharpness > file size > path",
        "counts": {
            "images": len(path),
            "kept": len(res.kept),
            "removed_exact": sum(r.kind == "exact" for r in res.removed),
            "removed_near": sum(r.kind == "near" for r in res.removed),
            "groups": len(res.groups),
            "unreadable": len(run.scan.problems),
            "from_cache": run.scan.cached,
        },
        "kept": [path[i] for i in res.kept],
        "removed": [
            {
                "path": path[r.index],
                "duplicate_of": path[r.duplicate_of],
                "kind": r.kind,
                "distance": round(r.distance, 5),
            }
            for r in res.removed
        ],
        "groups": [[path[i] for i in g] for g in res.groups],
        "ranking": [{"path": path[i], "score": round(run.scores[i], 5)} for i in run.ranking],
        "rank_method": opts.rank,
        "top": opts.top,
        "selected": [path[i] for i in run.selected],
        "problems": [p.to_dict() for p in run.scan.problems],
    }


def unreadable_summary(problems: Sequence[Problem], shown: int = UNREADABLE_SHOWN) -> str:
    """``N unreadable`` with the first ``shown`` file names: ``2 unreadable (a.jpg, b.png)``, ``9 unreadable
    (a.jpg, b.png, c.jpg and 6 more)``; the full list with reasons is in ``problems`` of dedup.json."""
    if not problems:
        return "0 unreadable"
    names = ", ".join(Path(p.path).name for p in problems[:shown])
    more = f" and {len(problems) - shown} more" if len(problems) > shown else ""
    return f"{len(problems)} unreadable ({names}{more})"


def write_outputs(run: DedupRun, doc: dict[str, Any], out: Path, json_name: str = "dedup.json") -> dict[str, Path]:
    """``dedup.json`` (or ``json_name``), ``distances.png``, ``report.html`` (+ ``thumbs/``) in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    files = {"json": out / json_name, "histogram": out / "distances.png", "report": out / "report.html"}
    files["json"].write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    write_histogram(run.nn_dist, doc["threshold"], files["histogram"], f"{len(run.nn_dist)} images")
    images, removed = run.scan.images, {r.index: r for r in run.result.removed}
    groups = [_report_group(g, removed) for g in run.result.groups[:REPORT_GROUPS]]
    top = run.ranking[:REPORT_TOP]
    wanted = [(images[i].path, images[i].facts.sha256) for i in [*(i for _, g in groups for i in g), *top]]
    thumbs = make_thumbs(wanted, out / "thumbs")

    def caption(i: int) -> str:
        r = removed.get(i)
        name = Path(images[i].path).name
        return f"KEPT {name}" if r is None else f"{r.kind} {r.distance:.3f} {name}"

    c = doc["counts"]
    summary = [
        f"{c['images']} images: {c['kept']} kept, {c['removed_exact']} exact and {c['removed_near']} near duplicates "
        f"removed, {unreadable_summary(run.scan.problems)}",
        f"threshold {doc['threshold']:.3f} on model {doc['model']}",
        f"keeper policy: {doc['keeper_policy']}",
    ]
    write_html(
        files["report"],
        str(doc["tool"]),
        summary,
        [(heading, [(images[i].path, caption(i), i not in removed) for i in g]) for heading, g in groups],
        [(images[i].path, f"{run.scores[i]:.3f} {Path(images[i].path).name}") for i in top],
        thumbs,
        files["histogram"].name,
        len(run.result.groups),
        [(p.path, p.reason) for p in run.scan.problems],
    )
    return files


def _report_group(group: Sequence[int], removed: Mapping[int, Any]) -> tuple[str, list[int]]:
    """A group's heading (its size, how many kept and removed, how many shown) and the images shown: its kept
    images first, then the removed ones, in keeper order, at most :data:`REPORT_GROUP_IMAGES`."""
    kept = [i for i in group if i not in removed]
    shown = [*kept, *(i for i in group if i in removed)][:REPORT_GROUP_IMAGES]
    heading = f"{len(group)} images: {len(kept)} kept, {len(group) - len(kept)} removed"
    if len(shown) < len(group):
        heading += f" (showing {len(shown)} of {len(group)})"
    return heading, shown


def check_apply_target(roots: Sequence[Path], to: Path, mode: str) -> None:
    """Raise ValueError for an unknown mode, a ``to`` inside an input folder, or a ``to`` holding files."""
    if mode not in APPLY_MODES:
        raise ValueError(f"unknown apply mode {mode!r}; choose {' or '.join(APPLY_MODES)}")
    to_r = to.resolve()
    if any(to_r.is_relative_to(Path(r).resolve()) for r in roots if Path(r).is_dir()):
        raise ValueError(f"{to}: --to must not be inside an input folder")
    if to.exists() and any(to.iterdir()):
        raise ValueError(f"{to}: folder is not empty; choose a new --to")


def apply_selection(paths: Sequence[str], roots: Sequence[Path], to: Path, mode: str) -> int:
    """Copy (or hard-link, falling back to a copy) ``paths`` into ``to/<root name>/<path below root>``.

    Refuses a ``to`` inside an input folder or one that already holds files. Returns the number placed."""
    check_apply_target(roots, to, mode)
    roots = [Path(r).resolve() for r in roots]
    for path in map(Path, paths):
        root = next((r for r in roots if r.is_dir() and path.is_relative_to(r)), path.parent)
        dst = to / root.name / path.relative_to(root)
        dst.parent.mkdir(parents=True, exist_ok=True)
        if mode == "link":
            try:
                os.link(path, dst)
                continue
            except OSError:
                pass
        shutil.copy2(path, dst)
    return len(paths)

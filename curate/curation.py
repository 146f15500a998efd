"""FiIW-style curation with labels carried through (the ``fuzzyfire curate CONFIG`` pipeline):

merge labelled sources -> exact duplicates -> near duplicates -> diversity ranking -> top N -> seeded split in
which no group of near duplicates straddles two splits -> a curated dataset (COCO + YOLO + manifest) with
``curation.json``, ``report.html`` and ``distances.png`` beside it.

The schema dataclasses below are built from YAML by :mod:`ground.config.loader` (see ``configs/curate-shared.yaml``).
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from curate.dedupjob import DedupRun, dedup_document, dedup_options, run_dedup, tie_key, write_outputs
from curate.embed import OnnxEmbedder, Preprocess, load_embedder
from curate.embedcache import EmbeddingCache
from curate.rank import rank_order
from curate.scan import ScanResult
from curate.settings import DuplicateSearchConfig, EmbedderConfig, ExecutorConfig, RankConfig
from curate.sources import MergeConfig, SourceConfig, merge_sources
from curate.split import near_groups, resolve_sizes, split_groups, straddling_groups
from ground.data.dataset import Dataset
from ground.data.problems import Problem
from ground.data.writer import write_dataset
from ground.run.cluster import Cluster, open_cluster

CURATION_FILE = "curation.json"  # what the curation did, beside the curated dataset


def read_curation(folder: Path) -> dict[str, Any] | None:
    """The :data:`CURATION_FILE` record beside a curated dataset ``folder`` (``counts``: images read, kept,
    removed_exact, removed_near, unreadable; ``splits``: images per split); None for a folder not curated."""
    path = Path(folder) / CURATION_FILE
    return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None


@dataclass(frozen=True)
class DedupConfig(DuplicateSearchConfig):
    protect_sources: tuple[str, ...] = ()  # source names whose images are never removed


@dataclass(frozen=True)
class SplitConfig:
    sizes: dict[str, float] = field(default_factory=lambda: {"train": 0.8, "valid": 0.1, "test": 0.1})  # fractions
    # summing to 1, or counts like {train: 1000, valid: 200, test: 200}
    group_threshold: float = 0.6  # images closer than this always share a split (>= dedup threshold)
    seed: int = 0  # same seed + same inputs -> byte-identical split


@dataclass(frozen=True)
class CurateConfig(MergeConfig):
    """The sources merged (:class:`~curate.sources.MergeConfig`: ``sources``, ``classes``, ``images``), then
    deduplicated, ranked, cut to the top N and split."""

    dedup: DedupConfig = DedupConfig()  # exact and near-duplicate removal
    rank: RankConfig = RankConfig()  # diversity ranking of the kept images
    split: SplitConfig = SplitConfig()  # group-aware split (no near-duplicate group across two splits)
    model: EmbedderConfig = EmbedderConfig()  # the embedding CNN (built-in ImageNet Lite0, or your ONNX)
    executor: ExecutorConfig = ExecutorConfig()  # where decoding and embedding run: here, or on a Ray cluster


@dataclass
class CurateResult:
    dataset: Dataset  # the curated images (absolute paths) with their split
    document: dict[str, Any]  # curation.json content
    run: DedupRun
    problems: list[Problem]


def build_embedder(cfg: EmbedderConfig) -> OnnxEmbedder:
    if cfg.path is None:
        return load_embedder(device=cfg.device)
    pre = Preprocess(cfg.input_size, tuple(cfg.mean), tuple(cfg.std), cfg.bgr, cfg.layout, cfg.blur)  # type: ignore[arg-type]
    return load_embedder(cfg.path, pre, output=cfg.output, device=cfg.device)


def _selection_size(cfg: CurateConfig, n: int) -> int | None:
    if cfg.rank.top is not None:
        return min(cfg.rank.top, n)
    values = list(cfg.split.sizes.values())
    fractions = all(v <= 1 for v in values) and abs(sum(values) - 1) < 1e-6
    return None if fractions else min(int(sum(values)), n)


def curate(
    cfg: CurateConfig,
    base: Path,
    out: Path,
    embedder: OnnxEmbedder,
    cache: EmbeddingCache | None,
    scan: ScanResult | None = None,
    cluster: Cluster | None = None,
) -> CurateResult:
    """Run the pipeline (module docstring); relative source paths resolve against ``base``. ``scan``: the
    facts and embeddings of the merged images, when already computed (e.g. a previous result's ``run.scan``);
    ``cluster``: the Ray cluster that decodes and embeds (:func:`curate.dedupjob.run_dedup`)."""
    merged, problems = merge_sources(cfg, base, out)
    protect = tuple(_source_path(s, base) for s in cfg.sources if s.name and s.name in cfg.dedup.protect_sources)
    paths = [Path(img.file_name) for img in merged.images]
    opts = dedup_options(cfg.dedup, replace(cfg.rank, top=None), cfg.model, protect)
    run = run_dedup(paths, embedder, cache, opts, scan, cluster)  # ranks every kept image; the top N is cut below
    top = _selection_size(cfg, len(run.result.kept))
    opts = replace(opts, top=top)
    if top is not None and cfg.rank.method == "kcenter":  # the k-center order depends on N
        kept = run.result.kept
        keys = [tie_key(run.scan.images[i]) for i in kept]
        order, _ = rank_order(run.scan.vectors[kept], keys, "kcenter", cfg.rank.k, cfg.dedup.backend, top)
        run.ranking = [kept[i] for i in order]
    run.selected = sorted(run.ranking[:top] if top is not None else run.ranking)
    split_of, groups = assign_splits(run, cfg.split, len(run.selected))
    by_path = {run.scan.images[i].path: name for i, name in split_of.items()}
    curated = merged.filter_images(lambda img: img.file_name in by_path)
    curated = replace(curated, images=tuple(replace(img, split=by_path[img.file_name]) for img in curated.images))
    doc = dedup_document(run, opts, [str(_source_path(s, base)) for s in cfg.sources])
    doc["tool"] = "fuzzyfire curate"
    found = Counter(img.split for img in curated.images)
    doc["splits"] = {name: found.get(name, 0) for name in cfg.split.sizes}
    doc["split_groups"] = {"threshold": cfg.split.group_threshold, "groups": len(groups), "straddling": 0}
    doc["split_seed"] = cfg.split.seed
    return CurateResult(curated, doc, run, problems + run.scan.problems)


def curate_dataset(
    cfg: CurateConfig,
    base: Path,
    out: Path,
    cache: Path | None,
    provenance: Mapping[str, Any],
    overwrite: bool = False,
) -> tuple[CurateResult, dict[str, Path]]:
    """``fuzzyfire curate`` whole: :func:`curate` with ``cfg.model``'s embedder and the embedding cache file
    ``cache`` (None: no cache), then the dataset in ``out`` (COCO + YOLO + manifest; ``provenance``: the
    manifest's ``command``, ``args`` and ``sources``) and ``curation.json`` + its report beside it. Returns the
    result and the report files; raises :class:`ground.data.writer.OutputError` when ``out`` is refused."""
    embedder = build_embedder(cfg.model)
    cluster = open_cluster(cfg.executor.name, cfg.executor.address)
    db = EmbeddingCache(cache) if cache is not None else None
    try:
        result = curate(cfg, base, out, embedder, db, cluster=cluster)
    finally:
        if db is not None:
            db.close()
        if cluster is not None:
            cluster.close()
    write_dataset(result.dataset, out, ("coco", "yolo"), cfg.images, overwrite=overwrite, **provenance)
    return result, write_outputs(result.run, result.document, out, CURATION_FILE)


def assign_splits(run: DedupRun, cfg: SplitConfig, n: int) -> tuple[dict[int, str], list[list[int]]]:
    """Image index -> split for the selected images; groups of near duplicates (threshold
    ``cfg.group_threshold``) stay whole. Returns the assignment and the groups (image indices)."""
    selected = run.selected
    local = near_groups(run.scan.vectors[selected], cfg.group_threshold, "auto", run.scan.crops[selected])
    groups = [[selected[i] for i in g] for g in local]
    counts = resolve_sizes(cfg.sizes, n)
    assignment = split_groups(groups, counts, np.random.default_rng(cfg.seed))
    assert not straddling_groups(groups, assignment), "a near-duplicate group straddles two splits"
    return assignment, groups


def _source_path(src: SourceConfig, base: Path) -> Path:
    return (src.path if src.path.is_absolute() else base / src.path).resolve()

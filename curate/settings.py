"""The settings sections curate's commands share, and the settings of ``fuzzyfire dedup`` and ``fuzzyfire leakage``.

:class:`EmbedderConfig` (the embedding CNN), :class:`ExecutorConfig` (where decoding and embedding run),
:class:`DuplicateSearchConfig` (which images are duplicates) and :class:`RankConfig` (how the kept ones are
ranked) are sections of :class:`DedupJobConfig`, :class:`LeakageJobConfig` and
:class:`curate.curation.CurateConfig` alike, so a key means the same in every command (``model.path``,
``dedup.threshold``, ``rank.top``, ``executor.name``). Frozen dataclasses built from YAML, flags and ``--set`` by
:mod:`ground.cli.options`; the commands' flags hold no defaults of their own.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Optional

from curate.dedup import DEFAULT_THRESHOLD


@dataclass(frozen=True)
class EmbedderConfig:
    """Embedding model: ``path: null`` = built-in EfficientNet-Lite0 (then leave the rest at defaults)."""

    path: Optional[Path] = None  # ONNX file of your own CNN
    input_size: int = 224  # user models only: input side in pixels, square
    mean: tuple[float, ...] = (127.0, 127.0, 127.0)  # user models only: subtracted per channel on 0..255
    std: tuple[float, ...] = (128.0, 128.0, 128.0)  # user models only: divisor per channel on 0..255
    bgr: bool = False  # user models only: BGR channel order
    layout: Literal["nchw", "nhwc"] = "nchw"  # user models only: nchw | nhwc input layout
    output: Optional[str] = None  # output name used as the embedding (default: first)
    blur: float = 0.0  # Gaussian sigma in input pixels after resizing
    batch_size: int = 4  # images per onnxruntime call
    workers: int = 0  # decode + embed threads; 0 = one per CPU core
    device: str = "auto"  # auto | cpu | cuda | cuda:N: onnxruntime's CUDA provider when installed (auto: if present)


#: The keys of :class:`EmbedderConfig` that describe a user model's input: left at their defaults for the built-in.
PREPROCESSING: tuple[str, ...] = ("input_size", "mean", "std", "bgr", "layout", "output", "blur")


@dataclass(frozen=True)
class ExecutorConfig:
    """Where decoding, embedding and a partitioned search run (docs/scaling.md)."""

    name: Literal["local", "ray"] = "local"  # local (this process, a thread per core) | ray (Ray workers)
    address: Optional[str] = None  # ray: a running cluster (HOST:6379 or ray://HOST:10001); null = a local Ray


@dataclass(frozen=True)
class DuplicateSearchConfig:
    """Which images are duplicates: exact copies, and near ones closer than ``threshold``."""

    near: bool = True  # false: exact duplicates only
    threshold: float = DEFAULT_THRESHOLD  # Euclidean distance of unit embeddings, 0..2
    backend: Literal["auto", "numpy", "flat", "ivf", "hnsw", "partition"] = "auto"  # numpy | flat (exact faiss)
    # | ivf | hnsw (approximate, beyond ~1M images) | partition (k-means cells, beyond ~10M); auto picks by size


@dataclass(frozen=True)
class RankConfig:
    method: Literal["score", "kcenter"] = "score"  # score = mean distance to k nearest kept images | kcenter =
    # farthest-point order
    k: int = 10  # neighbours in the score
    top: Optional[int] = None  # keep the N most diverse kept images; null: all (curate: the sum of the split
    # counts when they are counts)


@dataclass(frozen=True)
class DedupJobConfig:
    """``fuzzyfire dedup DIR...``: exact and near duplicates in image folders, the kept images ranked."""

    dedup: DuplicateSearchConfig = DuplicateSearchConfig()  # exact and near duplicates
    calibrate: bool = False  # pick dedup.threshold from augmented copies of your own images instead
    precision: float = 0.99  # calibrate: target (balanced) pair precision, 0..1
    seed: int = 0  # calibrate: seed of the sampled images and their augmentations
    rank: RankConfig = RankConfig()  # diversity ranking of the kept images
    model: EmbedderConfig = EmbedderConfig()  # the embedding CNN (built-in ImageNet Lite0, or your ONNX)
    executor: ExecutorConfig = ExecutorConfig()  # where decoding and embedding run: here, or on a Ray cluster


@dataclass(frozen=True)
class LeakageJobConfig:
    """``fuzzyfire leakage A B``: every image pair of two folders that is an exact or near duplicate."""

    threshold: float = DEFAULT_THRESHOLD  # near-duplicate distance of unit embeddings, 0..2
    backend: Literal["auto", "numpy", "flat", "ivf", "hnsw"] = "auto"  # search backend (dedup.backend, without
    # partition)
    show: int = 20  # pairs printed (--json FILE writes every pair)
    model: EmbedderConfig = EmbedderConfig()  # the embedding CNN (built-in ImageNet Lite0, or your ONNX)
    executor: ExecutorConfig = ExecutorConfig()  # where decoding and embedding run: here, or on a Ray cluster

"""Decode and embed on Ray workers: the ``--executor ray`` half of :mod:`curate.scan`.

**Design: tasks over file shards, one onnxruntime session per worker process.** The driver lists the files;
Ray tasks hash them in shards of :data:`HASH_SHARD_FILES` (the driver reads no file); the driver reads the
embedding cache as a local run does; the misses are cut into shards of
:data:`SHARD_IMAGES` consecutive files (whole batches of ``batch_size``, so every onnxruntime call sees the same
images as in a local run) and each shard is one Ray task reserving one CPU. A task decodes its files (they must
be at the same path on every node: shared storage), embeds both views and returns the facts and raw vectors;
the driver writes them to the content-hash cache as they arrive, so an interrupted run resumes from the cache
and later commands reuse the vectors. The model travels once through Ray's object store (a worker needs no copy
of the user's cache folder) and each worker process keeps its session for every later task (what an actor pool
would give), while a task stays a pure function of its shard: a task whose worker dies is simply run again
(:meth:`ground.run.cluster.Cluster.map`), which an actor pool's lost in-flight batches would not give for free,
and nothing beyond Ray core is needed (Ray Data would add pyarrow and pandas).

**GPUs.** ``device`` ``cuda`` (or ``auto`` on a cluster with GPUs) makes each task reserve
``1 / TASKS_PER_GPU`` of a GPU and run onnxruntime's CUDA provider: decoding stays on the CPU, several decoding
tasks feed one GPU.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from curate.decode import embed_batch, hash_image_file
from curate.embed import OnnxEmbedder, Preprocess
from curate.embedcache import FileFacts
from ground.data.problems import Problem
from ground.run.cluster import Cluster
from ground.run.progress import progress

SHARD_IMAGES = 256  # images per Ray task (rounded to whole batches)
HASH_SHARD_FILES = 2048  # files per hashing task
TASKS_PER_GPU = 4  # embedding tasks sharing one GPU (each decodes on its own CPU)

Embedded = tuple[FileFacts, NDArray[np.float32]]  # facts and raw [whole view, centre view] vector (2 D,)


@dataclass(frozen=True)
class EmbedSpec:
    """What a worker needs to rebuild the driver's embedder: the model's bytes (an ObjectRef in a list, so Ray
    does not fetch them for a worker that has the session already), its identity, preprocessing, output."""

    model: list[Any]
    model_id: str
    name: str
    preprocess: Preprocess
    output: str
    device: str
    batch_size: int


_SESSIONS: dict[tuple[str, str], OnnxEmbedder] = {}  # a worker process's embedders, by (model id, device)


def worker_embedder(spec: EmbedSpec) -> OnnxEmbedder:
    """The embedder of ``spec`` in this worker process, built on first use (one session per process)."""
    key = (spec.model_id, spec.device)
    if key not in _SESSIONS:
        import cv2
        import ray

        cv2.setNumThreads(1)  # one decode pipeline per reserved CPU
        data = ray.get(spec.model[0])
        _SESSIONS[key] = OnnxEmbedder(
            spec.name, spec.preprocess, spec.output, device=spec.device, model_bytes=data, model_id=spec.model_id
        )
    return _SESSIONS[key]


def embed_shard(paths: Sequence[str], spec: EmbedSpec) -> list[tuple[str, Embedded | Problem]]:
    """A Ray task: decode and embed ``paths`` (absolute POSIX) in batches of ``spec.batch_size``; (path, (facts,
    raw vector) or Problem) in input order."""
    embedder = worker_embedder(spec)
    out: list[tuple[str, Embedded | Problem]] = []
    for s in range(0, len(paths), spec.batch_size):
        batch = [Path(p) for p in paths[s : s + spec.batch_size]]
        out += [(p.as_posix(), item) for p, item in embed_batch(batch, embedder)]
    return out


def hash_shard(paths: Sequence[str]) -> list[tuple[int, str] | Problem]:
    """A Ray task: ``(bytes, sha256)`` or a Problem for each of ``paths``, in order
    (:func:`curate.decode.hash_image_file`)."""
    return [hash_image_file(Path(p)) for p in paths]


def hash_on_cluster(paths: Sequence[Path], cluster: Cluster) -> list[tuple[int, str] | Problem]:
    """:func:`curate.decode.hash_image_file` of every path, read on the cluster's workers (shards of
    :data:`HASH_SHARD_FILES`): the driver then reads no file. In input order."""
    shards = _shards(paths, HASH_SHARD_FILES)
    out: list[list[tuple[int, str] | Problem]] = [[] for _ in shards]
    done = cluster.map(hash_shard, shards, num_cpus=1)
    for k, hashed in progress(done, total=len(shards), desc="hashing", unit="shard", min_items=8):
        out[k] = hashed
    return [h for shard in out for h in shard]


def task_gpus(cluster: Cluster, device: str) -> float:
    """GPU share each embedding task reserves: ``1 / TASKS_PER_GPU`` for ``cuda`` (refused on a cluster without
    GPUs) or ``auto`` on a cluster with GPUs, else 0."""
    from ground.run.device import parse_device

    kind, _ = parse_device(device)
    if kind == "cpu" or (kind == "auto" and cluster.gpus() == 0):
        return 0.0
    cluster.require_gpus(1 / TASKS_PER_GPU, f"embedding on device {device!r}")
    return 1 / TASKS_PER_GPU


def embed_on_cluster(
    paths: Sequence[Path], embedder: OnnxEmbedder, cluster: Cluster, batch_size: int
) -> Iterator[list[tuple[Path, Embedded | Problem]]]:
    """Decode and embed ``paths`` on ``cluster``, one task per shard (see the module docstring), on the device
    the driver's ``embedder`` was asked for; yields each shard's (path, (facts, raw vector) or Problem) list as
    it finishes (shards in any order)."""
    shards = _shards(paths, max(batch_size, SHARD_IMAGES // batch_size * batch_size))
    gpus = task_gpus(cluster, embedder.device)
    spec = EmbedSpec(
        [cluster.put(embedder.path.read_bytes())],
        embedder.model_id,
        embedder.path.name,
        embedder.preprocess,
        embedder.output,
        "cuda" if gpus else "cpu",
        batch_size,
    )
    for _, results in cluster.map(embed_shard, shards, spec, num_cpus=1, num_gpus=gpus):
        yield [(Path(p), item) for p, item in results]


def _shards(paths: Sequence[Path], size: int) -> list[list[str]]:
    """``paths`` as absolute POSIX strings (what every node reads), cut into runs of ``size``."""
    return [[p.as_posix() for p in paths[s : s + size]] for s in range(0, len(paths), size)]

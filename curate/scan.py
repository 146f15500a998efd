"""Scan image files once: content hash, decoded-pixel hash, size, sharpness and embedding per file.

A pool of threads (one per core) hashes every file, then each thread decodes, resizes and embeds whole batches
(:func:`curate.decode.embed_batch`): OpenCV, hashlib and onnxruntime (one intra-op thread per call) release the GIL,
so the cores stay busy without oversubscription. With a Ray cluster the batches are embedded on its workers
instead (:mod:`curate.embedremote`), the same vectors. Results are cached by content hash
(:mod:`curate.embedcache`), so a rerun only reads and hashes the files and decodes the new ones. Unreadable files
become :class:`Problem` records.
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from curate.decode import embed_batch, hash_image_file
from curate.embed import OnnxEmbedder, l2_normalize
from curate.embedcache import EmbeddingCache, FileFacts
from curate.embedremote import embed_on_cluster, hash_on_cluster
from ground.data.problems import Problem
from ground.data.walk import walk_files
from ground.image.imageio import is_image_file
from ground.run.cluster import Cluster
from ground.run.progress import progress

T = TypeVar("T")
R = TypeVar("R")
_SAVE_EVERY = 2048  # images embedded between cache commits (an interrupted run resumes from there)


@dataclass(frozen=True)
class ScannedImage:
    path: str  # absolute POSIX path
    facts: FileFacts


@dataclass
class ScanResult:
    """Readable images in input order. ``vectors[i]`` / ``crops[i]``: L2-normalised embeddings (N, D) float32 of
    the whole of ``images[i]`` and of its centre view (see :mod:`curate.embed`)."""

    images: list[ScannedImage]
    vectors: NDArray[np.float32]
    crops: NDArray[np.float32]
    problems: list[Problem] = field(default_factory=list)
    model_id: str = ""
    cached: int = 0  # images whose facts and embedding came from the cache


def list_image_files(inputs: Iterable[Path | str]) -> list[Path]:
    """Image files under the given folders (recursive, linked folders followed, hidden entries skipped) or given
    directly; absolute, unique, sorted."""
    found: set[Path] = set()
    for item in inputs:
        path = Path(item).absolute()
        if path.is_dir():
            found.update(walk_files(path, is_image_file))
        elif path.is_file():
            found.add(path)
        else:
            raise FileNotFoundError(f"{item}: no such file or folder")
    return sorted(found, key=lambda p: p.as_posix())


def list_images_or_fail(inputs: Iterable[Path | str]) -> list[Path]:
    """:func:`list_image_files`; ValueError naming ``inputs`` and the suffixes looked for when there are none."""
    inputs = list(inputs)
    paths = list_image_files(inputs)
    if not paths:
        from ground.image.imageio import IMAGE_SUFFIXES

        raise ValueError(
            f"no image files in {', '.join(map(str, inputs))} (looked for {' '.join(sorted(IMAGE_SUFFIXES))}, "
            "in subfolders too)"
        )
    return paths


def bounded_map(fn: Callable[[T], R], items: Sequence[T], pool: ThreadPoolExecutor, ahead: int) -> Iterator[R]:
    """``map(fn, items)`` on ``pool`` in input order, at most ``ahead`` results pending (bounded memory)."""
    pending: deque[Future[R]] = deque()
    for item in items:
        pending.append(pool.submit(fn, item))
        if len(pending) >= ahead:
            yield pending.popleft().result()
    while pending:
        yield pending.popleft().result()


def scan_images(
    paths: Sequence[Path],
    embedder: OnnxEmbedder,
    cache: EmbeddingCache | None = None,
    workers: int = 0,
    batch_size: int = 4,
    cluster: Cluster | None = None,
) -> ScanResult:
    """Facts and normalised embeddings for ``paths`` (see :class:`ScanResult`); bad files become problems.

    ``workers`` threads (0 = one per CPU core) hash, decode and embed; ``batch_size`` images per onnxruntime
    call. With a ``cluster``, hashing, decoding and embedding run on its Ray workers (:mod:`curate.embedremote`):
    the same vectors, facts and problems."""
    workers = workers or os.cpu_count() or 2
    problems: list[Problem] = []
    with ThreadPoolExecutor(max_workers=workers) as pool:
        if cluster is None:
            hashed = list(progress(pool.map(hash_image_file, paths), total=len(paths), desc="hashing"))
        else:
            hashed = hash_on_cluster(paths, cluster)
        shas = {p: h[1] for p, h in zip(paths, hashed) if not isinstance(h, Problem)}
        problems += [h for h in hashed if isinstance(h, Problem)]
        facts = cache.get_facts(list(shas.values())) if cache else {}
        vectors = cache.get_vectors(embedder.model_id, list(shas.values())) if cache else {}
        cached = sum(1 for s in shas.values() if s in facts and s in vectors)
        todo = [p for p, s in shas.items() if s not in facts or s not in vectors]
        if cluster is None:
            batches = bounded_map(lambda b: embed_batch(b, embedder), _batches(todo, batch_size), pool, 2 * workers)
        else:
            batches = embed_on_cluster(todo, embedder, cluster, batch_size)
        for path, item in _saved(batches, len(todo), embedder.model_id, cache):
            if isinstance(item, Problem):
                problems.append(item)
            else:
                shas[path] = item[0].sha256  # the file may have changed since hashing
                facts[item[0].sha256], vectors[item[0].sha256] = item
    images = [ScannedImage(p.as_posix(), facts[shas[p]]) for p in paths if p in shas and shas[p] in vectors]
    dim = next(iter(vectors.values())).shape[0] if vectors else 0
    matrix = np.stack([vectors[im.facts.sha256] for im in images]) if images else np.zeros((0, dim), np.float32)
    half = matrix.shape[1] // 2  # cached rows hold [whole view, centre view]
    problems.sort(key=lambda p: p.path)
    return ScanResult(
        images, l2_normalize(matrix[:, :half]), l2_normalize(matrix[:, half:]), problems, embedder.model_id, cached
    )


def _batches(paths: Sequence[Path], size: int) -> list[Sequence[Path]]:
    return [paths[s : s + size] for s in range(0, len(paths), size)]


def _saved(
    batches: Iterable[list[tuple[Path, tuple[FileFacts, NDArray[np.float32]] | Problem]]],
    total: int,
    model_id: str,
    cache: EmbeddingCache | None,
) -> Iterator[tuple[Path, tuple[FileFacts, NDArray[np.float32]] | Problem]]:
    """Yield every (path, (facts, raw vector) or Problem) of ``batches`` (``total`` images in all, a progress
    bar), storing the embedded ones in ``cache`` every :data:`_SAVE_EVERY` images and at the end (an interrupted
    run resumes from there)."""
    unsaved: list[tuple[FileFacts, NDArray[np.float32]]] = []
    items = (entry for batch in batches for entry in batch)
    for path, item in progress(items, total=total, desc="embedding", min_items=80):
        if not isinstance(item, Problem):
            unsaved.append(item)
        yield path, item
        if cache is not None and len(unsaved) >= _SAVE_EVERY:
            cache.put(model_id, [u[0] for u in unsaved], np.stack([u[1] for u in unsaved]))
            unsaved = []
    if cache is not None and unsaved:
        cache.put(model_id, [u[0] for u in unsaved], np.stack([u[1] for u in unsaved]))

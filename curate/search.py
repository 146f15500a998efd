"""Nearest-neighbour search on L2-normalised vectors, in batches (never an N x N matrix).

For unit vectors the Euclidean distance ``d`` and the cosine similarity ``s`` are one: ``d = sqrt(2 - 2 s)``.
Every backend answers the same two questions about a base set of vectors (N, D):

- ``knn(queries (Q, D), k) -> (dist (Q, k) float32 ascending, idx (Q, k) int64, -1 when missing)``
- ``within(queries (Q, D), radius) -> (qi (E,), bi (E,), dist (E,))``: every base vector closer than ``radius``.

Backends (:data:`BACKENDS`): ``numpy`` (exact brute force, the reference), ``flat`` (faiss ``IndexFlatIP``,
exact), ``ivf`` (faiss ``IndexIVFFlat``, approximate, for ~1M+ vectors), ``hnsw`` (faiss ``IndexHNSWFlat``,
approximate; ``within`` = kNN with ``k = max_neighbors`` filtered by radius). ``auto`` = ``flat`` up to
:data:`AUTO_EXACT_MAX` vectors, ``ivf`` above. Duplicate pairs of very large sets come by partitions instead
(backend ``partition``, :mod:`curate.partition`); its kNN questions (ranking, nearest distances) go to ``ivf``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

AUTO_EXACT_MAX = 200_000
#: Orderings of distances and scores (which kept duplicate is nearest, the diversity ranking) compare them on this
#: grid, ties broken by content, so float noise far below it (2e-6 between builds, CPUs and thread counts:
#: ``experiments/embedding_noise.py``) reorders nothing. Thresholds keep their exact meaning (``d < t``).
DISTANCE_GRID = 1e-4
_BLOCK_CELLS = 1 << 24  # query rows x base rows per similarity block (64 MB of float32)

Idx = NDArray[np.int64]
Vec = NDArray[np.float32]


@dataclass(frozen=True)
class Pairs:
    """Pairs ``(i[e], j[e])`` at Euclidean distance ``dist[e]``; each array has shape (E,)."""

    i: Idx
    j: Idx
    dist: Vec

    def __len__(self) -> int:
        return int(self.i.shape[0])


def grid_cells(values: NDArray[np.floating]) -> NDArray[np.int64]:
    """(N,) distances or scores -> (N,) int64 cells of :data:`DISTANCE_GRID` (floor), for orderings."""
    return np.floor(np.asarray(values, np.float64) / DISTANCE_GRID).astype(np.int64)


def sim_to_dist(sim: NDArray[np.floating]) -> Vec:
    return np.sqrt(np.maximum(2.0 - 2.0 * np.asarray(sim, np.float32), 0.0)).astype(np.float32)


def dist_to_sim(dist: float) -> float:
    return 1.0 - dist * dist / 2.0


class SearchIndex(ABC):
    """A searchable base set of unit vectors (N, D)."""

    def __init__(self, base: NDArray[np.floating]) -> None:
        self.base = np.ascontiguousarray(base, np.float32)
        if self.base.ndim != 2:
            raise ValueError(f"vectors must be (N, D), got shape {self.base.shape}")

    @abstractmethod
    def knn(self, queries: NDArray[np.floating], k: int) -> tuple[Vec, Idx]: ...

    @abstractmethod
    def within(self, queries: NDArray[np.floating], radius: float) -> tuple[Idx, Idx, Vec]: ...

    def query_rows(self) -> int:
        return max(1, _BLOCK_CELLS // max(1, len(self.base)))


class NumpyIndex(SearchIndex):
    """Exact brute force in numpy, one block of query rows at a time (the reference for the others)."""

    def knn(self, queries: NDArray[np.floating], k: int) -> tuple[Vec, Idx]:
        q = np.asarray(queries, np.float32)
        k_eff = min(k, len(self.base))
        dist = np.full((len(q), k), np.inf, np.float32)
        idx = np.full((len(q), k), -1, np.int64)
        for s in range(0, len(q), self.query_rows()):
            sims = q[s : s + self.query_rows()] @ self.base.T
            top = np.argsort(-sims, axis=1, kind="stable")[:, :k_eff]
            dist[s : s + len(sims), :k_eff] = sim_to_dist(np.take_along_axis(sims, top, 1))
            idx[s : s + len(sims), :k_eff] = top
        return dist, idx

    def within(self, queries: NDArray[np.floating], radius: float) -> tuple[Idx, Idx, Vec]:
        q = np.asarray(queries, np.float32)
        qi, bi, ds = [], [], []
        for s in range(0, len(q), self.query_rows()):
            sims = q[s : s + self.query_rows()] @ self.base.T
            r, c = np.nonzero(sims > dist_to_sim(radius))
            qi.append(r + s)
            bi.append(c)
            ds.append(sim_to_dist(sims[r, c]))
        return _cat(qi, bi, ds)


class FaissIndex(SearchIndex):
    """Common faiss plumbing: inner-product index over the base, batched queries."""

    def __init__(self, base: NDArray[np.floating]) -> None:
        super().__init__(base)
        self.index = self._build()

    @abstractmethod
    def _build(self): ...  # noqa: ANN202 - a faiss index

    def knn(self, queries: NDArray[np.floating], k: int) -> tuple[Vec, Idx]:
        q = np.ascontiguousarray(queries, np.float32)
        dists, idxs = [], []
        for s in range(0, len(q), 8192):
            sims, idx = self.index.search(q[s : s + 8192], k)
            dists.append(np.where(idx >= 0, sim_to_dist(np.where(idx >= 0, sims, -1.0)), np.inf).astype(np.float32))
            idxs.append(idx.astype(np.int64))
        if not dists:
            return np.zeros((0, k), np.float32), np.zeros((0, k), np.int64)
        return np.concatenate(dists), np.concatenate(idxs)

    def within(self, queries: NDArray[np.floating], radius: float) -> tuple[Idx, Idx, Vec]:
        q = np.ascontiguousarray(queries, np.float32)
        qi, bi, ds = [], [], []
        for s in range(0, len(q), 4096):
            lims, sims, idx = self.index.range_search(q[s : s + 4096], dist_to_sim(radius))
            lims = lims.astype(np.int64)
            qi.append(np.repeat(np.arange(len(lims) - 1), np.diff(lims)) + s)
            bi.append(idx.astype(np.int64))
            ds.append(sim_to_dist(sims))
        return _cat(qi, bi, ds)


class FlatIndex(FaissIndex):
    """Exact: faiss ``IndexFlatIP``."""

    def _build(self):  # noqa: ANN202
        import faiss

        index = faiss.IndexFlatIP(self.base.shape[1])
        index.add(self.base)
        return index


class IVFIndex(FaissIndex):
    """Approximate: ``IndexIVFFlat`` with ``nlist = 4 sqrt(N)`` cells (10 k-means iterations on a seeded sample
    of ``40 nlist`` vectors) and ``nprobe`` cells visited per query. Memory: the vectors once (N x D float32)."""

    def __init__(self, base: NDArray[np.floating], nprobe: int = 16, seed: int = 0) -> None:
        self.nprobe, self.seed = nprobe, seed
        super().__init__(base)

    def _build(self):  # noqa: ANN202
        import faiss

        n, d = self.base.shape
        nlist = max(1, min(int(4 * math.sqrt(n)), n // 39))
        quantizer = faiss.IndexFlatIP(d)
        index = faiss.IndexIVFFlat(quantizer, d, nlist, faiss.METRIC_INNER_PRODUCT)
        rng = np.random.default_rng(self.seed)
        sample = self.base[np.sort(rng.choice(n, size=min(n, 40 * nlist), replace=False))]
        index.cp.seed = self.seed
        index.cp.niter = 10  # k-means iterations: cells only need to be roughly right (nprobe covers the rest)
        index.train(sample)
        index.add(self.base)
        index.nprobe = min(self.nprobe, nlist)
        self._quantizer = quantizer  # keep alive alongside the index
        return index


class HNSWIndex(FaissIndex):
    """Approximate: ``IndexHNSWFlat`` (M = 32); ``within`` keeps the ``max_neighbors`` nearest in radius."""

    def __init__(self, base: NDArray[np.floating], max_neighbors: int = 64, ef_search: int = 128) -> None:
        self.max_neighbors, self.ef_search = max_neighbors, ef_search
        super().__init__(base)

    def _build(self):  # noqa: ANN202
        import faiss

        index = faiss.IndexHNSWFlat(self.base.shape[1], 32, faiss.METRIC_INNER_PRODUCT)
        index.hnsw.efConstruction = 80
        index.add(self.base)
        index.hnsw.efSearch = max(self.ef_search, self.max_neighbors)
        return index

    def within(self, queries: NDArray[np.floating], radius: float) -> tuple[Idx, Idx, Vec]:
        dist, idx = self.knn(queries, min(self.max_neighbors, len(self.base)))
        r, c = np.nonzero((dist < radius) & (idx >= 0))
        return r.astype(np.int64), idx[r, c], dist[r, c]


BACKENDS: dict[str, type[SearchIndex]] = {"numpy": NumpyIndex, "flat": FlatIndex, "ivf": IVFIndex, "hnsw": HNSWIndex}


def build_index(base: NDArray[np.floating], backend: str = "auto") -> SearchIndex:
    """An index of the unit vectors ``base`` (N, D) with the named backend (see the module docstring)."""
    if backend == "auto":
        backend = "flat" if len(base) <= AUTO_EXACT_MAX else "ivf"
    if backend == "partition":  # pairs come by partitions (curate.partition); its kNN questions go to ivf
        backend = "ivf"
    if backend not in BACKENDS:
        raise ValueError(f"unknown search backend {backend!r}; choose auto or one of {', '.join(BACKENDS)}")
    return BACKENDS[backend](base)


def self_pairs(index: SearchIndex, radius: float) -> Pairs:
    """Unordered pairs ``i < j`` of base vectors closer than ``radius``, sorted by (i, j).

    A pair found from either end counts (approximate backends may see it from one side only)."""
    qi, bi, dist = index.within(index.base, radius)
    return canonical_pairs(qi, bi, dist, len(index.base))


def duplicate_pairs(
    vectors: NDArray[np.floating], crops: NDArray[np.floating] | None, radius: float, backend: str = "auto"
) -> Pairs:
    """Pairs ``i < j`` whose two-view distance ``min(d(v_i, v_j), d(c_i, v_j), d(v_i, c_j))`` is below
    ``radius``, for whole-image vectors ``vectors`` (N, D) and centre-view vectors ``crops`` (N, D) (a cropped
    copy of an image matches that image's centre view). ``crops=None``: whole views only."""
    index = build_index(vectors, backend)
    qi, bi, dist = index.within(index.base, radius)
    if crops is not None and len(crops):
        ci, cb, cd = index.within(crops, radius)
        qi, bi, dist = np.concatenate([qi, ci]), np.concatenate([bi, cb]), np.concatenate([dist, cd])
    return canonical_pairs(qi, bi, dist, len(vectors))


def canonical_pairs(qi: Idx, bi: Idx, dist: Vec, n: int) -> Pairs:
    """Unordered pairs ``i < j`` (self pairs dropped), each once with its smallest distance, sorted by (i, j)."""
    i, j = np.minimum(qi, bi), np.maximum(qi, bi)
    keep = i != j
    key, d = i[keep] * n + j[keep], dist[keep]
    order = np.lexsort((d, key))
    key, d = key[order], d[order]
    key, first = np.unique(key, return_index=True)
    return Pairs(key // n, key % n, d[first])


def _cat(qi: list, bi: list, ds: list) -> tuple[Idx, Idx, Vec]:
    if not qi:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.float32)
    return (
        np.concatenate(qi).astype(np.int64),
        np.concatenate(bi).astype(np.int64),
        np.concatenate(ds).astype(np.float32),
    )

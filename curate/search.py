"""Nearest-neighbour search on L2-normalised vectors, in batches (never an N x N matrix).

For unit vectors the Euclidean distance ``d`` and the cosine similarity ``s`` are one: ``d = sqrt(2 - 2 s)``.
Every backend answers the same two questions about a base set of vectors (N, D):

- ``knn(queries (Q, D), k) -> (dist (Q, k) float32 ascending, idx (Q, k) int64, -1 when missing)``
- ``within(queries (Q, D), radius) -> (qi (E,), bi (E,), dist (E,))``: every base vector closer than ``radius``.

Those float32 answers depend on the CPU, the thread count and the batch (BLAS and faiss kernels sum in other
orders): 33 of 423 pair distances differed by up to 4.6e-6 between a driver and its Ray workers. So a distance
that decides (a threshold, a nearest neighbour) or is reported is never the search's own: the search finds
candidates within :func:`search_radius` (the radius widened by the float32 error bound :func:`float32_slack`),
and each candidate's distance is computed again in float64 from the float32 vectors (:func:`pair_distances`:
exact products, summed in a fixed binary tree, no BLAS), the same bits on any x86 CPU, thread count or
executor. Pairs (:func:`duplicate_pairs`, :func:`exact_pairs`) and neighbours (:func:`exact_knn`) are decided on
those.

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
_EXACT_CELLS = 1 << 16  # pairs x D per block of float64 products (512 KB: in cache, 3x faster than 16 MB)
KNN_SPARE = 4  # candidates fetched beyond k by exact_knn, so float32 misorder at the k-th rarely needs a refetch

Idx = NDArray[np.int64]
Vec = NDArray[np.float32]
Dist = NDArray[np.float64]


@dataclass(frozen=True)
class Pairs:
    """Pairs ``(i[e], j[e])`` at Euclidean distance ``dist[e]`` (float64, :func:`pair_distances`); each array has
    shape (E,)."""

    i: Idx
    j: Idx
    dist: Dist

    def __len__(self) -> int:
        return int(self.i.shape[0])


def grid_cells(values: NDArray[np.floating]) -> NDArray[np.int64]:
    """(N,) distances or scores -> (N,) int64 cells of :data:`DISTANCE_GRID` (floor), for orderings."""
    return np.floor(np.asarray(values, np.float64) / DISTANCE_GRID).astype(np.int64)


def sim_to_dist(sim: NDArray[np.floating]) -> Vec:
    return np.sqrt(np.maximum(2.0 - 2.0 * np.asarray(sim, np.float32), 0.0)).astype(np.float32)


def dist_to_sim(dist: float) -> float:
    return 1.0 - dist * dist / 2.0


def float32_slack(dim: int) -> float:
    """A bound on ``|d32^2 - d^2|``, a squared distance as a float32 search reports it against the exact one, for
    unit vectors of length ``dim``: a float32 dot product is within ``dim * 2^-24`` of the exact one in any
    summation order, with or without FMA (Higham, Accuracy and Stability, 3.1), so ``d^2 = 2 - 2 s`` within twice
    that; doubled again, and a few units more for the conversions and the threshold's float32 rounding."""
    return 4.0 * (dim + 16) * 2.0**-24


def search_radius(radius: float, dim: int) -> float:
    """The float32 search radius that finds every pair of unit vectors (length ``dim``) whose exact distance is
    below ``radius``: ``sqrt(radius^2 + float32_slack(dim))`` (0.45 -> 0.45009 at D = 320)."""
    return math.sqrt(radius * radius + float32_slack(dim))


def pair_distances(a: NDArray[np.floating], b: NDArray[np.floating], i: Idx, j: Idx) -> Dist:
    """(E,) float64 distances ``sqrt(max(2 - 2 <a[i[e]], b[j[e]]>, 0))`` of rows of ``a`` (N, D) and ``b`` (M, D)
    (float32; other dtypes are rounded to float32 first). Each product of two float32 values is exact in float64
    and the D products are summed in a fixed binary tree of float64 additions (no BLAS, no numpy reduction
    loop), so the bits depend on neither the CPU nor the thread count nor how the pairs were batched."""
    a, b = np.asarray(a, np.float32), np.asarray(b, np.float32)
    i, j = np.asarray(i, np.int64), np.asarray(j, np.int64)
    out = np.empty(len(i), np.float64)
    rows = max(1, _EXACT_CELLS // max(1, a.shape[1]))
    for s in range(0, len(i), rows):
        dots = _tree_sum(a[i[s : s + rows]].astype(np.float64) * b[j[s : s + rows]])  # exact products
        out[s : s + rows] = np.sqrt(np.maximum(2.0 - 2.0 * dots, 0.0))
    return out


def two_view_distances(
    a: NDArray[np.floating],
    a_crops: NDArray[np.floating] | None,
    b: NDArray[np.floating],
    b_crops: NDArray[np.floating] | None,
    i: Idx,
    j: Idx,
) -> Dist:
    """(E,) float64 two-view distances ``min(d(a_i, b_j), d(a'_i, b_j), d(a_i, b'_j))`` (:func:`pair_distances`)
    of whole views ``a`` (N, D), ``b`` (M, D) and centre views ``a_crops`` (N, D), ``b_crops`` (M, D) (None:
    that view left out). Within one set pass it twice: ``two_view_distances(v, c, v, c, i, j)``."""
    dist = pair_distances(a, b, i, j)
    if a_crops is not None and len(a_crops):
        dist = np.minimum(dist, pair_distances(a_crops, b, i, j))
    if b_crops is not None and len(b_crops):
        dist = np.minimum(dist, pair_distances(a, b_crops, i, j))
    return dist


def _tree_sum(p: NDArray[np.float64]) -> Dist:
    """(E, D) -> (E,) row sums in a fixed binary tree of elementwise additions (column c + w/2 onto column c, D
    padded with zeros to a power of 2 w): the same bits on any CPU, unlike a BLAS dot product or numpy's
    reduction (whose order follows the memory layout)."""
    d = p.shape[1]
    if d == 0:
        return np.zeros(len(p))
    width = 1 << (d - 1).bit_length()
    if width != d:  # the first level, against the padding (x + 0 = x) without building it
        half = width // 2
        p, tail = p[:, :half].copy(), p[:, half:]
        p[:, : d - half] += tail
    while p.shape[1] > 1:
        half = p.shape[1] // 2
        p = p[:, :half] + p[:, half:]
    return p[:, 0]


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
    """Unordered pairs ``i < j`` of base vectors closer than ``radius`` (exact float64 distances,
    :func:`exact_pairs`), sorted by (i, j).

    A pair found from either end counts (approximate backends may see it from one side only)."""
    qi, bi, _ = index.within(index.base, search_radius(radius, index.base.shape[1]))
    return exact_pairs(index.base, None, qi, bi, radius)


def duplicate_pairs(
    vectors: NDArray[np.floating], crops: NDArray[np.floating] | None, radius: float, backend: str = "auto"
) -> Pairs:
    """Pairs ``i < j`` whose two-view distance ``min(d(v_i, v_j), d(c_i, v_j), d(v_i, c_j))`` is below
    ``radius``, for whole-image vectors ``vectors`` (N, D) and centre-view vectors ``crops`` (N, D) (a cropped
    copy of an image matches that image's centre view). ``crops=None``: whole views only. Candidates come from
    the float32 search within :func:`search_radius`; the distances and the decision are :func:`exact_pairs`'."""
    index = build_index(vectors, backend)
    wide = search_radius(radius, index.base.shape[1])
    qi, bi, _ = index.within(index.base, wide)
    if crops is not None and len(crops):
        ci, cb, _ = index.within(crops, wide)
        qi, bi = np.concatenate([qi, ci]), np.concatenate([bi, cb])
    return exact_pairs(index.base, crops, qi, bi, radius)


def exact_pairs(
    vectors: NDArray[np.floating], crops: NDArray[np.floating] | None, qi: Idx, bi: Idx, radius: float
) -> Pairs:
    """The candidate pairs ``(qi[e], bi[e])`` (E,) of rows of ``vectors`` (N, D), in either order and repeated
    at will, as unordered pairs ``i < j`` (self pairs dropped) whose float64 two-view distance
    (:func:`two_view_distances` with centre views ``crops`` (N, D) or None) is below ``radius``, sorted by (i, j):
    the same pairs and bits however the candidates were found, as long as they include every such pair."""
    n = max(1, len(vectors))
    i, j = np.minimum(qi, bi).astype(np.int64), np.maximum(qi, bi).astype(np.int64)
    key = np.unique(i[i != j] * n + j[i != j])
    i, j = key // n, key % n
    dist = two_view_distances(vectors, crops, vectors, crops, i, j)
    keep = dist < radius
    return Pairs(i[keep], j[keep], dist[keep])


def exact_knn(index: SearchIndex, queries: NDArray[np.floating], k: int) -> tuple[Dist, Idx]:
    """The ``k`` nearest base vectors of each query (Q, D) by float64 distance (:func:`pair_distances`): (Q, k)
    float64 ascending (ties: lower index first; inf where missing) and (Q, k) int64 indices (-1 where missing).

    The index's float32 kNN gives ``k +`` :data:`KNN_SPARE` candidates; they are settled exactly, and a row
    whose k-th exact distance is not clear of its last candidate by :func:`float32_slack` (a vector not fetched
    might be nearer) asks again with twice as many. With an exact index the answer is the exact kNN on any CPU;
    with an approximate one, the exact order of what it finds."""
    q = np.ascontiguousarray(queries, np.float32)
    n, k_eff = len(index.base), min(k, len(index.base))
    dist, idx = np.full((len(q), k), np.inf), np.full((len(q), k), -1, np.int64)
    rows, fetch = np.arange(len(q)), min(n, k_eff + KNN_SPARE)
    slack = float32_slack(index.base.shape[1])
    while len(rows) and k_eff:
        d32, cand = index.knn(q[rows], fetch)
        found = cand >= 0
        exact = np.full(cand.shape, np.inf)
        r, c = np.nonzero(found)
        exact[r, c] = pair_distances(q[rows], index.base, r, cand[r, c])
        order = np.lexsort((np.where(found, cand, n), exact))[:, :k_eff]
        best, best_idx = np.take_along_axis(exact, order, 1), np.take_along_axis(cand, order, 1)
        last = d32[:, -1].astype(np.float64)
        clear = (fetch >= n) | ~np.isfinite(last) | (best[:, -1] ** 2 < last**2 - slack)
        dist[rows[clear], :k_eff], idx[rows[clear], :k_eff] = best[clear], best_idx[clear]
        rows, fetch = rows[~clear], min(n, 2 * fetch)
    return dist, idx


def _cat(qi: list, bi: list, ds: list) -> tuple[Idx, Idx, Vec]:
    if not qi:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.float32)
    return (
        np.concatenate(qi).astype(np.int64),
        np.concatenate(bi).astype(np.int64),
        np.concatenate(ds).astype(np.float32),
    )

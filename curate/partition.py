"""Near-duplicate pairs by partitions, for collections too large for one index on one node (the ``partition``
search backend; SemDeDup-style).

1. **Cells.** k-means (faiss, seeded sample) cuts the unit vectors (N, D) into ``cells`` of about
   :data:`CELL_VECTORS` vectors; each vector's *home* is its nearest centroid.
2. **Probes.** Each query (every whole-image vector, and every centre view when given) probes its ``nprobe``
   nearest cells (found in tasks of :data:`ASSIGN_ROWS` queries on a cluster: N x cells x D work).
3. **Tasks.** A task takes a run of cells (about :data:`TASK_VECTORS` home vectors in all) and searches exactly
   (faiss ``IndexFlatIP``) the home vectors of each cell for the queries that probe it, within the radius. Tasks
   run in this process one after another, or as Ray tasks on a :class:`~ground.run.cluster.Cluster`; each
   carries only its own vectors, so a worker's memory is O(task) and the driver's is the vectors, their probes
   and the pairs: O(N (D + nprobe)).

A pair is found when one end's home is among the other's probed cells: the search is approximate, its recall
against exact search is measured by ``bench/bench_search_partition.py``. Tasks search within
:func:`curate.search.search_radius` and return candidates only; the driver computes each candidate's two-view
distance in float64 and applies the radius (:func:`curate.search.exact_pairs`), and a probe whose nearest or
last cell is within float32 error of the next is settled exactly (:func:`nearest_cells`), so task order, batch
sizes, thread counts and the executor change neither the pairs nor a bit of their distances.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from curate.search import FlatIndex, Pairs, exact_knn, exact_pairs, float32_slack, search_radius
from ground.run.cluster import Cluster
from ground.run.progress import progress

PARTITION = "partition"  # the backend's name (``--backend partition``)
#: ``auto`` searches by partitions above this many vectors: one flat or IVF index of 10 M x 320 float32 is 13 GB
#: on one node, and its search one node's work.
AUTO_PARTITION_MIN = 10_000_000
CELL_VECTORS = 1000  # mean home vectors per cell
NPROBE = 8  # cells each query searches
TASK_VECTORS = 10_000  # home vectors per task (cells are grouped up to this): a task carries about
# 2 nprobe TASK_VECTORS D float32 of queries (200 MB at D = 320 with centre views)
ASSIGN_ROWS = 200_000  # queries per task that finds their nearest cells (on a cluster)
KMEANS_SAMPLE = 64  # training vectors per centroid (faiss warns below 39)
KMEANS_ITER = 10


@dataclass(frozen=True)
class CellTask:
    """One task: ``cells`` runs of home vectors ``base[starts[c]:starts[c+1]]`` with global ids ``base_ids``,
    searched by queries ``queries[qstarts[c]:qstarts[c+1]]`` with global ids ``query_ids``. Shapes: base (B, D),
    queries (Q, D) float32; starts (C + 1,), qstarts (C + 1,) int64."""

    base: NDArray[np.float32]
    base_ids: NDArray[np.int64]
    starts: NDArray[np.int64]
    queries: NDArray[np.float32]
    query_ids: NDArray[np.int64]
    qstarts: NDArray[np.int64]


def search_cells(task: CellTask, radius: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The candidates (query ids (E,), base ids (E,), global) closer than ``radius`` by the float32 search inside
    each cell of ``task``; their distances are the driver's (:func:`curate.search.exact_pairs`)."""
    qi, bi = [], []
    for c in range(len(task.starts) - 1):
        b0, b1, q0, q1 = task.starts[c], task.starts[c + 1], task.qstarts[c], task.qstarts[c + 1]
        if b1 == b0 or q1 == q0:
            continue
        q, b, _ = FlatIndex(task.base[b0:b1]).within(task.queries[q0:q1], radius)
        qi.append(task.query_ids[q0:q1][q])
        bi.append(task.base_ids[b0:b1][b])
    if not qi:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(qi), np.concatenate(bi)


def train_cells(vectors: NDArray[np.float32], cells: int, seed: int) -> NDArray[np.float32]:
    """(cells, D) unit centroids of spherical k-means on a seeded sample of ``vectors`` (N, D)."""
    import faiss

    n, d = vectors.shape
    rng = np.random.default_rng(seed)
    sample = vectors[np.sort(rng.choice(n, size=min(n, KMEANS_SAMPLE * cells), replace=False))]
    kmeans = faiss.Kmeans(d, cells, niter=KMEANS_ITER, seed=seed, spherical=True, verbose=False)
    kmeans.train(np.ascontiguousarray(sample, np.float32))
    return np.ascontiguousarray(kmeans.centroids, np.float32)


def nearest_cells(vectors: NDArray[np.float32], centroids: NDArray[np.float32], k: int) -> NDArray[np.int64]:
    """(N, k) int64 indices of each vector's ``k`` nearest centroids (D-dimensional unit rows), nearest first.

    The nearest (the home) and the set of ``k`` are exact: a row whose first two or whose k-th and next float32
    distances lie within twice :func:`curate.search.float32_slack` of each other is settled in float64
    (:func:`curate.search.exact_knn`), so a probe does not depend on the CPU, the thread count or the batch."""
    k = min(k, len(centroids))
    index = FlatIndex(centroids)
    dist, idx = index.knn(vectors, min(k + 1, len(centroids)))
    sq, slack = dist.astype(np.float64) ** 2, 2 * float32_slack(centroids.shape[1])
    close = np.zeros(len(vectors), bool)
    if sq.shape[1] > 1:
        close |= sq[:, 1] - sq[:, 0] <= slack
    if sq.shape[1] > k:
        close |= sq[:, k] - sq[:, k - 1] <= slack
    rows = np.flatnonzero(close)
    if len(rows):
        idx[rows, :k] = exact_knn(index, vectors[rows], k)[1]
    return idx[:, :k]


def probe_cells(
    vectors: NDArray[np.float32],
    crops: NDArray[np.float32] | None,
    centroids: NDArray[np.float32],
    nprobe: int,
    cluster: Cluster | None = None,
) -> NDArray[np.int64]:
    """(Q, nprobe) nearest cells of every query, nearest first: rows 0..N-1 the whole views, then the centre
    views. On a ``cluster`` in tasks of :data:`ASSIGN_ROWS` rows (the centroids sent once)."""
    views = [vectors] if crops is None or not len(crops) else [vectors, crops]
    if cluster is None:
        return np.concatenate([nearest_cells(v, centroids, nprobe) for v in views])
    chunks = [v[s : s + ASSIGN_ROWS] for v in views for s in range(0, len(v), ASSIGN_ROWS)]
    out: list[NDArray[np.int64]] = [np.zeros((0, nprobe), np.int64)] * len(chunks)
    for k, found in cluster.map(nearest_cells, chunks, cluster.put(centroids), nprobe, num_cpus=1):
        out[k] = found
    return np.concatenate(out)


def plan_tasks(
    probe: NDArray[np.int64], n: int, cells: int, task_vectors: int = TASK_VECTORS
) -> list[tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]]:
    """Index plans of the tasks for the probes ``probe`` (Q, nprobe) of :func:`probe_cells` (``n`` whole views,
    each one's home its first probe): (base ids, cell starts, query row ids, query cell starts) each, cells in
    order. Query rows ``r >= n`` stand for centre view ``r - n``."""
    home = probe[:n, 0]
    base_order = np.argsort(home, kind="stable")
    base_starts = np.searchsorted(home[base_order], np.arange(cells + 1))
    flat_cell = probe.ravel()
    query_order = np.argsort(flat_cell, kind="stable")
    query_rows = (query_order // probe.shape[1]).astype(np.int64)
    query_starts = np.searchsorted(flat_cell[query_order], np.arange(cells + 1))
    plans, first = [], 0
    for c in range(cells):
        if base_starts[c + 1] - base_starts[first] >= task_vectors or c == cells - 1:
            b = base_starts[first : c + 2]
            q = query_starts[first : c + 2]
            plans.append((base_order[b[0] : b[-1]], b - b[0], query_rows[q[0] : q[-1]], q - q[0]))
            first = c + 1
    return plans


def make_task(
    plan: tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]],
    vectors: NDArray[np.float32],
    crops: NDArray[np.float32] | None,
) -> CellTask:
    """The :class:`CellTask` of one plan: its vectors copied out of ``vectors`` (N, D) and ``crops``."""
    base_ids, starts, rows, qstarts = plan
    n = len(vectors)
    whole = rows < n
    queries = np.empty((len(rows), vectors.shape[1]), np.float32)
    queries[whole] = vectors[rows[whole]]
    if crops is not None and not whole.all():
        queries[~whole] = crops[rows[~whole] - n]
    return CellTask(vectors[base_ids], base_ids, starts, queries, np.where(whole, rows, rows - n), qstarts)


def partitioned_pairs(
    vectors: NDArray[np.floating],
    crops: NDArray[np.floating] | None,
    radius: float,
    cluster: Cluster | None = None,
    cells: int | None = None,
    nprobe: int = NPROBE,
    seed: int = 0,
) -> Pairs:
    """Pairs ``i < j`` whose two-view distance is below ``radius`` (as :func:`curate.search.duplicate_pairs`, float64
    distances), found by partitions (see the module docstring); ``cells`` default ``N / CELL_VECTORS``. Tasks
    run on ``cluster`` when given, else here."""
    vectors = np.ascontiguousarray(vectors, np.float32)
    crops = None if crops is None else np.ascontiguousarray(crops, np.float32)
    n = len(vectors)
    if n < 2:
        return exact_pairs(vectors, crops, np.zeros(0, np.int64), np.zeros(0, np.int64), radius)
    cells = min(n, cells or max(1, n // CELL_VECTORS))
    centroids = train_cells(vectors, cells, seed)
    plans = plan_tasks(probe_cells(vectors, crops, centroids, nprobe, cluster), n, cells)
    tasks = (make_task(plan, vectors, crops) for plan in plans)  # made as they are needed (bounded memory)
    wide = search_radius(radius, vectors.shape[1])
    if cluster is None:
        done = ((k, search_cells(task, wide)) for k, task in enumerate(tasks))
    else:
        done = cluster.map(search_cells, tasks, wide, num_cpus=1)
    found = [r for _, r in progress(done, total=len(plans), desc="partitions", unit="task", min_items=4)]
    qi, bi = (np.concatenate([f[k] for f in found]) for k in range(2))
    return exact_pairs(vectors, crops, qi, bi, radius)

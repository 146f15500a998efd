"""Partitioned near-duplicate search: on planted vectors it finds >= 99 % of the exact pairs and nothing else,
with the exact search's float64 distances; every vector is searched in its home cell; the pairs and their bits
are the same for any thread count and task size, in this process and on a real Ray head; a dedup with
``backend="partition"`` keeps what the exact search keeps."""

from __future__ import annotations

import numpy as np
import pytest

from curate.embed import l2_normalize
from curate.partition import make_task, nearest_cells, partitioned_pairs, plan_tasks, probe_cells, train_cells
from curate.search import duplicate_pairs
from ground.run.cluster import Cluster

RADIUS = 0.45


def planted(n: int, dim: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(n, dim) unit vectors around 50 themes, a tenth of them noisy copies of others, and (n, dim) "centre views"
    (each vector nudged), as :func:`curate.search.duplicate_pairs` takes them."""
    rng = np.random.default_rng(seed)
    themes = rng.standard_normal((50, dim)).astype(np.float32)
    x = themes[rng.integers(0, 50, n)] + 1.2 * rng.standard_normal((n, dim)).astype(np.float32)
    k = n // 10
    src = rng.integers(0, n - k, k)
    x[n - k :] = x[src] + rng.uniform(0.05, 0.25, (k, 1)).astype(np.float32) * rng.standard_normal((k, dim))
    crops = x + 0.2 * rng.standard_normal((n, dim)).astype(np.float32)
    return l2_normalize(x), l2_normalize(crops)


def test_partitions_find_the_exact_pairs_with_their_distances() -> None:
    x, crops = planted(6000, 48, seed=0)
    exact = duplicate_pairs(x, crops, RADIUS, "numpy")
    found = partitioned_pairs(x, crops, RADIUS, cells=12)
    truth = dict(zip(zip(exact.i.tolist(), exact.j.tolist()), exact.dist.tolist()))
    got = dict(zip(zip(found.i.tolist(), found.j.tolist()), found.dist.tolist()))
    assert len(truth) > 500
    assert set(got) <= set(truth)  # nothing but true pairs
    assert len(set(got) & set(truth)) / len(truth) >= 0.99
    assert all(got[p] == truth[p] for p in got)  # the same float64 distances, bit for bit


def test_every_vector_has_one_home_and_every_query_its_probes() -> None:
    x, crops = planted(3000, 32, seed=1)
    centroids = train_cells(x, 9, seed=0)
    probe = probe_cells(x, crops, centroids, nprobe=3)
    assert probe.shape == (2 * len(x), 3) and np.array_equal(probe[: len(x), :1], nearest_cells(x, centroids, 1))
    plans = plan_tasks(probe, len(x), 9, task_vectors=700)
    assert len(plans) > 1
    homes = np.concatenate([p[0] for p in plans])
    assert np.array_equal(np.sort(homes), np.arange(len(x)))  # each vector in exactly one cell
    rows = np.concatenate([p[2] for p in plans])
    assert np.array_equal(np.bincount(rows, minlength=2 * len(x)), np.full(2 * len(x), 3))  # nprobe per view
    task = make_task(plans[0], x, crops)
    whole = plans[0][2] < len(x)
    assert np.array_equal(task.queries[whole], x[task.query_ids[whole]])
    assert np.array_equal(task.queries[~whole], crops[task.query_ids[~whole]])
    assert np.array_equal(task.base, x[task.base_ids])


def test_probes_are_the_exact_nearest_cells_ties_to_the_lower_cell() -> None:
    from curate.search import pair_distances

    x, _ = planted(2000, 32, seed=5)
    centroids = train_cells(x, 40, seed=0)
    probe = nearest_cells(x, centroids, 4)
    rows, cells = np.repeat(np.arange(len(x)), 40), np.tile(np.arange(40), len(x))
    exact = pair_distances(x, centroids, rows, cells).reshape(len(x), 40)
    truth = np.lexsort((np.broadcast_to(np.arange(40), exact.shape), exact))[:, :4]
    assert np.array_equal(probe[:, 0], truth[:, 0])  # the home
    assert np.array_equal(np.sort(probe, axis=1), np.sort(truth, axis=1))  # the probed set
    axes = np.eye(8, dtype=np.float32)
    between = l2_normalize(np.array([[1, 1, 0, 0, 0, 0, 0, 0], [0, 0, 1, 1, 1, 0, 0, 0]], np.float32))
    assert nearest_cells(between, axes, 1)[:, 0].tolist() == [0, 2]  # exact ties: the lower cell
    assert nearest_cells(between, axes[::-1].copy(), 1)[:, 0].tolist() == [6, 3]
    assert sorted(nearest_cells(between, axes, 3)[1].tolist()) == [2, 3, 4]


@pytest.mark.slow
def test_a_ray_cluster_finds_the_same_pairs(cluster: Cluster, monkeypatch: pytest.MonkeyPatch) -> None:
    from curate import partition

    x, crops = planted(4000, 32, seed=2)
    monkeypatch.setattr(partition, "ASSIGN_ROWS", 1000)  # 8 assignment tasks
    here = partitioned_pairs(x, crops, RADIUS, cells=16)
    there = partitioned_pairs(x, crops, RADIUS, cluster=cluster, cells=16)
    for a, b in zip((here.i, here.j, here.dist), (there.i, there.j, there.dist)):
        assert np.array_equal(a, b)


def test_the_same_pairs_and_bits_for_any_thread_count_and_task_size(monkeypatch: pytest.MonkeyPatch) -> None:
    """Probes found in one call or in tasks of 500 rows, cells searched in tasks of any size, faiss on 1 or 2
    threads: the same pairs and float64 distances; a radius at a pair's distance leaves it out, the next float
    up takes it in."""
    import faiss

    from curate import partition

    x, crops = planted(4000, 32, seed=4)
    ref = partitioned_pairs(x, crops, RADIUS, cells=16)
    assert len(ref) > 300
    before = faiss.omp_get_max_threads()
    try:
        for threads, task_vectors, assign_rows in ((1, 300, 500), (2, 10**6, 500), (1, 10**6, 10**6)):
            faiss.omp_set_num_threads(threads)
            monkeypatch.setattr(partition, "TASK_VECTORS", task_vectors)
            monkeypatch.setattr(partition, "ASSIGN_ROWS", assign_rows)
            got = partitioned_pairs(x, crops, RADIUS, cluster=_InProcess(), cells=16)
            for a, b in zip((got.i, got.j, got.dist), (ref.i, ref.j, ref.dist)):
                assert np.array_equal(a, b)
    finally:
        faiss.omp_set_num_threads(before)
    k = len(ref) // 2
    d, pair = float(ref.dist[k]), (ref.i[k], ref.j[k])
    at = partitioned_pairs(x, crops, d, cells=16)
    assert pair not in set(zip(at.i, at.j))
    above = partitioned_pairs(x, crops, float(np.nextafter(d, 3.0)), cells=16)
    assert pair in set(zip(above.i, above.j))


class _InProcess:
    """The part of :class:`ground.run.cluster.Cluster` the partitioned search uses, run here: probes in tasks of
    ``ASSIGN_ROWS`` as on a cluster, results yielded last task first (a cluster yields them as they finish)."""

    def put(self, value: object) -> object:
        return value

    def map(self, fn, items, *args, **_resources):  # noqa: ANN001, ANN201 - Cluster.map's shape
        return reversed([(k, fn(item, *args)) for k, item in enumerate(items)])


def test_dedup_by_partitions_keeps_what_exact_search_keeps(monkeypatch: pytest.MonkeyPatch) -> None:
    from curate import partition
    from curate.dedup import find_duplicates
    from curate.embedcache import FileFacts
    from curate.scan import ScannedImage

    x, crops = planted(1500, 32, seed=3)
    images = [
        ScannedImage(f"/img/{i:05d}.jpg", FileFacts(f"{i:064x}", 1000 + i, 640, 480, f"p{i}", float(i % 7)))
        for i in range(len(x))
    ]
    monkeypatch.setattr(partition, "CELL_VECTORS", 100)  # 15 cells
    exact = find_duplicates(images, x, RADIUS, "flat", crops=crops)
    parted = find_duplicates(images, x, RADIUS, "partition", crops=crops)
    assert len(exact.removed) > 100
    assert parted.kept == exact.kept and parted.groups == exact.groups

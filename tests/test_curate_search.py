"""Search backends: faiss == numpy brute force (exact ones), approximate ones with high recall; the distances that
decide are float64, equal to a reference formula and the same bits for every backend, thread count and block."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from curate.embed import l2_normalize
from curate.search import (
    BACKENDS,
    build_index,
    dist_to_sim,
    duplicate_pairs,
    exact_knn,
    pair_distances,
    self_pairs,
    sim_to_dist,
    two_view_distances,
)

REPO = Path(__file__).resolve().parents[1]


def _planted(n: int = 600, d: int = 32, seed: int = 0) -> np.ndarray:
    """Unit vectors with planted near copies: the last third are noisy copies of the first third."""
    rng = np.random.default_rng(seed)
    base = rng.standard_normal((n - n // 3, d))
    copies = base[: n // 3] + 0.15 * rng.standard_normal((n // 3, d))
    return l2_normalize(np.concatenate([base, copies]))


def _pair_set(pairs) -> set[tuple[int, int]]:
    return set(zip(pairs.i.tolist(), pairs.j.tolist()))


def _far_from(x: np.ndarray, radius: float, eps: float = 1e-4) -> set[tuple[int, int]]:
    """Pairs whose distance is within eps of the radius (float order may decide them either way)."""
    d = sim_to_dist(x @ x.T)
    i, j = np.nonzero(np.abs(d - radius) < eps)
    return {(a, b) for a, b in zip(i.tolist(), j.tolist()) if a < b}


def test_distance_similarity_round_trip() -> None:
    for d in (0.0, 0.3, 1.0, 1.9):
        assert sim_to_dist(np.array([dist_to_sim(d)]))[0] == pytest.approx(d, abs=1e-3)


@pytest.mark.parametrize("backend", ["flat", "ivf", "hnsw"])
def test_faiss_range_pairs_match_brute_force(backend: str) -> None:
    x = _planted()
    radius = 0.5
    ref = self_pairs(build_index(x, "numpy"), radius)
    got = self_pairs(build_index(x, backend), radius)
    assert len(ref) >= 200  # the planted copies
    border = _far_from(x, radius)
    missing, extra = _pair_set(ref) - _pair_set(got) - border, _pair_set(got) - _pair_set(ref) - border
    assert not extra
    if backend == "flat":
        assert not missing
        np.testing.assert_allclose(np.sort(got.dist), np.sort(ref.dist), atol=1e-3)
    else:
        assert len(missing) <= 0.05 * len(ref)


@pytest.mark.parametrize("backend", ["numpy", "flat"])
def test_two_view_pairs_match_brute_force(backend: str) -> None:
    """min(d(v_i, v_j), d(c_i, v_j), d(v_i, c_j)) < r, computed densely, equals the batched search."""
    rng = np.random.default_rng(5)
    v = _planted(240, 32, seed=5)
    c = l2_normalize(v + 0.4 * rng.standard_normal(v.shape))
    c[:20] = l2_normalize(v[100:120] + 0.05 * rng.standard_normal((20, 32)))  # i's centre view ~ whole of 100+i
    radius = 0.6
    sims = np.maximum.reduce([v @ v.T, c @ v.T, v @ c.T])
    d = sim_to_dist(sims)
    i, j = np.nonzero(np.triu(d < radius, 1))
    expected = set(zip(i.tolist(), j.tolist()))
    got = duplicate_pairs(v, c, radius, backend)
    border = {(a, b) for a, b in zip(*np.nonzero(np.triu(np.abs(d - radius) < 1e-4, 1)))}
    assert _pair_set(got) ^ expected <= border
    assert {(k, 100 + k) for k in range(20)} <= _pair_set(got)  # found only through the centre views
    assert not {(k, 100 + k) for k in range(20)} & _pair_set(self_pairs(build_index(v, "numpy"), radius))
    np.testing.assert_allclose(got.dist, d[got.i, got.j], atol=1e-3)


def test_flat_knn_matches_numpy() -> None:
    x = _planted(300, 16, seed=1)
    q = x[:50]
    d_ref, i_ref = build_index(x, "numpy").knn(q, 5)
    d_got, i_got = build_index(x, "flat").knn(q, 5)
    np.testing.assert_allclose(d_got, d_ref, atol=1e-3)
    assert (i_got[:, 0] == np.arange(50)).all() and (i_ref[:, 0] == np.arange(50)).all()
    assert (i_got == i_ref).mean() > 0.98  # ties may swap


def test_queries_against_another_set() -> None:
    a, b = _planted(90, 32, seed=2)[:60], _planted(90, 32, seed=2)[60:]
    for backend in ("numpy", "flat"):
        qi, bi, dist = build_index(b, backend).within(a, 0.5)
        assert set(zip(qi.tolist(), bi.tolist())) == {(k, k) for k in range(30)}
        assert (dist < 0.5).all()


def test_knn_with_more_neighbours_than_vectors() -> None:
    x = _planted(9, 4)
    dist, idx = build_index(x, "numpy").knn(x, 20)
    assert (idx[:, 9:] == -1).all() and np.isinf(dist[:, 9:]).all()
    _, fidx = build_index(x, "flat").knn(x, 20)
    assert (fidx[:, 9:] == -1).all()


def test_unknown_backend_raises() -> None:
    with pytest.raises(ValueError, match="unknown search backend"):
        build_index(_planted(30, 4), "annoy")
    with pytest.raises(ValueError):
        build_index(np.zeros(5, np.float32), "numpy")
    assert set(BACKENDS) == {"numpy", "flat", "ivf", "hnsw"}


def _reference_distance(a: np.ndarray, b: np.ndarray) -> float:
    """sqrt(2 - 2 <a, b>) with the dot product summed exactly (math.fsum of the float32 values' products)."""
    dot = math.fsum(float(x) * float(y) for x, y in zip(a.tolist(), b.tolist()))
    return math.sqrt(max(2.0 - 2.0 * dot, 0.0))


@pytest.mark.parametrize("dim", [1, 37, 320])
def test_exact_distances_equal_a_float64_reference_whatever_the_batch(dim: int, monkeypatch) -> None:
    from curate import search

    x = _planted(200, dim, seed=dim).astype(np.float32)
    rng = np.random.default_rng(dim)
    i, j = rng.integers(0, len(x), 500), rng.integers(0, len(x), 500)
    i[:20], j[:20] = np.arange(20), np.arange(20)  # self pairs: distance ~0
    got = pair_distances(x, x, i, j)
    assert got.dtype == np.float64 and got.shape == (500,)
    ref = np.array([_reference_distance(x[a], x[b]) for a, b in zip(i, j)])
    assert np.abs(got - ref).max() <= 1e-12 + 1e-15 / np.maximum(ref, 1e-3).min()
    monkeypatch.setattr(search, "_EXACT_CELLS", 3 * dim)  # blocks of 3 pairs
    assert np.array_equal(pair_distances(x, x, i, j), got)
    assert np.array_equal(pair_distances(x, x, j[::-1], i[::-1])[::-1], got)  # symmetric, in any order


def test_every_exact_backend_gives_the_same_pairs_and_bits() -> None:
    """The float32 searches (numpy's BLAS, faiss's kernels) differ in the last bits; the pairs' float64 distances
    do not, and they equal the reference formula."""
    rng = np.random.default_rng(7)
    v = _planted(400, 64, seed=7)
    c = l2_normalize(v + 0.3 * rng.standard_normal(v.shape))
    ref = duplicate_pairs(v, c, 0.5, "numpy")
    assert len(ref) > 100 and ref.dist.dtype == np.float64 and (ref.dist < 0.5).all()
    for backend in ("flat", "hnsw"):
        got = duplicate_pairs(v, c, 0.5, backend)
        for a, b in zip((got.i, got.j, got.dist), (ref.i, ref.j, ref.dist)):
            assert np.array_equal(a, b)
    views = [(v, v), (c, v), (v, c)]
    k = 17
    two_view = min(_reference_distance(p[ref.i[k]], q[ref.j[k]]) for p, q in views)
    assert abs(ref.dist[k] - two_view) <= 1e-12
    assert np.array_equal(two_view_distances(v, c, v, c, ref.i, ref.j), ref.dist)


def _numpy_threads_run(tmp_path, threads: int) -> dict[str, np.ndarray]:
    """duplicate_pairs (numpy and flat) and exact_knn in a fresh interpreter whose BLAS and OpenMP use ``threads``."""
    script = (
        "import sys, numpy as np\n"
        "from curate.search import build_index, duplicate_pairs, exact_knn\n"
        "d = np.load(sys.argv[1]); v, c = d['v'], d['c']\n"
        "out = {}\n"
        "for b in ('numpy', 'flat'):\n"
        "    p = duplicate_pairs(v, c, 0.5, b)\n"
        "    out.update({b + '_i': p.i, b + '_j': p.j, b + '_d': p.dist})\n"
        "    out[b + '_kd'], out[b + '_ki'] = exact_knn(build_index(v, b), c, 5)\n"
        "np.savez(sys.argv[2], **out)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS"):
        env[var] = str(threads)
    out = tmp_path / f"threads{threads}.npz"
    subprocess.run([sys.executable, "-c", script, str(tmp_path / "in.npz"), str(out)], env=env, cwd=REPO, check=True)
    return dict(np.load(out))


def test_the_same_pairs_and_bits_for_any_thread_count_and_block(tmp_path, monkeypatch) -> None:
    import faiss

    from curate import search

    rng = np.random.default_rng(3)
    v = _planted(3000, 96, seed=3)
    c = l2_normalize(v + 0.3 * rng.standard_normal(v.shape))
    np.savez(tmp_path / "in.npz", v=v, c=c)
    one, two = _numpy_threads_run(tmp_path, 1), _numpy_threads_run(tmp_path, 2)
    assert len(one["numpy_i"]) > 500
    for key in one:
        assert np.array_equal(one[key], two[key]), key
    for b in ("numpy", "flat"):  # the backends agree with each other, bit for bit
        for part in ("_i", "_j", "_d", "_kd", "_ki"):
            assert np.array_equal(one[b + part], one["numpy" + part]), b + part
    before = faiss.omp_get_max_threads()
    monkeypatch.setattr(search, "_BLOCK_CELLS", 7 * len(v))  # numpy: blocks of 7 query rows
    try:
        for threads in (1, 2):
            faiss.omp_set_num_threads(threads)
            for b in ("numpy", "flat"):
                p = duplicate_pairs(v, c, 0.5, b)
                assert np.array_equal(p.dist, one[b + "_d"]) and np.array_equal(p.i, one[b + "_i"])
                kd, ki = exact_knn(build_index(v, b), c, 5)
                assert np.array_equal(kd, one["numpy_kd"]) and np.array_equal(ki, one["numpy_ki"])
    finally:
        faiss.omp_set_num_threads(before)


@pytest.mark.parametrize("backend", ["numpy", "flat", "hnsw"])
def test_a_pair_at_the_threshold_is_decided_on_its_exact_distance(backend: str) -> None:
    """A radius equal to a pair's float64 distance leaves it out (d < t), the next float up takes it in, whatever
    the float32 search said about it (here rounded to either side on purpose)."""
    v = _planted(300, 32, seed=4)
    ref = duplicate_pairs(v, None, 0.6, "numpy")
    for k in (0, len(ref) // 2, len(ref) - 1):
        d = float(ref.dist[k])
        pair = (int(ref.i[k]), int(ref.j[k]))
        assert pair not in _pair_set(duplicate_pairs(v, None, d, backend))
        got = duplicate_pairs(v, None, float(np.nextafter(d, 3.0)), backend)
        assert pair in _pair_set(got) and got.dist[_pair_set_index(got, pair)] == d
        for r in (float(np.float32(d)), float(np.nextafter(np.float32(d), np.float32(3)))):  # float32 neighbours
            assert (pair in _pair_set(duplicate_pairs(v, None, r, backend))) == (d < r)


def _pair_set_index(pairs, pair: tuple[int, int]) -> int:
    return int(np.flatnonzero((pairs.i == pair[0]) & (pairs.j == pair[1]))[0])


def test_exact_knn_settles_ties_and_misorder_by_refetching(monkeypatch) -> None:
    """Ten identical copies of one vector tie exactly: the k nearest are the lowest indices, even when the float32
    kNN fetched other copies and no spare candidates (each row then asks again with twice as many)."""
    from curate import search

    monkeypatch.setattr(search, "KNN_SPARE", 0)
    x = _planted(60, 16, seed=9)
    x[[5, 11, 17, 23, 29, 35, 41, 47, 53, 59]] = x[5]
    for backend in ("numpy", "flat"):
        dist, idx = exact_knn(build_index(x, backend), x[[5, 59, 0]], 3)
        assert dist.dtype == np.float64 and idx.shape == (3, 3)
        assert idx[:2].tolist() == [[5, 11, 17]] * 2 and np.all(dist[:2] == dist[0, 0])
        everything = pair_distances(x, x, np.zeros(len(x), np.int64), np.arange(len(x)))
        assert idx[2].tolist() == np.lexsort((np.arange(len(x)), everything))[:3].tolist()
    dist, idx = exact_knn(build_index(x[:2], "flat"), x[:3], 5)  # more neighbours than vectors
    assert (idx[:, 2:] == -1).all() and np.isinf(dist[:, 2:]).all()

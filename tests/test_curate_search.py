"""Search backends: faiss == numpy brute force (exact ones), approximate ones with high recall."""

from __future__ import annotations

import numpy as np
import pytest

from curate.embed import l2_normalize
from curate.search import BACKENDS, build_index, dist_to_sim, duplicate_pairs, self_pairs, sim_to_dist


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

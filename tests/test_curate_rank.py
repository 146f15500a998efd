"""Diversity ranking: outliers score high, duplicates low; k-center covers every cluster first."""

from __future__ import annotations

import numpy as np
import pytest

from curate.embed import l2_normalize
from curate.rank import diversity_scores, k_center, rank_order


def _clusters(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """4 tight clusters of 10 unit vectors (32-d) and 1 isolated vector (last row); labels per row."""
    rng = np.random.default_rng(seed)
    centers = rng.standard_normal((5, 32))
    rows = [centers[c] + 0.05 * rng.standard_normal(32) for c in range(4) for _ in range(10)]
    rows.append(centers[4])
    return l2_normalize(np.array(rows)), np.array([c for c in range(4) for _ in range(10)] + [4])


def test_isolated_vector_scores_highest() -> None:
    x, _ = _clusters()
    scores = diversity_scores(x, k=5)
    assert scores.shape == (41,)
    assert int(np.argmax(scores)) == 40
    assert scores[:40].max() < 0.5 * scores[40]


def test_scores_match_brute_force() -> None:
    x, _ = _clusters(1)
    d = np.linalg.norm(x[:, None] - x[None], axis=2)
    np.fill_diagonal(d, np.inf)
    expected = np.sort(d, axis=1)[:, :3].mean(axis=1)
    np.testing.assert_allclose(diversity_scores(x, k=3), expected, atol=2e-3)
    np.testing.assert_allclose(diversity_scores(x, k=3, backend="numpy"), expected, atol=2e-3)


def test_k_center_visits_every_cluster_first() -> None:
    x, labels = _clusters(2)
    picked = k_center(x, 5, first=0)
    assert len(set(picked)) == 5 and set(labels[picked]) == {0, 1, 2, 3, 4}


def test_rank_order_methods_and_errors() -> None:
    x, labels = _clusters(3)
    keys = [f"{i:03d}" for i in range(len(x))]
    order, scores = rank_order(x, keys, "score", k=5)
    assert order[0] == 40 and sorted(order) == list(range(41))
    order_kc, _ = rank_order(x, keys, "kcenter", k=5)
    assert order_kc[0] == 40 and set(labels[order_kc[:5]]) == {0, 1, 2, 3, 4}
    with pytest.raises(ValueError, match="unknown ranking"):
        rank_order(x, keys, "random")
    assert diversity_scores(x[:1]).tolist() == [0.0]
    with pytest.raises(ValueError):
        k_center(x, 3, first=99)


def test_equal_scores_follow_the_keys() -> None:
    """Two mirror-image vectors score the same up to float bits: the tie-break keys order them."""
    m = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    vectors = np.array([[1, 0, 0], [0, 1, 0], m, [0, 0, 1]], np.float32)
    for keys in (["a", "b", "c", "d"], ["b", "a", "c", "d"]):
        order, _ = rank_order(vectors, keys, "score", k=2)
        first, second = (0, 1) if keys[0] < keys[1] else (1, 0)
        assert order.index(first) < order.index(second)


def test_scores_are_float64_means_the_same_bits_for_any_backend_and_thread_count() -> None:
    """Each score is the mean of the k smallest exact distances (fsum reference) rounded to float32, whatever
    computed the kNN; exact copies tie exactly, so self may sit behind them."""
    import math

    import faiss

    rng = np.random.default_rng(4)
    x = l2_normalize(rng.standard_normal((300, 48)) + np.repeat(rng.standard_normal((30, 48)), 10, axis=0))
    x[1:4] = x[0]  # exact copies
    ref = diversity_scores(x, k=5, backend="numpy")
    before = faiss.omp_get_max_threads()
    try:
        for threads in (1, 2):
            faiss.omp_set_num_threads(threads)
            assert np.array_equal(diversity_scores(x, k=5, backend="flat"), ref)
    finally:
        faiss.omp_set_num_threads(before)
    for row in (0, 2, 150):
        dots = [math.fsum(float(a) * float(b) for a, b in zip(x[row], x[j])) for j in range(len(x)) if j != row]
        nearest = sorted(math.sqrt(max(2 - 2 * s, 0.0)) for s in dots)[:5]
        assert abs(float(ref[row]) - math.fsum(nearest) / 5) <= np.spacing(ref[row])

"""Diversity ranking of kept images by their embeddings (unit vectors, Euclidean distance).

- :func:`diversity_scores`: the mean distance to the ``k`` nearest other vectors ("relative distance to the
  other samples" of the FiIW curation); a higher score = a more unusual image. The neighbours and their
  distances are float64 (:func:`curate.search.exact_knn`), so a score has the same bits on any CPU.
- :func:`k_center`: farthest-point selection (Gonzalez 1985): each pick maximises its distance to those already
  picked, a 2-approximation of the best covering of the set by ``n`` images.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from curate.search import build_index, exact_knn, grid_cells

RANK_METHODS: tuple[str, ...] = ("score", "kcenter")


def diversity_scores(vectors: NDArray[np.float32], k: int = 10, backend: str = "auto") -> NDArray[np.float32]:
    """(N,) float32 mean Euclidean distance of each unit vector (N, D) to its ``k`` nearest others (fewer if
    N <= k, or where an approximate backend finds fewer), from float64 distances summed in a fixed order."""
    n = len(vectors)
    if n < 2:
        return np.zeros(n, np.float32)
    k_eff = min(k, n - 1)
    dist, idx = exact_knn(build_index(vectors, backend), vectors, k_eff + 1)
    # drop self (normally column 0; behind equally near copies it may sit elsewhere, or past the k + 1)
    keep = idx != np.arange(n)[:, None]
    keep[keep.all(axis=1), -1] = False
    dist = dist[keep].reshape(n, k_eff)
    found = np.isfinite(dist)
    total = np.zeros(n)
    for c in range(k_eff):  # ascending distances, summed left to right
        total += np.where(found[:, c], dist[:, c], 0.0)
    return (total / np.maximum(found.sum(axis=1), 1)).astype(np.float32)


def k_center(vectors: NDArray[np.float32], n: int, first: int) -> list[int]:
    """``n`` row indices chosen farthest-point first (distances compared on the
    :data:`curate.search.DISTANCE_GRID`), starting at row ``first``; ties -> lowest index.

    Memory O(N); time O(n N D)."""
    total = len(vectors)
    if not 0 <= first < total:
        raise ValueError(f"first index {first} outside 0..{total - 1}")
    picked = [first]
    nearest = np.linalg.norm(vectors - vectors[first], axis=1)
    for _ in range(min(n, total) - 1):
        nxt = int(np.argmax(grid_cells(nearest)))
        picked.append(nxt)
        nearest = np.minimum(nearest, np.linalg.norm(vectors - vectors[nxt], axis=1))
        nearest[picked] = -1.0
    return picked


def rank_order(
    vectors: NDArray[np.float32],
    keys: list[str],
    method: str = "score",
    k: int = 10,
    backend: str = "auto",
    top: int | None = None,
) -> tuple[list[int], NDArray[np.float32]]:
    """Row indices best first, and the (N,) diversity scores. Scores are compared on the
    :data:`curate.search.DISTANCE_GRID`; ``keys`` (e.g. content hashes) break ties.

    ``score``: descending score (all rows). ``kcenter``: the ``top`` (default all) rows in farthest-point
    order from the top-scored row, then the rest by score."""
    if method not in RANK_METHODS:
        raise ValueError(f"unknown ranking method {method!r}; choose one of {', '.join(RANK_METHODS)}")
    scores = diversity_scores(vectors, k, backend)
    cells = grid_cells(scores)
    by_score = sorted(range(len(vectors)), key=lambda i: (-int(cells[i]), keys[i]))
    if method == "score" or not by_score:
        return by_score, scores
    picked = k_center(vectors, len(vectors) if top is None else top, by_score[0])
    chosen = set(picked)
    return picked + [i for i in by_score if i not in chosen], scores

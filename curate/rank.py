"""Diversity ranking of kept images by their embeddings (unit vectors, Euclidean distance).

- :func:`diversity_scores`: the mean distance to the ``k`` nearest other vectors ("relative distance to the
  other samples" of the FiIW curation); a higher score = a more unusual image.
- :func:`k_center`: farthest-point selection (Gonzalez 1985): each pick maximises its distance to those already
  picked, a 2-approximation of the best covering of the set by ``n`` images.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from curate.search import build_index, grid_cells

RANK_METHODS: tuple[str, ...] = ("score", "kcenter")


def diversity_scores(vectors: NDArray[np.float32], k: int = 10, backend: str = "auto") -> NDArray[np.float32]:
    """(N,) mean Euclidean distance of each unit vector (N, D) to its ``k`` nearest others (fewer if N <= k)."""
    n = len(vectors)
    if n < 2:
        return np.zeros(n, np.float32)
    k_eff = min(k, n - 1)
    dist, idx = build_index(vectors, backend).knn(vectors, k_eff + 1)
    others = idx != np.arange(n)[:, None]
    # drop self (normally column 0; with exact duplicates it may sit elsewhere)
    dist = np.where(others, dist, np.nan)
    dist = np.where(np.isfinite(dist), dist, np.nan)
    return np.nan_to_num(np.nanmean(np.sort(dist, axis=1)[:, :k_eff], axis=1)).astype(np.float32)


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

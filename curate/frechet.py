"""Fréchet distance between two sets of embeddings, and its interval over equal-size random subsets.

The Fréchet (2-Wasserstein) distance between the Gaussians fitted to two sets of row vectors X (n1, D) and
Y (n2, D) is ``|mu_x - mu_y|^2 + Tr(S_x) + Tr(S_y) - 2 Tr((S_x S_y)^(1/2))`` (the FID formula). With
``S_x = A^T A`` and ``S_y = B^T B`` for centred, scaled rows A = (X - mu_x) / sqrt(n1 - 1) (same for B),
``Tr((S_x S_y)^(1/2))`` is the nuclear norm of ``A B^T`` (n1, n2): no matrix square root, exact, and cheap
when the sets are smaller than the dimension (as 200 images of 1,280-d Lite0 embeddings are).

The estimate is biased upwards by O(D / n): compare distances only at equal set sizes. :func:`gap_interval`
does so, measuring a synthetic set against one random half of the real set and the other half against the
same half (the real-vs-real floor), with the same number of images on every side.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: Random equal-size draws of a gap interval (``synth gap``'s and an experiment report's default).
DRAWS = 200


def _factor(x: NDArray[np.floating]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(mean (D,), factor F with F^T F = covariance): F is (n, D), or (D, D) when n > D."""
    x = np.asarray(x, np.float64)
    if len(x) < 2:
        raise ValueError(f"a Fréchet distance needs at least 2 vectors per set, got {len(x)}")
    mu = x.mean(0)
    f = (x - mu) / np.sqrt(len(x) - 1)
    if len(f) > f.shape[1]:
        w, v = np.linalg.eigh(f.T @ f)
        f = np.sqrt(np.clip(w, 0, None))[:, None] * v.T
    return mu, f


def frechet_distance(x: NDArray[np.floating], y: NDArray[np.floating]) -> float:
    """Fréchet distance between the Gaussians fitted to rows of ``x`` (n1, D) and ``y`` (n2, D); >= 0."""
    if x.ndim != 2 or y.ndim != 2 or x.shape[1] != y.shape[1]:
        raise ValueError(f"two (n, D) sets of the same D expected, got {x.shape} and {y.shape}")
    mu_x, a = _factor(x)
    mu_y, b = _factor(y)
    cross = np.linalg.svd(a @ b.T, compute_uv=False).sum()
    d = float(np.sum((mu_x - mu_y) ** 2) + np.sum(a * a) + np.sum(b * b) - 2 * cross)
    return max(d, 0.0)


@dataclass(frozen=True)
class Interval:
    """Median and 2.5–97.5 % range of a statistic over random draws."""

    median: float
    low: float
    high: float

    def __str__(self) -> str:
        return f"{self.median:.3f} [{self.low:.3f}, {self.high:.3f}]"


@dataclass(frozen=True)
class Gap:
    """Fréchet distances at ``size`` images per side over ``draws`` random draws: ``synthetic`` = a synthetic
    subset vs half of the real set, ``floor`` = the other real half vs the same half, ``ratio`` = their
    quotient per draw (1 = as close to the real set as the real set is to itself)."""

    synthetic: Interval
    floor: Interval
    ratio: Interval
    size: int
    draws: int


def _interval(values: NDArray[np.float64]) -> Interval:
    low, median, high = np.percentile(values, [2.5, 50, 97.5])
    return Interval(float(median), float(low), float(high))


def gap_interval(
    synthetic: NDArray[np.floating],
    real: NDArray[np.floating],
    rng: np.random.Generator,
    draws: int = DRAWS,
    size: int | None = None,
) -> Gap:
    """The embedding gap of ``synthetic`` (n_s, D) to ``real`` (n_r, D) and the real-vs-real floor.

    Each draw splits the real rows into two disjoint random halves of ``size`` rows (default
    min(n_s, n_r // 2)) and draws ``size`` synthetic rows without replacement."""
    size = size or min(len(synthetic), len(real) // 2)
    if size < 2 or size > len(synthetic) or 2 * size > len(real):
        raise ValueError(
            f"need 2 <= size <= synthetic images ({len(synthetic)}) and 2 x size <= real images ({len(real)}), "
            f"got size {size}"
        )
    if draws < 1:
        raise ValueError(f"draws must be >= 1, got {draws}")
    syn, floor = np.empty(draws), np.empty(draws)
    for i in range(draws):
        order = rng.permutation(len(real))
        half, other = real[order[:size]], real[order[size : 2 * size]]
        syn[i] = frechet_distance(synthetic[rng.choice(len(synthetic), size, replace=False)], half)
        floor[i] = frechet_distance(other, half)
    ratio = syn / np.maximum(floor, 1e-12)
    return Gap(_interval(syn), _interval(floor), _interval(ratio), size, draws)

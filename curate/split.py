"""Seeded, group-aware splits: images that are near duplicates of each other always land in the same split.

Sizes are counts (``{train: 1000, valid: 200, test: 200}``) or fractions summing to 1
(``{train: 0.8, valid: 0.1, test: 0.1}``). Groups are placed largest first (random order among equal sizes),
each into the split furthest below its target, so counts are met exactly when groups are singletons and as
closely as whole groups allow otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from curate.dedup import UnionFind
from curate.search import duplicate_pairs


def resolve_sizes(sizes: Mapping[str, float], n: int) -> dict[str, int]:
    """Split name -> image count for ``n`` images. Fractions (all <= 1, summing to 1) use largest remainders;
    counts must be whole numbers summing to at most ``n``."""
    if not sizes or any(v < 0 for v in sizes.values()):
        raise ValueError(f"split sizes must be a non-empty mapping of non-negative numbers, got {dict(sizes)}")
    values = list(sizes.values())
    if all(v <= 1 for v in values) and math.isclose(sum(values), 1.0, abs_tol=1e-6):
        raw = [v * n for v in values]
        counts = [math.floor(r) for r in raw]
        by_remainder = sorted(range(len(raw)), key=lambda i: (-(raw[i] - counts[i]), i))
        for i in by_remainder[: n - sum(counts)]:
            counts[i] += 1
        return dict(zip(sizes, counts))
    if any(v != int(v) for v in values):
        raise ValueError(f"split sizes {dict(sizes)} are neither fractions summing to 1 nor whole counts")
    if sum(values) > n:
        raise ValueError(f"split counts {dict(sizes)} need {int(sum(values))} images, only {n} available")
    return {k: int(v) for k, v in sizes.items()}


def near_groups(
    vectors: NDArray[np.float32], threshold: float, backend: str = "auto", crops: NDArray[np.float32] | None = None
) -> list[list[int]]:
    """Connected components of the rows of unit ``vectors`` (N, D) (with centre views ``crops``) closer than
    ``threshold`` (:func:`curate.search.duplicate_pairs`: float64 distances decide); singletons included."""
    uf = UnionFind(len(vectors))
    if len(vectors) > 1 and threshold > 0:
        pairs = duplicate_pairs(vectors, crops, threshold, backend)
        for a, b in zip(pairs.i.tolist(), pairs.j.tolist()):
            uf.union(a, b)
    return uf.components()


def split_groups(
    groups: Sequence[Sequence[int]], counts: Mapping[str, int], rng: np.random.Generator
) -> dict[int, str]:
    """Item -> split name; every group goes whole into one split. Items beyond the total count are left out
    (smallest groups last, so what is left out is decided by the seed among equal sizes)."""
    canonical = sorted((sorted(g) for g in groups if g), key=lambda g: g[0])
    perm = rng.permutation(len(canonical))
    order = sorted(range(len(canonical)), key=lambda k: (-len(canonical[perm[k]]), k))
    filled = dict.fromkeys(counts, 0)
    assignment: dict[int, str] = {}
    for k in order:
        group = canonical[perm[k]]
        name = max(counts, key=lambda s: counts[s] - filled[s])  # first split wins ties
        if counts[name] - filled[name] <= 0:
            continue
        filled[name] += len(group)
        assignment.update(dict.fromkeys(group, name))
    return assignment


def straddling_groups(groups: Sequence[Sequence[int]], assignment: Mapping[int, str]) -> list[list[int]]:
    """Groups whose assigned members sit in more than one split (should be none)."""
    return [list(g) for g in groups if len({assignment[i] for i in g if i in assignment}) > 1]

"""Group-aware splits: exact counts, fractions, seeded, and no group ever straddles two splits."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from curate.embed import l2_normalize
from curate.split import near_groups, resolve_sizes, split_groups, straddling_groups


def _groups(seed: int) -> list[list[int]]:
    """Random partition of 0..199 into groups of size 1..6."""
    rng = np.random.default_rng(seed)
    items = rng.permutation(200).tolist()
    groups, i = [], 0
    while i < len(items):
        size = int(rng.integers(1, 7))
        groups.append(items[i : i + size])
        i += size
    return groups


@pytest.mark.parametrize("seed", range(5))
def test_no_group_straddles_and_counts_are_close(seed: int) -> None:
    groups = _groups(seed)
    counts = {"train": 140, "valid": 30, "test": 30}
    assignment = split_groups(groups, counts, np.random.default_rng(seed))
    assert straddling_groups(groups, assignment) == []
    got = Counter(assignment.values())
    assert sum(got.values()) == 200
    assert all(abs(got[k] - v) <= 6 for k, v in counts.items())


def test_singletons_give_exact_counts_and_seed_decides() -> None:
    groups = [[i] for i in range(100)]
    a = split_groups(groups, {"train": 70, "valid": 20, "test": 10}, np.random.default_rng(1))
    assert Counter(a.values()) == {"train": 70, "valid": 20, "test": 10}
    b = split_groups(groups, {"train": 70, "valid": 20, "test": 10}, np.random.default_rng(1))
    c = split_groups(groups, {"train": 70, "valid": 20, "test": 10}, np.random.default_rng(2))
    assert a == b and a != c


def test_group_order_does_not_matter() -> None:
    groups = _groups(7)
    shuffled = [list(reversed(g)) for g in reversed(groups)]
    counts = {"train": 150, "test": 50}
    assert split_groups(groups, counts, np.random.default_rng(0)) == split_groups(
        shuffled, counts, np.random.default_rng(0)
    )


def test_counts_below_total_leave_items_out() -> None:
    a = split_groups([[i] for i in range(10)], {"train": 3, "test": 2}, np.random.default_rng(0))
    assert Counter(a.values()) == {"train": 3, "test": 2}


def test_resolve_sizes() -> None:
    assert resolve_sizes({"train": 0.8, "valid": 0.1, "test": 0.1}, 1001) == {"train": 801, "valid": 100, "test": 100}
    assert resolve_sizes({"train": 1000, "valid": 200, "test": 200}, 1400) == {"train": 1000, "valid": 200, "test": 200}
    with pytest.raises(ValueError, match="only 10"):
        resolve_sizes({"train": 10, "test": 5}, 10)
    with pytest.raises(ValueError, match="neither"):
        resolve_sizes({"train": 0.5, "test": 2.5}, 10)
    with pytest.raises(ValueError):
        resolve_sizes({}, 10)


def test_near_groups_join_close_vectors() -> None:
    rng = np.random.default_rng(0)
    base = rng.standard_normal((6, 64))
    x = l2_normalize(np.concatenate([base, base[:2] + 0.05 * rng.standard_normal((2, 64))]))
    assert near_groups(x, 0.3) == [[0, 6], [1, 7], [2], [3], [4], [5]]
    assert near_groups(x, 0.0) == [[i] for i in range(8)]

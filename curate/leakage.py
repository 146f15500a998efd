"""Leakage between two image sets (e.g. train vs test): exact copies and near duplicates across the sets.

Exact = equal file bytes or equal decoded pixels (distance 0); near = unit embeddings closer than the
threshold in the two-view distance of :func:`curate.search.duplicate_pairs` (whole vs whole, centre view vs
whole, both ways). Searches indexes in batches (never an |A| x |B| matrix) for candidates; each candidate's
distance is computed in float64 (:func:`curate.search.two_view_distances`) and decides, the same bits on any
CPU or thread count.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from curate.scan import ScanResult
from curate.search import build_index, search_radius, two_view_distances


@dataclass(frozen=True)
class Leak:
    a: str  # path in set A
    b: str  # path in set B
    kind: Literal["exact", "near"]
    distance: float


def find_leaks(a: ScanResult, b: ScanResult, threshold: float, backend: str = "auto") -> list[Leak]:
    """Every (A, B) pair of duplicates, sorted by (distance, a, b); one entry per pair."""
    leaks: dict[tuple[str, str], Leak] = {}
    for attr in ("sha256", "pixel_hash"):
        in_b: dict[str, list[str]] = {}
        for im in b.images:
            in_b.setdefault(getattr(im.facts, attr), []).append(im.path)
        for im in a.images:
            for other in in_b.get(getattr(im.facts, attr), []):
                leaks.setdefault((im.path, other), Leak(im.path, other, "exact", 0.0))
    if a.images and b.images and threshold > 0:
        ia, ib, dist = _near(a, b, threshold, backend)
        for i, j, d in zip(ia.tolist(), ib.tolist(), dist.tolist()):
            key = (a.images[i].path, b.images[j].path)
            leaks.setdefault(key, Leak(*key, "near", d))
    return sorted(leaks.values(), key=lambda x: (x.distance, x.a, x.b))


def _near(a: ScanResult, b: ScanResult, threshold: float, backend: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows of A (E,) and of B (E,) int64 whose float64 two-view distance (E,) is below ``threshold``; candidates
    from the float32 search within :func:`curate.search.search_radius` (A's whole and centre views against B's
    whole views, B's centre views against A's whole views)."""
    wide = search_radius(threshold, a.vectors.shape[1])
    index_b, index_a = build_index(b.vectors, backend), build_index(a.vectors, backend)
    whole_a, whole_b, _ = index_b.within(a.vectors, wide)
    crop_a, of_b, _ = index_b.within(a.crops, wide)
    crop_b, of_a, _ = index_a.within(b.crops, wide)
    key = np.unique(np.concatenate([whole_a, crop_a, of_a]) * len(b.images) + np.concatenate([whole_b, of_b, crop_b]))
    ia, ib = key // len(b.images), key % len(b.images)
    dist = two_view_distances(a.vectors, a.crops, b.vectors, b.crops, ia, ib)
    keep = dist < threshold
    return ia[keep], ib[keep], dist[keep]


def leak_summary(a: ScanResult, b: ScanResult, leaks: list[Leak]) -> dict[str, int]:
    return {
        "images_a": len(a.images),
        "images_b": len(b.images),
        "pairs": len(leaks),
        "exact_pairs": sum(x.kind == "exact" for x in leaks),
        "a_with_leak": len({x.a for x in leaks}),
        "b_with_leak": len({x.b for x in leaks}),
    }

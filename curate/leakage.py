"""Leakage between two image sets (e.g. train vs test): exact copies and near duplicates across the sets.

Exact = equal file bytes or equal decoded pixels (distance 0); near = unit embeddings closer than the
threshold in the two-view distance of :func:`curate.search.duplicate_pairs` (whole vs whole, centre view vs
whole, both ways). Searches indexes in batches (never an |A| x |B| matrix).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from curate.scan import ScanResult
from curate.search import build_index


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
        near: dict[tuple[int, int], float] = {}
        index_b, index_a = build_index(b.vectors, backend), build_index(a.vectors, backend)
        for queries, index, a_asks in ((a.vectors, index_b, True), (a.crops, index_b, True), (b.crops, index_a, False)):
            qi, ti, dist = index.within(queries, threshold)
            for q, t, d in zip(qi.tolist(), ti.tolist(), dist.tolist()):
                key = (q, t) if a_asks else (t, q)
                near[key] = min(d, near.get(key, d))
        for (ia, ib), d in near.items():
            key = (a.images[ia].path, b.images[ib].path)
            leaks.setdefault(key, Leak(*key, "near", float(d)))
    return sorted(leaks.values(), key=lambda x: (x.distance, x.a, x.b))


def leak_summary(a: ScanResult, b: ScanResult, leaks: list[Leak]) -> dict[str, int]:
    return {
        "images_a": len(a.images),
        "images_b": len(b.images),
        "pairs": len(leaks),
        "exact_pairs": sum(x.kind == "exact" for x in leaks),
        "a_with_leak": len({x.a for x in leaks}),
        "b_with_leak": len({x.b for x in leaks}),
    }

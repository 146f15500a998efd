"""Exact and near duplicates among scanned images, with a documented keeper policy.

- **Exact**: equal file bytes (sha256), then equal decoded pixels (same picture re-encoded losslessly or with
  other metadata). Distance 0.
- **Near**: two-view distance of L2-normalised embeddings below ``threshold`` (whole image vs whole image,
  or vs the other's centre view; :func:`curate.search.duplicate_pairs`), found by range search, never an
  N x N matrix.

**Keeper policy.** Images are ranked by: protected first (under a ``--protect`` folder), then largest
resolution (width x height), then sharpness (variance of the Laplacian), then file size, then content (sha256),
then path (A..Z). Walking that order, an image is *kept* unless a duplicate of it was already kept; a removed image names the
nearest kept duplicate (``duplicate_of``). Hence no two kept images are duplicates, every removed image is a
true duplicate of a kept one (no chaining through intermediate frames), and protected images are never removed.

**Groups** are the connected components of the duplicate pairs (union-find), reported keeper first. Results do
not depend on input order: vectors are indexed in (sha256, path) order and all choices follow the total order
above. Nor on the machine, for the same embeddings: every pair's distance is computed in float64 from the
embeddings (:func:`curate.search.exact_pairs`), so the threshold decides the same on any CPU, thread count or
executor. Nor on the last bits of the embeddings where they need not: a removed image names the kept duplicate
in the nearest :data:`curate.search.DISTANCE_GRID` cell (keeper order among equals), sharpness is compared to
10 significant digits and ties go to content, not path. Embeddings that differ (another onnxruntime build or
kernel) can still move a distance across the threshold (any threshold has an edge); docs/findings.md ("Is the
curated set the same on every machine?") measures how far the shared data's decisions are from it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from curate.partition import AUTO_PARTITION_MIN, PARTITION, partitioned_pairs
from curate.scan import ScannedImage
from curate.search import Pairs, duplicate_pairs, grid_cells
from ground.run.cluster import Cluster

#: Default near-duplicate radius on unit EfficientNet-Lite0 embeddings (see ``experiments/dedup_quality.py``).
DEFAULT_THRESHOLD = 0.45


@dataclass(frozen=True)
class Removal:
    index: int  # into the images list
    duplicate_of: int  # index of the kept image it duplicates
    kind: Literal["exact", "near"]
    distance: float


@dataclass
class DedupResult:
    """``kept``: image indices (ascending); ``removed``: one :class:`Removal` each; ``groups``: lists of image
    indices (keeper first, then in keeper order), groups ordered by their keeper's path."""

    kept: list[int]
    removed: list[Removal]
    groups: list[list[int]] = field(default_factory=list)
    pairs: Pairs | None = None  # near pairs among exact-unique images (indices into images)


def keeper_order(images: Sequence[ScannedImage], protected: Sequence[bool]) -> list[int]:
    """Indices of ``images`` in keeper-policy order (best keeper first)."""

    def key(i: int) -> tuple:
        f = images[i].facts
        return (
            not protected[i],
            -f.width * f.height,
            -significant(f.sharpness, 10),
            -f.bytes,
            f.sha256,
            images[i].path,
        )

    return sorted(range(len(images)), key=key)


def significant(value: float, digits: int) -> float:
    """``value`` rounded to ``digits`` significant digits (0 stays 0)."""
    return float(f"{value:.{digits - 1}e}")


def is_protected(images: Sequence[ScannedImage], folders: Sequence[Path | str]) -> list[bool]:
    roots = [Path(f).resolve() for f in folders]
    return [any(Path(im.path).is_relative_to(r) for r in roots) for im in images]


def exact_duplicates(images: Sequence[ScannedImage], protected: Sequence[bool]) -> list[Removal]:
    """Removals of byte-identical, then pixel-identical, copies (the best keeper of each set stays)."""
    removed: list[Removal] = []
    gone: set[int] = set()
    for attr in ("sha256", "pixel_hash"):
        first: dict[str, int] = {}
        for i in keeper_order(images, protected):
            if i in gone:
                continue
            value = getattr(images[i].facts, attr)
            if value in first and not protected[i]:
                removed.append(Removal(i, first[value], "exact", 0.0))
                gone.add(i)
            else:
                first.setdefault(value, i)
    return removed


def near_pairs(
    images: Sequence[ScannedImage],
    vectors: NDArray[np.float32],
    candidates: Sequence[int],
    threshold: float,
    backend: str,
    crops: NDArray[np.float32] | None = None,
    cluster: Cluster | None = None,
) -> Pairs:
    """Pairs (indices into ``images``) of ``candidates`` closer than ``threshold`` (unit ``vectors`` (N, D) and
    centre views ``crops`` (N, D)), with float64 distances decided as :func:`curate.search.exact_pairs` decides;
    indexed in (sha256, path) order so the result ignores input order. Backend
    ``partition`` (``auto`` above :data:`AUTO_PARTITION_MIN` candidates) searches by partitions
    (:mod:`curate.partition`), on ``cluster`` when given."""
    order = sorted(candidates, key=lambda i: (images[i].facts.sha256, images[i].path))
    if len(order) < 2:
        return Pairs(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.float64))
    views = vectors[order], None if crops is None else crops[order]
    if backend == PARTITION or (backend == "auto" and len(order) > AUTO_PARTITION_MIN):
        local = partitioned_pairs(*views, threshold, cluster)
    else:
        local = duplicate_pairs(*views, threshold, backend)
    ids = np.asarray(order, np.int64)
    i, j = ids[local.i], ids[local.j]
    return Pairs(np.minimum(i, j), np.maximum(i, j), local.dist)


def greedy_keep(
    n: int, pairs: Pairs, order: Sequence[int], allowed: Sequence[bool], protected: Sequence[bool]
) -> list[Removal]:
    """Walk ``order``; remove an allowed, unprotected image when a kept neighbour exists (the nearest named:
    smallest :func:`curate.search.grid_cells` distance, then earliest in ``order``)."""
    ptr, nbr, dist = _adjacency(n, pairs)
    cells = grid_cells(dist)
    rank = np.empty(n, np.int64)
    rank[np.asarray(order, np.int64)] = np.arange(len(order))
    kept = np.zeros(n, bool)
    removed = []
    for i in order:
        if not allowed[i]:
            continue
        lo, hi = ptr[i], ptr[i + 1]
        hit = np.flatnonzero(kept[nbr[lo:hi]]) + lo
        if len(hit) and not protected[i]:
            k = hit[np.lexsort((rank[nbr[hit]], cells[hit]))[0]]
            removed.append(Removal(i, int(nbr[k]), "near", float(dist[k])))
        else:
            kept[i] = True
    return removed


def find_duplicates(
    images: Sequence[ScannedImage],
    vectors: NDArray[np.float32] | None,
    threshold: float = DEFAULT_THRESHOLD,
    backend: str = "auto",
    protect: Sequence[Path | str] = (),
    near: bool = True,
    crops: NDArray[np.float32] | None = None,
    cluster: Cluster | None = None,
) -> DedupResult:
    """Exact then (with ``vectors`` (N, D) unit rows, optional centre views ``crops`` (N, D), and ``near``) near
    duplicates; see the module docstring. ``cluster``: where a partitioned search runs (:func:`near_pairs`)."""
    if threshold < 0 or threshold > 2:
        raise ValueError(f"threshold is a Euclidean distance between unit vectors, 0..2; got {threshold}")
    protected = is_protected(images, protect)
    removed = exact_duplicates(images, protected)
    gone = {r.index for r in removed}
    survivors = [i for i in range(len(images)) if i not in gone]
    pairs = None
    if near and vectors is not None:
        assert len(vectors) == len(images), "one vector per image"
        pairs = near_pairs(images, vectors, survivors, threshold, backend, crops, cluster)
        allowed = [i not in gone for i in range(len(images))]
        removed += greedy_keep(len(images), pairs, keeper_order(images, protected), allowed, protected)
    gone = {r.index for r in removed}
    kept = [i for i in range(len(images)) if i not in gone]
    groups = duplicate_groups(images, removed, pairs, protected)
    return DedupResult(kept, sorted(removed, key=lambda r: images[r.index].path), groups, pairs)


def duplicate_groups(
    images: Sequence[ScannedImage], removed: Sequence[Removal], pairs: Pairs | None, protected: Sequence[bool]
) -> list[list[int]]:
    """Connected components (size >= 2) of exact links and near pairs, keeper order inside each."""
    uf = UnionFind(len(images))
    for r in removed:
        uf.union(r.index, r.duplicate_of)
    if pairs is not None:
        for a, b in zip(pairs.i.tolist(), pairs.j.tolist()):
            uf.union(a, b)
    rank = {i: k for k, i in enumerate(keeper_order(images, protected))}
    groups = [sorted(g, key=rank.__getitem__) for g in uf.components() if len(g) > 1]
    return sorted(groups, key=lambda g: images[g[0]].path)


class UnionFind:
    """Disjoint sets over 0..n-1 with path halving and union by size."""

    def __init__(self, n: int) -> None:
        self.parent = list(range(n))
        self.size = [1] * n

    def find(self, a: int) -> int:
        parent = self.parent
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    def union(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra == rb:
            return
        if self.size[ra] < self.size[rb]:
            ra, rb = rb, ra
        self.parent[rb] = ra
        self.size[ra] += self.size[rb]

    def components(self) -> list[list[int]]:
        """Every set as an ascending list, sets ordered by their smallest member."""
        sets: dict[int, list[int]] = {}
        for a in range(len(self.parent)):
            sets.setdefault(self.find(a), []).append(a)
        return sorted(sets.values(), key=lambda s: s[0])


def _adjacency(n: int, pairs: Pairs) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """CSR adjacency of the undirected pairs: neighbours of i are ``nbr[ptr[i]:ptr[i+1]]``."""
    src = np.concatenate([pairs.i, pairs.j])
    dst = np.concatenate([pairs.j, pairs.i])
    dist = np.concatenate([pairs.dist, pairs.dist])
    order = np.argsort(src, kind="stable")
    ptr = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=ptr[1:])
    return ptr, dst[order], dist[order]

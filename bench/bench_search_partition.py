"""Partitioned near-duplicate search (:mod:`curate.partition`, the ``partition`` backend) on N planted unit
256-d vectors (``bench_search_1m.planted``: random vectors, 5 % noisy copies): time, recall against exact brute
force on the pairs of 2,000 planted copies, and the driver's peak memory, measured at N and modelled at 10 M.

The driver holds the vectors (N x D float32), their probes (N x nprobe int64, twice: the cells and their order)
and the pairs; a task holds its own cells only. ``--ray W`` runs the tasks on a local Ray with W CPUs (its
workers' memory is not the driver's).

.venv/bin/python bench/bench_search_partition.py [N] [--ray W]   # targets at 1M: recall >= 0.99, memory O(N d)
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
import tracemalloc

import numpy as np
from bench_search_1m import COPIES, DIM, RADIUS, planted

from curate.embed import l2_normalize
from curate.partition import CELL_VECTORS, NPROBE, partitioned_pairs
from curate.search import build_index


def driver_bytes(n: int, dim: int, nprobe: int = NPROBE) -> int:
    """The driver's arrays for N vectors: vectors (N D float32), probes and their sort (2 N nprobe int64), homes
    and their order (2 N int64), and planted-rate pairs (5 % of N, 20 bytes each)."""
    return n * dim * 4 + 2 * n * nprobe * 8 + 2 * n * 8 + int(0.05 * n) * 20


def planted_dim(n: int, dim: int, rng: np.random.Generator) -> np.ndarray:
    """:func:`bench_search_1m.planted` in ``dim`` dimensions, the copies' noise scaled to keep their distances."""
    k = int(n * COPIES)
    x = rng.standard_normal((n, dim), dtype=np.float32)
    src = rng.integers(0, n - k, k)
    noise = rng.uniform(0.1, 0.3, (k, 1)).astype(np.float32) * rng.standard_normal((k, dim), dtype=np.float32)
    x[n - k :] = x[src] + noise
    return l2_normalize(x)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", nargs="?", type=float, default=200_000)
    parser.add_argument("--ray", type=int, default=0, help="run the tasks on a local Ray with this many CPUs")
    parser.add_argument(
        "--dim",
        type=int,
        default=DIM,
        help=f"vector dimension (default {DIM}); a small one simulates a large N: what the search allocates beyond "
        "the vectors depends on N, not on the dimension",
    )
    args = parser.parse_args()
    n = int(args.n)
    rng = np.random.default_rng(0)
    x = planted(n, rng) if args.dim == DIM else planted_dim(n, args.dim, rng)
    base_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    cluster = None
    if args.ray:
        from ground.run.cluster import Cluster

        cluster = Cluster(local_cpus=args.ray)
    tracemalloc.start()  # numpy's allocations: what the search adds to the driver beyond the vectors
    start = time.perf_counter()
    pairs = partitioned_pairs(x, None, RADIUS, cluster)
    total_s = time.perf_counter() - start
    search_peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    if cluster is not None:
        cluster.close()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    copies = int(n * COPIES)  # the planted copies are the last rows: each has its source within reach
    queries = np.sort(n - copies + rng.choice(copies, size=min(copies, 2000), replace=False))
    qi, bi, _ = build_index(x, "numpy").within(x[queries], RADIUS)  # exact, without a second copy of x
    exact = {(min(int(queries[q]), int(b)), max(int(queries[q]), int(b))) for q, b in zip(qi, bi) if queries[q] != b}
    found = set(zip(pairs.i.tolist(), pairs.j.tolist()))
    recall = len(exact & found) / max(1, len(exact))

    where = f"ray{args.ray}" if args.ray else "local"
    print(
        f"search_partition_n: {n} vectors x {args.dim} d, {max(1, n // CELL_VECTORS)} cells, nprobe {NPROBE}, {where}"
    )
    print(f"search_partition_total_seconds: {total_s:.1f} s")
    print(f"search_partition_pairs: {len(pairs)} pairs within {RADIUS}")
    print(
        f"search_partition_recall: {recall:.4f} vs exact, pairs of {len(queries)} planted copies ({len(exact)} pairs; target >= 0.99)"
    )
    print(f"search_partition_driver_peak_rss: {rss:.0f} MB (vectors alone {x.nbytes / 2**20:.0f} MB; the planted data "
          f"made {base_rss:.0f} MB before the search)")  # fmt: skip
    print(f"search_partition_driver_search_peak: {search_peak:.0f} MB allocated by the search beyond the vectors")
    print(
        f"search_partition_driver_model: {driver_bytes(n, args.dim) / 2**20:.0f} MB at {n} vectors (arrays the driver holds)"
    )
    print(f"search_partition_driver_model_10m: {driver_bytes(10_000_000, DIM) / 2**30:.1f} GB at 10M x {DIM} d, "
          f"{driver_bytes(10_000_000, 320) / 2**30:.1f} GB at 10M x 320 d (Lite0, whole views)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())

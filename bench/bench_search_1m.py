"""Near-duplicate search on N random unit 256-d vectors (default 200,000; pass 1e6 for the million-vector figure) with planted near copies:
the IVF backend's self range search (all pairs closer than the radius), its time, peak RSS and recall against
exact brute force (numpy) on a seeded sample of queries.

.venv/bin/python bench/bench_search_1m.py [N] [BACKEND]   # targets: <= 600 s, recall >= 0.95, memory O(N d)
"""

from __future__ import annotations

import resource
import sys
import time

import numpy as np

from curate.embed import l2_normalize
from curate.search import build_index, self_pairs

DIM = 256
RADIUS = 0.45
COPIES = 0.05  # share of vectors that are noisy copies of others (distance ~0.2-0.4)


def planted(n: int, rng: np.random.Generator) -> np.ndarray:
    """(n, DIM) float32 unit vectors; the last COPIES*n rows are near copies of random earlier rows."""
    k = int(n * COPIES)
    x = rng.standard_normal((n, DIM), dtype=np.float32)
    src = rng.integers(0, n - k, k)
    x[n - k :] = x[src] + rng.uniform(0.1, 0.3, (k, 1)).astype(np.float32) * rng.standard_normal(
        (k, DIM), dtype=np.float32
    )
    return l2_normalize(x)


def main() -> int:
    n = int(float(sys.argv[1])) if len(sys.argv) > 1 else 200_000  # 1e6: the full-size figure (~2.5 min)
    backend = sys.argv[2] if len(sys.argv) > 2 else "ivf"
    rng = np.random.default_rng(0)
    x = planted(n, rng)
    start = time.perf_counter()
    index = build_index(x, backend)
    build_s = time.perf_counter() - start
    pairs = self_pairs(index, RADIUS)
    total_s = time.perf_counter() - start
    queries = np.sort(rng.choice(n, size=min(n, 2000), replace=False))
    qi, bi, _ = build_index(x, "numpy").within(x[queries], RADIUS)  # exact, without a second copy of x
    exact = {(int(queries[q]), int(b)) for q, b in zip(qi, bi) if queries[q] != b}
    exact = {(min(a, b), max(a, b)) for a, b in exact}
    found = set(zip(pairs.i.tolist(), pairs.j.tolist()))
    recall = len(exact & found) / max(1, len(exact))
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"search_{backend}_n: {n} vectors x {DIM} d")
    print(f"search_{backend}_build_seconds: {build_s:.1f} s")
    print(f"search_{backend}_total_seconds: {total_s:.1f} s (target <= 600 for 1M)")
    print(f"search_{backend}_pairs: {len(pairs)} pairs within {RADIUS}")
    print(
        f"search_{backend}_recall: {recall:.4f} vs exact on {len(queries)} queries ({len(exact)} pairs; target >= 0.95)"
    )
    print(f"search_{backend}_peak_rss: {rss:.0f} MB (vectors alone {x.nbytes / 2**20:.0f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

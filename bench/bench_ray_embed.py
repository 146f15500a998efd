"""Hash + decode + embed throughput on ../shared/data/fire-cctv-416 (3,996 416-px frames, no embedding cache):
local (one thread per core, and one thread) against Ray workers (:mod:`curate.embedremote`) on a local Ray of 1
and of 2 CPUs, started beforehand (its start is timed apart: a cluster is started once for many commands). The Ray runs
must give the local vectors bit for bit (the same onnxruntime batches).

.venv/bin/python bench/bench_ray_embed.py [FOLDER] [--images N]   # target: Ray 2 workers >= 0.8 x local
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from curate.embed import load_embedder
from curate.scan import ScanResult, list_image_files, scan_images
from ground.run.cluster import Cluster

DEFAULT = Path(__file__).resolve().parents[2] / "shared" / "data" / "fire-cctv-416"


def _timed(fn) -> tuple[ScanResult, float]:  # noqa: ANN001 - a function returning a ScanResult
    start = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT)
    parser.add_argument("--images", type=int, default=0, help="first N images only (default all)")
    args = parser.parse_args()
    if not args.folder.is_dir():
        print(f"ray_embed_skipped: {args.folder} not found", file=sys.stderr)
        return 0
    paths = list_image_files([args.folder])[: args.images or None]
    embedder = load_embedder()
    cores = os.cpu_count() or 1
    local, local_s = _timed(lambda: scan_images(paths, embedder))
    _, one_s = _timed(lambda: scan_images(paths, embedder, workers=1))
    rates = {"local": len(paths) / local_s, "local_1_thread": len(paths) / one_s}
    same = True
    for cpus in (1, 2):
        start = time.perf_counter()
        with Cluster(local_cpus=cpus) as cluster:
            startup_s = time.perf_counter() - start
            remote, remote_s = _timed(lambda: scan_images(paths, embedder, cluster=cluster))  # noqa: B023
        rates[f"ray_{cpus}_workers"] = len(paths) / remote_s
        same &= np.array_equal(remote.vectors, local.vectors) and remote.images == local.images
        print(f"ray_embed_start_{cpus}_workers: {startup_s:.1f} s (a local Ray with {cpus} CPU(s), once per command)")
    for name, rate in rates.items():
        print(f"ray_embed_{name}: {rate:.1f} img/s ({len(paths)} images)")
    print(
        f"ray_embed_ratio_2_workers_to_local: {rates['ray_2_workers'] / rates['local']:.2f} ({cores} cores; target >= 0.8)"
    )
    print(f"ray_embed_ratio_1_worker_to_local_1_thread: {rates['ray_1_workers'] / rates['local_1_thread']:.2f}")
    print(f"ray_embed_same_vectors: {'yes' if same else 'NO'} (Ray vectors and facts equal to local, bit for bit)")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())

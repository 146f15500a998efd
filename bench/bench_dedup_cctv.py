"""``fuzzyfire dedup`` end to end on ../shared/data/fire-cctv-416 (3,996 images): cold (empty embedding
cache; the one-off ONNX export is done beforehand and timed apart), warm rerun, peak RSS of each run; and its
limit, decoding and embedding alone (the same batches in the same thread pool, nothing else), measured in the
same run so the ratio holds on any machine.

.venv/bin/python bench/bench_dedup_cctv.py [FOLDER]   # targets: cold >= 0.8 of decode+embed alone, <= 5 s warm,
                                                      # <= 2 GB
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DEFAULT = REPO.parent / "shared" / "data" / "fire-cctv-416"
FUZZYFIRE = [sys.executable, "-m", "fuzzyfire.cli"]


def _run(args: list[str], env: dict[str, str]) -> tuple[float, float]:
    """(seconds, peak RSS in MB) of one ``fuzzyfire`` subprocess."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    start = time.perf_counter()
    subprocess.run([*FUZZYFIRE, *args], env=env, check=True, stdout=subprocess.DEVNULL)
    seconds = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return seconds, max(peak, before) / 1024


def decode_embed_alone(src: Path) -> tuple[int, float]:
    """(images, seconds) of decoding and embedding every image of ``src`` and nothing else: no hashing, cache,
    search, ranking or report (the thread pool and batches of ``fuzzyfire dedup``)."""
    from concurrent.futures import ThreadPoolExecutor

    from curate.decode import embed_batch
    from curate.embed import load_embedder
    from curate.scan import bounded_map, list_image_files

    paths = list_image_files([src])
    embedder = load_embedder()
    workers = os.cpu_count() or 2
    batches = [paths[s : s + 4] for s in range(0, len(paths), 4)]
    with ThreadPoolExecutor(workers) as pool:
        start = time.perf_counter()
        for _ in bounded_map(lambda b: embed_batch(b, embedder), batches, pool, 2 * workers):
            pass
        return len(paths), time.perf_counter() - start


def main() -> int:
    src = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT
    if not src.is_dir():
        print(f"dedup_cctv_skipped: {src} not found", file=sys.stderr)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "FUZZYFIRE_CACHE": str(Path(tmp) / "cache")}
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, "-c", "from curate.embed import builtin_model_path; builtin_model_path()"],
            env=env,
            check=True,
        )
        export_s = time.perf_counter() - start
        out = Path(tmp) / "out"
        cold_s, cold_rss = _run(["dedup", str(src), "--out", str(out)], env)
        doc = json.loads((out / "dedup.json").read_text())
        warm_s, warm_rss = _run(["dedup", str(src), "--out", str(out)], env)
        os.environ["FUZZYFIRE_CACHE"] = env["FUZZYFIRE_CACHE"]
        alone_n, alone_s = decode_embed_alone(src)
    n = doc["counts"]["images"]
    print(f"dedup_cctv_model_export: {export_s:.1f} s (once per install)")
    print(f"dedup_cctv_cold_seconds: {cold_s:.1f} s ({n} images)")
    print(f"dedup_cctv_cold_throughput: {n / cold_s:.0f} img/s")
    print(f"dedup_cctv_decode_embed_alone: {alone_n / alone_s:.0f} img/s (the limit: decode + forward, nothing else)")
    print(f"dedup_cctv_ratio_to_decode_embed: {n / cold_s / (alone_n / alone_s):.2f} (target >= 0.8)")
    print(f"dedup_cctv_warm_seconds: {warm_s:.2f} s (target <= 5)")
    print(f"dedup_cctv_peak_rss: {max(cold_rss, warm_rss):.0f} MB (target <= 2048)")
    print(f"dedup_cctv_kept: {doc['counts']['kept']} images (threshold {doc['threshold']})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

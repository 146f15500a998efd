"""Convert ../shared/data/fire-cctv-416 (3,996 images) YOLO -> COCO + YOLO; prints seconds and images/s.

.venv/bin/python bench/bench_convert.py [DATASET]
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from ground.data.formats.registry import read_dataset
from ground.data.writer import write_dataset

DEFAULT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "fire-cctv-416"


def main() -> int:
    src = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT
    if not src.is_dir():
        print(f"convert_skipped: {src} not found", file=sys.stderr)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        ds = read_dataset(src).dataset
        read_s = time.perf_counter() - start
        write_dataset(ds, Path(tmp) / "out", ["coco", "yolo"], images="copy", command="bench")
        total = time.perf_counter() - start
    print(f"convert_read_seconds: {read_s:.2f} s")
    print(f"convert_total_seconds: {total:.2f} s ({len(ds.images)} images, target <= 20 s)")
    print(f"convert_throughput: {len(ds.images) / total:.0f} img/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

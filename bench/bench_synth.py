"""Synth throughput: flame simulation steps/s, compositing images/s (no rendering), Method 2 images/s at 320 px.
Prints ``name: value unit`` lines."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from synth import flames as F
from synth.composite import composite
from synth.method2 import Method2Config, plan_flames, run_method2


def main() -> None:
    p = F.FlameParams(frames=240, keep_every=12, warmup=0)
    t = time.perf_counter()
    seq = F.generate_sequence("bench", p, np.random.default_rng(0))
    dt = time.perf_counter() - t
    print(f"flame_fluid_steps_per_s: {p.frames / dt:.1f} steps/s")
    print(f"flame_fluid_frames_per_s: {len(seq.sprites) / dt:.2f} kept frames/s")
    library = [seq]
    cfg = Method2Config(width=640, height=480)
    rng = np.random.default_rng(1)
    bg = rng.integers(0, 255, (480, 640, 3), dtype=np.uint8)
    depth = np.full((480, 640), 4.0, np.float32)
    plans = [[pl for pl, _ in plan_flames(cfg, library, depth, 1.0, rng)] for _ in range(50)]
    t = time.perf_counter()
    for placements in plans:
        composite(bg, placements)
    print(f"composite_640x480: {len(plans) / (time.perf_counter() - t):.1f} img/s")
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Method2Config(n=64, width=320, height=240, scenes=8)
        t = time.perf_counter()
        run_method2(cfg, library, Path(tmp) / "m2")
        print(f"method2_320x240: {cfg.n / (time.perf_counter() - t):.1f} img/s")


if __name__ == "__main__":
    main()

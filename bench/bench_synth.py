"""Synth throughput against the issue's targets. Prints ``name: value unit`` lines.

- flame simulation: steps/s and kept frames/s of one stable-fluid sequence;
- compositing alone at 640x480 (target >= 20 img/s);
- Method 2: ``--n`` images at 640x480 from 48 environments, rendering included (target: 1,000 in <= 3 min);
- Method 1: ``--n`` images at 640x480 (target: 1,000 in <= 6 min);
- the Method runs make images in ``--workers`` processes (default one per core; the same bytes as one process);
- RSS over each run, this process and its workers (median over 5 % windows of the run's time; the final dataset
  writing is left out): growth
  from 10 % to 90 % of the run and from 50 % to 90 % (target: flat). The run keeps each
  environment's pyrender scene once built (48 here; Method 2 builds its last one at ~38 % of a 1,000-image run,
  Method 1 at ~5 %), so growth before that is the scene cache; a leak shows as growth in the second half.

With ``--environments PATH`` (e.g. ``configs/scenes``) the Method runs use those 3D files instead of the 48
procedural environments (the issue's file-scene targets: Method 2 <= 3 min, Method 1 <= 6 min, RSS flat).

``--only cutouts``: Method 2 with real flame cut-outs (``--cutouts DIR``, a ``fuzzyfire synth cutouts`` output;
default: cut here from the train split of ``../shared/data/fire-cctv-416``) composited on ``--photos`` at 416x416,
the study's own-cut-out pools: an RGBA cut-out emits no light, so its glow is no blur (the same bytes; a cut-out
drawn thousands of pixels large used to stall a worker for minutes).

``--only smoke``: Method 2 on ``--photos`` at 416x416 in one process, ``--n`` images without and with smoke (plumes
above half the flames and alone in half the images, boxed and judged: :mod:`synth.smoke`); the ratio of their
times per image is smoke's cost (target <= 1.30).

Usage: ``python bench/bench_synth.py [--n 200] [--only flames,composite,method2,method1,cutouts,smoke]
[--environments P] [--photos DIR] [--cutouts DIR] [--workers 0]``.
Figures depend on the machine and on other load: take them on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from synth.compose.composite import composite
from synth.flames import simulate as F
from synth.flames.library import FlameLibraryConfig, build_library
from synth.generate import generate
from synth.method1 import Method1Config
from synth.method2 import Method2Config, plan_flames


def _statm_mb(pid: str) -> float:
    with open(f"/proc/{pid}/statm", encoding="ascii") as f:
        return int(f.read().split()[1]) * 4096 / 1e6


def rss_mb() -> float:
    """RSS of this process and its child processes (the image workers; Linux /proc), MB."""
    me, total = str(os.getpid()), _statm_mb("self")
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", encoding="ascii") as f:
                ppid = f.read().rsplit(")", 1)[1].split()[1]
            total += _statm_mb(entry) if ppid == me else 0.0
        except OSError:  # the process ended
            continue
    return total


class RssSampler:
    """Samples RSS every ``period`` seconds in a thread: (seconds since start, MB) pairs."""

    def __init__(self, period: float = 0.25) -> None:
        self.period, self.samples = period, []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        t0 = time.perf_counter()
        while not self._stop.is_set():
            self.samples.append((time.perf_counter() - t0, rss_mb()))
            self._stop.wait(self.period)

    def __enter__(self) -> RssSampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def at(self, fraction: float) -> float:
        """Median RSS (MB) over the 5 % of the run's time starting at ``fraction`` of it."""
        end = self.samples[-1][0]
        window = [mb for t, mb in self.samples if fraction * end <= t <= (fraction + 0.05) * end]
        return float(np.median(window)) if window else self.samples[-1][1]


def bench_flames() -> None:
    p = F.FlameParams(frames=240, keep_every=12, warmup=0)
    t = time.perf_counter()
    seq = F.generate_sequence("bench", p, np.random.default_rng(0))
    dt = time.perf_counter() - t
    print(f"flame_fluid_steps_per_s: {p.frames / dt:.1f} steps/s")
    print(f"flame_fluid_frames_per_s: {len(seq.sprites) / dt:.2f} kept frames/s")


def bench_composite(library) -> None:
    cfg = Method2Config(width=640, height=480, negatives=0.0)
    rng = np.random.default_rng(1)
    bg = rng.integers(0, 255, (480, 640, 3), dtype=np.uint8)
    depth = np.full((480, 640), 4.0, np.float32)
    plans = [[pl for pl, _ in plan_flames(cfg, library, depth, 1.0, rng)] for _ in range(100)]
    t = time.perf_counter()
    for placements in plans:
        composite(bg, placements)
    print(f"composite_640x480: {len(plans) / (time.perf_counter() - t):.1f} img/s")


def bench_run(name: str, run: Callable[[Path], object], n: int, size: str = "640x480") -> None:
    with tempfile.TemporaryDirectory() as tmp, RssSampler() as rss:
        t = time.perf_counter()
        run(Path(tmp) / name)
        dt = time.perf_counter() - t
    print(f"{name}_{size}_images_per_s: {n / dt:.2f} img/s")
    print(f"{name}_{size}_{n}_images: {dt:.1f} s")
    print(f"{name}_rss_growth_10_to_90pct: {rss.at(0.85) - rss.at(0.1):.1f} MB")
    print(f"{name}_rss_growth_50_to_90pct: {rss.at(0.85) - rss.at(0.5):.1f} MB")  # all 48 environments built
    print(f"{name}_rss_peak: {max(mb for _, mb in rss.samples):.0f} MB")


def bench_smoke(library, photos: Path, n: int) -> None:
    """Method 2 on fire-free photos (416 px, one process) without and with smoke (a plume above half the flames, a
    lone plume in half the images, smoke boxed and judged): seconds per image of both and their ratio (the smoke's
    cost; target <= 1.30)."""
    from synth.smoke.library import SmokeConfig, smoke_library

    base = Method2Config(n=n, width=416, height=416, backgrounds=(photos,), images_per_view=2)
    smoky = replace(base, smoke_class=True, smoke=SmokeConfig(above=0.5, alone=0.5))
    took = {}
    with tempfile.TemporaryDirectory() as tmp:  # warm-up: imports, the photo list, the first decodes
        generate(replace(base, n=4), library, Path(tmp) / "out", workers=1)
    for name, cfg, lib in (("plain", base, library), ("smoke", smoky, [*library, *smoke_library(smoky.smoke)])):
        with tempfile.TemporaryDirectory() as tmp:
            t = time.perf_counter()
            generate(cfg, lib, Path(tmp) / "out", workers=1)
            took[name] = (time.perf_counter() - t) / n
        print(f"method2_{name}_416_s_per_image: {took[name]:.3f} s")
    print(f"method2_smoke_time_ratio: {took['smoke'] / took['plain']:.2f} x")


def bench_cutouts(n: int, cutouts: Path | None, real: Path, photos: Path, workers: int) -> None:
    from fuzzyfire.cli import main as cli
    from synth.flames.sprites import load_library

    with tempfile.TemporaryDirectory() as tmp:
        if cutouts is None:
            cutouts = Path(tmp) / "cutouts"
            t = time.perf_counter()
            if cli(["synth", "cutouts", str(real), "--split", "train", "--out", str(cutouts)]) != 0:
                raise SystemExit(f"could not cut flames from {real}")
            print(f"cutouts_from_train_split: {time.perf_counter() - t:.1f} s")
        library = load_library([cutouts])
        cfg = Method2Config(n=n, width=416, height=416, scenes=0, backgrounds=(photos,), background_holdout=0.25,
                            images_per_view=2, flames=FlameLibraryConfig(source="cutouts"))  # fmt: skip
        bench_run("method2_cutouts", lambda out: generate(cfg, library, out, workers=workers), n, "416x416")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=200, help="images per Method run (1000 for the full-size figures)")
    ap.add_argument("--only", default="flames,composite,method2,method1")
    ap.add_argument("--environments", type=Path, help="3D files / folders / sidecars instead of procedural scenes")
    data = Path(__file__).resolve().parents[2] / "shared" / "data"
    photos = data / "fire-free"
    ap.add_argument("--photos", type=Path, default=photos, help=f"--only cutouts, smoke: photos (default {photos})")
    ap.add_argument("--cutouts", type=Path, help="--only cutouts: a synth cutouts folder (default: cut them here)")
    ap.add_argument(
        "--workers", type=int, default=0, help="image processes of the Method runs (default 0 = one per core)"
    )
    args = ap.parse_args()
    workers = args.workers or os.cpu_count() or 1
    print(f"synth_workers: {workers} processes")
    scenes = {"scenes": 0, "environments": (args.environments,)} if args.environments else {"scenes": 48}
    tag = "_files" if args.environments else ""
    only = set(args.only.split(","))
    if "flames" in only:
        bench_flames()
    if "cutouts" in only:
        bench_cutouts(args.n, args.cutouts, data / "fire-cctv-416", args.photos, workers)
    if not only & {"composite", "method2", "method1", "smoke"}:
        return
    t = time.perf_counter()
    library = build_library(FlameLibraryConfig())
    print(f"flame_library_12x240_steps: {time.perf_counter() - t:.1f} s")
    if "composite" in only:
        bench_composite(library)
    if "smoke" in only:
        bench_smoke(library, args.photos, args.n)
    if "method2" in only:
        cfg2 = Method2Config(n=args.n, width=640, height=480, **scenes)
        bench_run(f"method2{tag}", lambda out: generate(cfg2, library, out, workers=workers), args.n)
    if "method1" in only:
        cfg1 = Method1Config(n=args.n, width=640, height=480, **scenes)
        bench_run(f"method1{tag}", lambda out: generate(cfg1, library, out, workers=workers), args.n)


if __name__ == "__main__":
    main()

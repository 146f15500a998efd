"""Realism ablation of Method 2 on the shared data: how far each variant's images are from the real common set
(embedding gap, ``fuzzyfire synth gap``) and, with ``--train``, what a detector trained only on them scores
(synthetic-only R0_S400 of configs/shared-data.yaml, the study's detector, AP50 on the common and rare sets).

Variants (400 images at 416x416, seed 0, each a cached pool of the experiment pipeline):

- ``procedural``: the 24 procedural rooms, no flame light, no strong camera effects (the previous generator);
- ``files``: the 12 scenes of ../shared/data/scenes (configs/scenes sidecars), no light, no camera effects;
- ``files_light``: + flames lighting their surroundings;
- ``files_light_camera``: + camera effects (low light, defocus, motion blur, vignette, CCTV) - the default;
- ``files_opaque``: + flames opaque (luminous coverage 0.85-1 instead of 0.5-0.95: real flames hide what is
  behind them and outshine it);
- ``files_opaque_dark``: + the scene at low exposure in 40 % of images (night, or a camera exposed for the fire);
- ``files_views``: the default with 2 images per rendered view instead of 8 (200 viewpoints instead of 50);
- ``files_closeups``: ``files_views`` with 30 % of the fire images framed as close-ups (one flame filling 40-100 %
  of the frame height, its base near the bottom edge: a fire seen from close by, as in the rare set);
- ``files_natural``: ``files_views`` with opaque flames (coverage 0.85-1) and no chemical-colour flames (the
  real sets have none; with 12 sequences, 2 are blue or red and look pink on light walls).
- ``files_cutouts``: ``files_views`` with *real* flames in place of simulated ones: every fire box of the
  curated real train split cut out by ``fuzzyfire synth cutouts`` (never the test split). Its distance to the
  other variants is the share of the gap the flames' appearance accounts for; the rest is the scenes.
- ``files_surfaces``: ``files_views`` with flames standing only on up-facing surfaces (``stand: surfaces``, the
  default since; every variant above keeps ``stand: anywhere``, the rule it was measured with);
- ``photos``: the fire-free photographs of ../shared/data as sites (a quarter held out by content hash), 2 images
  per photo view;
- ``panoramas``: the 29 panoramas of ../shared/data as places, 2 images per view;
- ``photos_panoramas``: both in one pool, half the views each.
- ``blend_alpha``, ``blend_blur``, ``blend_poisson``: ``panoramas`` with every flame pasted in one blend mode of
  synth/blend.py (feathered alpha, blurred edge, Poisson clone) instead of added as light (screen / add);
- ``blend_matched``: ``panoramas`` with flames tinted by the local light, blurred and grained like the background;
- ``blend_all``: ``panoramas`` with the five blend modes drawn per flame, matched looks and decoy pastes in 30 % of
  the images (no paste cue left to learn);
- ``distractors``: ``panoramas`` with distractors (lamps, a low sun, cones, red cloth, jackets, tail lights, glare;
  no box) in half of the images;
- ``distractors_blend_all``: both.
- ``streets``: 16 procedural kit streets from ../shared/data/kits (flames on the ground of their fire zones);
- ``mix``: panoramas (half the views), the 12 interiors (flames on up-facing surfaces) and the 16 kit streets.
- ``texture``: ``panoramas`` with the simulated flames' inner streaks (``flames.texture: 0.5``);
- ``never_darken``: ``panoramas`` with flame edges that never darken what is behind them;
- ``look``: both (``texture`` + ``never_darken``: configs/shared-data.yaml's default; every other variant has the
  earlier flat look it was measured with).

Lines: ``synth_<variant>_gap`` (Fréchet distance to half the real train split, median of 200 draws),
``synth_<variant>_gap_ratio`` (to the real-vs-real floor), ``synth_real_floor``, and with ``--train``
``synth_<variant>_<test>_AP50_mean`` / ``_std`` over ``--seeds``. Skips cleanly without ../shared/data.

.venv/bin/python bench/bench_synth_realism.py [--out out/bench-synth-realism] [--train] [--seeds 0,1,2]
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "shared-data.yaml"
SHARED = ROOT.parent / "shared" / "data"
NO_CAMERA = [f"synth.method2.camera.{k}=0" for k in ("low_light", "defocus", "motion_blur", "vignette", "cctv")]
FILES = ["synth.method2.scenes=0", f"synth.method2.environments=[{(ROOT / 'configs' / 'scenes').as_posix()}]"]
PROCEDURAL = ["synth.method2.scenes=24", "synth.method2.environments=[]"]
OPAQUE = ["synth.method2.flame_opacity=[0.85,1.0]"]
ANYWHERE = ["synth.method2.stand=anywhere"]
PHOTOS = [f"synth.method2.backgrounds=[{(SHARED / 'fire-free').as_posix()}]", "synth.method2.background_holdout=0.25"]
PANORAMAS = [f"synth.method2.environments=[{(SHARED / 'panoramas').as_posix()}]"]
SITES = ["synth.method2.scenes=0", "synth.method2.environments=[]", "synth.method2.images_per_view=2"]
BLEND_ALL = [
    "synth.method2.blend.modes=[screen,add,alpha,blur,poisson]",
    "synth.method2.blend.harmonise=true",
    "synth.method2.blend.match_noise=true",
    "synth.method2.blend.decoys=0.3",
]
DISTRACTORS = ["synth.method2.distractors.share=0.5"]
STREETS = ["synth.method2.streets=16", f"synth.method2.kits=[{(SHARED / 'kits').as_posix()}]"]
ROOMS = (ROOT / "configs" / "scenes").as_posix()
#: Every variant starts from the flames' earlier look (the one the variants were measured with); ``texture``,
#: ``never_darken`` and ``look`` (the study's default since) turn it on.
FLAT = ["synth.method2.never_darken=false", "synth.method2.flames.texture=0"]
VARIANTS = {
    "procedural": [*ANYWHERE, *PROCEDURAL, "synth.method2.light=false", *NO_CAMERA],
    "files": [*ANYWHERE, *FILES, "synth.method2.light=false", *NO_CAMERA],
    "files_light": [*ANYWHERE, *FILES, *NO_CAMERA],
    "files_light_camera": [*ANYWHERE, *FILES],
    "files_opaque": [*ANYWHERE, *FILES, *OPAQUE],
    "files_opaque_dark": [*ANYWHERE, *FILES, *OPAQUE, "synth.method2.camera.low_light=0.4"],
    "files_views": [*ANYWHERE, *FILES, "synth.method2.images_per_view=2"],
    "files_closeups": [*ANYWHERE, *FILES, "synth.method2.images_per_view=2", "synth.method2.closeup=0.3"],
    "files_natural": [*ANYWHERE, *FILES, "synth.method2.images_per_view=2", *OPAQUE, "synth.method2.flames.rare=0"],
    "files_cutouts": [*ANYWHERE, *FILES, "synth.method2.images_per_view=2"],  # + flames.folders, see _cutout_library
    "files_surfaces": [*FILES, "synth.method2.images_per_view=2", "synth.method2.stand=surfaces"],
    "photos": [*SITES, *PHOTOS],
    "panoramas": [*SITES, *PANORAMAS],
    "photos_panoramas": [*SITES, *PHOTOS, *PANORAMAS, "synth.method2.photo_share=0.5"],
    "blend_alpha": [*SITES, *PANORAMAS, "synth.method2.blend.modes=[alpha]"],
    "blend_blur": [*SITES, *PANORAMAS, "synth.method2.blend.modes=[blur]"],
    "blend_poisson": [*SITES, *PANORAMAS, "synth.method2.blend.modes=[poisson]"],
    "blend_matched": [*SITES, *PANORAMAS, "synth.method2.blend.harmonise=true", "synth.method2.blend.match_noise=true"],
    "blend_all": [*SITES, *PANORAMAS, *BLEND_ALL],
    "distractors": [*SITES, *PANORAMAS, *DISTRACTORS],
    "distractors_blend_all": [*SITES, *PANORAMAS, *DISTRACTORS, *BLEND_ALL],
    "streets": [*SITES, *STREETS],
    "mix": [*SITES, f"synth.method2.environments=[{(SHARED / 'panoramas').as_posix()},{ROOMS}]", *STREETS],
    "texture": [*SITES, *PANORAMAS, "synth.method2.flames.texture=0.5"],
    "never_darken": [*SITES, *PANORAMAS, "synth.method2.never_darken=true"],
    "look": [*SITES, *PANORAMAS, "synth.method2.flames.texture=0.5", "synth.method2.never_darken=true"],
}
#: Variants whose flames are cut from the curated real train split.
CUTOUT_VARIANTS = ("files_cutouts",)


def _config(overrides: list[str], seeds: list[int]):
    from curate.core.config import load_config
    from fuzzyfire.experiment_config import ExperimentConfig

    grid = ["grid.mixtures=[R0_S400]", "grid.table1=[]", "grid.synthetic=method2", "synth.method1=null"]
    seeds_ = f"grid.seeds=[{','.join(map(str, seeds))}]"
    return load_config(CONFIG, ExperimentConfig, [*grid, seeds_, "report.samples=false", *FLAT, *overrides])


def _cutout_library(seeds: list[int], out: Path) -> Path:
    """The curated real train split's flames cut out once into ``out/cutouts-<real hash>`` (the real stage is
    built or reused first); returns that folder."""
    from curate.core.load import load_split
    from fuzzyfire.experiment import prepare_data
    from synth.cutouts import cutouts, write_cutouts

    real = prepare_data(_config([], seeds), CONFIG.parent, out, ()).real
    folder = out / f"cutouts-{real.path.name.rsplit('-', 1)[-1]}"
    if not (folder / "cutouts.json").exists():
        train = load_split(real.path, real.format, "train", ["fire"])
        write_cutouts(cutouts(train, "fire"), folder)
    return folder


def _gap_line(name: str, gap: dict) -> None:
    f = gap["frechet"]
    print(
        f"synth_{name}_gap: {f['synthetic']['median']:.3f} (95% range {f['synthetic']['low']:.3f}-{f['synthetic']['high']:.3f})"
    )
    print(f"synth_{name}_gap_ratio: {f['ratio']['median']:.2f} x the real-vs-real floor")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench-synth-realism")
    parser.add_argument("--train", action="store_true", help="also train and score synthetic-only R0_S400")
    parser.add_argument("--seeds", default="0")
    parser.add_argument("--only", default=",".join(VARIANTS), help="comma-separated variants")
    args = parser.parse_args()
    if not (SHARED / "fire-cctv-416").is_dir() or not (SHARED / "scenes").is_dir():
        print(f"synth_realism_skipped: {SHARED} not found", file=sys.stderr)
        return 0
    from fuzzyfire.aggregate import realism_gaps
    from fuzzyfire.datasets import Datasets
    from fuzzyfire.executors import LocalExecutor
    from fuzzyfire.experiment import grid_entries, needed_methods, prepare_data, run_experiment

    seeds = [int(s) for s in args.seeds.split(",")]
    floor_printed = False
    for name in args.only.split(","):
        out = args.out  # one curated real set; each variant's pool and runs have their own hash
        with contextlib.redirect_stdout(sys.stderr):
            extra = (
                [f"synth.method2.flames.folders=[{_cutout_library(seeds, out).as_posix()}]"]
                if name in CUTOUT_VARIANTS
                else []
            )
            cfg = _config([*VARIANTS[name], *extra], seeds)
            data = prepare_data(cfg, CONFIG.parent, out, needed_methods(grid_entries(cfg)))
            (gap,) = realism_gaps(cfg, data, Datasets(cfg.classes), out)
        if not floor_printed:
            print(f"synth_real_floor: {gap['frechet']['floor']['median']:.3f} (real train split vs its other half)")
            floor_printed = True
        _gap_line(name, gap)
        if not args.train:
            continue
        with contextlib.redirect_stdout(sys.stderr):
            result = run_experiment(cfg, CONFIG.parent, out, LocalExecutor())
        for test in sorted({r["test_set"] for r in result.rows}):
            values = 100 * np.array([r["AP50"] for r in result.rows if r["test_set"] == test])
            std = values.std(ddof=1) if len(values) > 1 else 0.0
            print(f"synth_{name}_{test}_AP50_mean: {values.mean():.1f} % ({len(values)} seeds: "
                  f"{', '.join(f'{v:.1f}' for v in values)}), std {std:.1f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())

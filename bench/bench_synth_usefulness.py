"""Does a synthetic pool help? R200_S200 (200 real + 200 synthetic images) against R200_S0 (the same 200 real
images alone) on the shared data, per Method 2 variant: the study of configs/shared-data.yaml on those two
mixtures, the study's detector, ``--seeds`` (default 0, 1, 2), Δ with the paired image-level bootstrap over
images (1,000 resamples, seeds averaged) - the measure of issue 22/23's targets. R200_S0 runs are shared by
every variant (trained once); each variant's pools and runs are cached under ``--out`` (pointing it at a study's
folder reuses that study's runs).

Variants (on shared-data.yaml: panoramas, the flames' new look, 2 images per view):

- ``flat``: the flames' earlier flat look (no streaks, edges may darken a wall);
- ``look``: the default (``flames.texture: 0.5``, ``never_darken``);
- ``finetune``: ``look`` with ``train.real_finetune: 10`` (the last 10 epochs on the real images only);
  ``own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_finetune`` the same on ASAE;
- ``cutouts``: each mixture's own real flames cut out and pasted (``flames.source: cutouts``);
- ``own_frames``: simulated flames composited on each mixture's own real training images, which keep their
  boxes (``own_frames: 1``);
- ``own_frames_half``: half the views on own frames, half on the panoramas;
- ``own_frames_cutouts``: own cut-out flames on own frames (copy-paste augmentation made by the study);
- ``own_frames_cutouts_source_box``: ``own_frames_cutouts`` with each cut-out boxed by the box it was cut from,
  moved and scaled with it (``cutout_box: source``: the annotators' margins around the flame pixels);
- ``own_frames_cutouts_half_photo_negatives_upscale2``: ``own_frames_cutouts_half_photo_negatives`` with no
  cut-out drawn above twice its own pixels (``cutout_max_upscale: 2``: no blurred blob from a small flame);
- ``own_frames_cutouts_half_photo_negatives_photo_distractors`` / ``..._distractors``: the same with half of the
  images carrying 1-2 fire-like regions cut from those photos (``distractors: {share: 0.5, kinds: [photo]}``:
  their lamps, lit windows, red sofas, pasted unboxed) / 1-2 drawn distractors (lamps, cones, tail lights ...);
- ``own_frames_cutouts_photo_negatives_photo_distractors``: ``own_frames_cutouts_photo_negatives`` (every photo
  left without a flame) with those photo distractors in half the images: the most negatives, for the alarm rate;
- ``own_frames_exposed_half_photo_negatives_photo_distractors``: the photo-distractor pool with exposed simulated
  flames in place of the cut-outs (``flames.source: simulated``, ``flames.exposed``): what simulated flames reach
  in the best recipe;
- ``own_frames_cutouts_half_photo_negatives_photo_distractors_4``: the photo-distractor pool with four images per
  view (``images_per_view: 4``: each view carries four draws of flames, half as many views);
- ``own_frames_exposed_lowgap_half_photo_negatives_photo_distractors``: the exposed-flame pool with the flames of
  the lowest flame gap measured (``flames: {rare: 0, texture: 0, sequences: 48, keep_every: 24}``, harmonised and
  noise-matched blends);
- ``own_frames_cutouts_half_photo_negatives_photo_distractors_blends``: the photo-distractor pool with each flame's
  blend drawn from all five modes, harmonised to the local light, blur and grain matched to the background
  (``blend: {modes: [screen, add, alpha, blur, poisson], harmonise, match_noise}``): no paste cue, trained;
- ``exposed_photos_half_negatives``: exposed simulated flames on half of those photos, the other half as they are,
  no panoramas (``environments: []``, ``flames.exposed``, ``photo_negatives: 0.5``);
- ``own_frames_cutouts_clean``: ``own_frames_cutouts`` without the cut-outs whose mask fills more than 85 % of
  their box (fire-lit rectangles: ``flames.cutout_max_fill: 0.85``);
- ``own_frames_none``: own frames with no flame added (``negatives: 1``): what the frames give by themselves
  (a second, cropped and camera-treated copy of each real image) - the control of ``own_frames``;
- ``own_frames_cutouts_1``: ``own_frames_cutouts`` with one image per view (``images_per_view: 1``: every image on
  another crop of another real frame, not two on each);
- ``rising_smoke``: ``look`` with the simulated flames' smoke only from their middle up (``flames.rising_smoke``);
- ``opaque_rising``: ``rising_smoke`` with the flames' bright bodies hiding a bright background (``opaque_body``);
- ``exposed``: ``look`` with the simulated flames coloured as a camera records fire (``flames.exposed``: white
  cores, orange, red edges; the chemical-colour ones keep theirs, so the variant shares the control);
- ``photo_negatives``: the fire-free photos of ``fire-free/`` (less the 25 % held out as the false-alarm test set)
  as they are, with no flame, for every synthetic image (``backgrounds``, ``negatives: 1``): hard negatives alone;
- ``look_photo_negatives``: ``look`` with a quarter of the views on those photos, left without flames
  (``photo_negatives: 1``: hard negatives beside the simulated flames);
- ``own_frames_cutouts_photo_negatives``: ``own_frames_cutouts`` with those photos beside the own frames as hard
  negatives (about half the views: the photos and frames are drawn in one order);
- ``own_frames_cutouts_half_photo_negatives``: the same with own cut-outs pasted on half of those photos and the
  other half left as they are (``photo_negatives: 0.5``: about a quarter of the views hard negatives).
- ``own_frames_cutouts_photo_negatives_photo_distractors_auto_exposure``: ASAE with every fire-free photo left as
  it is (``photo_negatives: 1``: about half the views hard negatives, the flames only on the own frames);
  ``own_frames_cutouts_photo_negatives_auto_exposure`` the same without the photo distractors (the pools and runs
  of configs/own-flames-negatives.yaml), ``..._anchored`` that one with ``frame_anchored``.

Lines: ``synth_use_<variant>_<test>_<metric>_delta: +d AP points (95% CI lo..hi, p)`` for AP50 and AP on every
test set with fire, ``synth_use_<variant>_vs_copies_<test>_<metric>_delta`` the same against the variant's control
(R200_S200 on flame-free copies of its real images: ``grid.control``, on in shared-data.yaml; trained once,
shared by the variants that differ only in their places, flames or frames: fuzzyfire/controls.py KEPT), ``synth_use_<variant>_R200_S200_<test>_AP50: mean % (seeds: ...), std`` and, on a
negatives-only set, ``..._alarms_per_100``; with a negatives-only set, also
``synth_use_<variant>_<test>_recall_at_10_alarms_delta``: the paired difference of the share of boxes found where
each model raises at most 10 alarms per 100 of those images (eval/operating.py). Skips cleanly without
../shared/data.

.venv/bin/python bench/bench_synth_usefulness.py [--out out/bench-synth-usefulness] [--seeds 0,1,2] [--only look,own_frames]  (the default pair)
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import sys
from pathlib import Path

import numpy as np

from eval.operating import RECALL_AT_ALARMS
from fuzzyfire.controls import control_label

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "shared-data.yaml"
SHARED = ROOT.parent / "shared" / "data"
STUDY = [
    "grid.table1=[]",
    "synth.method1=null",
    "grid.mixtures=[R200_S0,R200_S200]",
    "report.baseline=R200_S0",
    "report.gap_draws=0",
    "report.samples=false",
]
#: The fire-free photos as a pool's backgrounds, the quarter that is the false-alarm test set held out.
PHOTOS = ["synth.method2.backgrounds=[../../shared/data/fire-free]", "synth.method2.background_holdout=0.25"]
#: Half of the images carry 1-2 fire-like regions cut from those photos, unboxed.
PHOTO_DISTRACTORS = ["synth.method2.distractors.share=0.5", "synth.method2.distractors.kinds=[photo]"]
#: ASAE: own frames and own cut-outs, half the fire-free photos with flames, photo distractors, auto exposure
#: (the best own-cut-out pool of the AMD machine; the base of the variants that add one key to it).
ASAE = [
    *PHOTOS,
    "synth.method2.photo_negatives=0.5",
    "synth.method2.own_frames=1.0",
    "synth.method2.flames.source=cutouts",
    *PHOTO_DISTRACTORS,
    "synth.method2.auto_exposure=true",
]

#: ASAE without its photo distractors (the base of the designs that change them).
ASAE_WITHOUT_DISTRACTORS = [k for k in ASAE if k not in PHOTO_DISTRACTORS]

#: ASAE with every fire-free photo left as it is (the flames only on the own frames), with and without its
#: photo distractors; the second is configs/own-flames-negatives.yaml (its distractors keep their kinds at share 0,
#: so the pools are the same and so named).
ALL_PHOTOS_NEGATIVE = [*ASAE, "synth.method2.photo_negatives=1.0"]
ALL_PHOTOS_NEGATIVE_WITHOUT_DISTRACTORS = [*ALL_PHOTOS_NEGATIVE, "synth.method2.distractors.share=0"]

VARIANTS = {
    "flat": ["synth.method2.never_darken=false", "synth.method2.flames.texture=0"],
    "look": [],
    "finetune": ["train.real_finetune=10"],
    "cutouts": ["synth.method2.flames.source=cutouts"],
    "own_frames": ["synth.method2.own_frames=1.0"],
    "own_frames_half": ["synth.method2.own_frames=0.5"],
    "own_frames_cutouts": ["synth.method2.own_frames=1.0", "synth.method2.flames.source=cutouts"],
    "own_frames_cutouts_source_box": [
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        "synth.method2.cutout_box=source",
    ],
    "own_frames_none": ["synth.method2.own_frames=1.0", "synth.method2.negatives=1.0"],
    "own_frames_cutouts_1": [
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        "synth.method2.images_per_view=1",
    ],
    "rising_smoke": ["synth.method2.flames.rising_smoke=true"],
    "opaque_rising": ["synth.method2.flames.rising_smoke=true", "synth.method2.opaque_body=true"],
    "exposed": ["synth.method2.flames.exposed=true"],
    "photo_negatives": [
        "synth.method2.environments=[]",
        *PHOTOS,
        "synth.method2.negatives=1.0",
    ],
    "look_photo_negatives": [
        *PHOTOS,
        "synth.method2.photo_share=0.25",
        "synth.method2.panorama_share=0.75",
        "synth.method2.photo_negatives=1.0",
    ],
    "own_frames_cutouts_photo_negatives": [
        *PHOTOS,
        "synth.method2.photo_negatives=1.0",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
    ],
    "own_frames_cutouts_half_photo_negatives": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
    ],
    "own_frames_cutouts_half_photo_negatives_upscale2": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        "synth.method2.cutout_max_upscale=2.0",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        "synth.method2.distractors.share=0.5",
        "synth.method2.distractors.kinds=[photo]",
    ],
    "own_frames_cutouts_half_photo_negatives_distractors": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        "synth.method2.distractors.share=0.5",
    ],
    "own_frames_cutouts_photo_negatives_photo_distractors": [
        *PHOTOS,
        "synth.method2.photo_negatives=1.0",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        *PHOTO_DISTRACTORS,
    ],
    "own_frames_exposed_half_photo_negatives_photo_distractors": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.exposed=true",
        *PHOTO_DISTRACTORS,
    ],
    "own_frames_exposed_half_photo_negatives_photo_distractors_auto_exposure": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.exposed=true",
        *PHOTO_DISTRACTORS,
        "synth.method2.auto_exposure=true",
    ],
    "own_frames_exposed_half_photo_negatives_photo_distractors_auto_exposure_cluster": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.exposed=true",
        *PHOTO_DISTRACTORS,
        "synth.method2.auto_exposure=true",
        "synth.method2.flames.cluster=2",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure": ASAE,
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_log_heights": [
        *ASAE,
        "synth.method2.flame_heights=log",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_jitter": [
        *ASAE,
        "synth.method2.flame_jitter=true",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_separate": [
        *ASAE,
        "synth.method2.separate_flames=true",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_swap": [
        *ASAE,
        "synth.method2.frame_swap=0.5",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_anchored": [
        *ASAE,
        "synth.method2.frame_anchored=true",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_feather": [
        *ASAE,
        "synth.method2.flames.cutout_feather=0.2",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_groups": [
        *ASAE,
        "synth.method2.flames.cutout_groups=true",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_camera_cctv": [
        *ASAE,
        "synth.method2.camera.cctv=0.5",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_auto_exposure_finetune": [
        *ASAE,
        "train.real_finetune=10",
    ],
    "own_frames_cutouts_half_photo_negatives_auto_exposure": ASAE_WITHOUT_DISTRACTORS,
    "own_frames_cutouts_photo_negatives_photo_distractors_auto_exposure": ALL_PHOTOS_NEGATIVE,
    "own_frames_cutouts_photo_negatives_auto_exposure": ALL_PHOTOS_NEGATIVE_WITHOUT_DISTRACTORS,
    "own_frames_cutouts_photo_negatives_auto_exposure_anchored": [
        *ALL_PHOTOS_NEGATIVE_WITHOUT_DISTRACTORS,
        "synth.method2.frame_anchored=true",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_lights_distractors_auto_exposure": [  # lights, in every image
        *ASAE_WITHOUT_DISTRACTORS,
        "synth.method2.distractors.share=1.0",
        "synth.method2.distractors.max=3",
        "synth.method2.distractors.kinds=[photo,lights]",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_4": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        *PHOTO_DISTRACTORS,
        "synth.method2.images_per_view=4",
    ],
    "own_frames_exposed_lowgap_half_photo_negatives_photo_distractors": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.exposed=true",
        *PHOTO_DISTRACTORS,
        "synth.method2.flames.rare=0.0",
        "synth.method2.flames.texture=0.0",
        "synth.method2.flames.sequences=48",
        "synth.method2.flames.keep_every=24",
        "synth.method2.blend.harmonise=true",
        "synth.method2.blend.match_noise=true",
    ],
    "own_frames_cutouts_half_photo_negatives_photo_distractors_blends": [
        *PHOTOS,
        "synth.method2.photo_negatives=0.5",
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        *PHOTO_DISTRACTORS,
        "synth.method2.blend.modes=[screen,add,alpha,blur,poisson]",
        "synth.method2.blend.harmonise=true",
        "synth.method2.blend.match_noise=true",
    ],
    "exposed_photos_half_negatives": [
        *PHOTOS,
        "synth.method2.environments=[]",
        "synth.method2.flames.exposed=true",
        "synth.method2.photo_negatives=0.5",
    ],
    "own_frames_cutouts_clean": [
        "synth.method2.own_frames=1.0",
        "synth.method2.flames.source=cutouts",
        "synth.method2.flames.cutout_max_fill=0.85",
    ],
}
MIXTURE, BASELINE = "R200_S200", "R200_S0"


def _config(overrides: list[str], seeds: list[int]):
    from curate.core.config import load_config
    from fuzzyfire.experiment_config import ExperimentConfig

    seeds_ = f"grid.seeds=[{','.join(map(str, seeds))}]"
    return load_config(CONFIG, ExperimentConfig, [*STUDY, seeds_, *overrides])


def _print_deltas(name: str, table: Path) -> None:
    """The R200_S200 - R200_S0 lines of a study's ``tables/comparisons.csv``, then the R200_S200 - its control
    lines (``vs_copies``: the same mixture on flame-free copies of its real images, ``grid.control``)."""
    with table.open(encoding="utf-8") as f:
        rows = [
            r for r in csv.DictReader(f) if r["mixture"] == MIXTURE and r["metric"] in ("AP50", "AP", RECALL_AT_ALARMS)
        ]
    for baseline, what in ((BASELINE, ""), (control_label(MIXTURE), "vs_copies_")):
        for row in (r for r in rows if r["baseline"] == baseline):
            unit = "recall" if row["metric"] == RECALL_AT_ALARMS else "AP"
            print(f"synth_use_{name}_{what}{row['test_set']}_{row['metric']}_delta: {float(row['delta']):+.1f} {unit} "
                  f"points (95% CI {float(row['low']):+.1f}..{float(row['high']):+.1f}, p {row['p_value']})")  # fmt: skip


def _print_means(name: str, rows: list[dict]) -> None:
    """Mean and std over seeds of R200_S200's AP50 per test set with fire, and of its alarms per 100 images on a
    negatives-only set."""
    for test in sorted({r["test_set"] for r in rows}):
        mine = [r for r in rows if r["test_set"] == test and r["mixture"] == MIXTURE and "table2" in r["tables"]]
        if any(r["AP50"] is not None for r in mine):
            key, unit, values = "AP50", " %", [100 * r["AP50"] for r in mine]
        else:
            key, unit, values = "alarms_per_100", "", [r["alarms_per_100"] for r in mine]
        arr = np.array(values, dtype=float)
        std = arr.std(ddof=1) if len(arr) > 1 else 0.0
        print(f"synth_use_{name}_{MIXTURE}_{test}_{key}: {arr.mean():.1f}{unit} (seeds: "
              f"{', '.join(f'{v:.1f}' for v in arr)}), std {std:.1f}")  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench-synth-usefulness")
    parser.add_argument("--seeds", default="0,1,2")
    parser.add_argument(
        "--only", default="look,own_frames", help=f"comma-separated variants of {', '.join(VARIANTS)} (~20 min each)"
    )
    args = parser.parse_args()
    if not (SHARED / "fire-cctv-416").is_dir() or not (SHARED / "panoramas").is_dir():
        print(f"synth_usefulness_skipped: {SHARED} not found", file=sys.stderr)
        return 0
    from fuzzyfire.executors import LocalExecutor
    from fuzzyfire.experiment import run_experiment

    seeds = [int(s) for s in args.seeds.split(",")]
    for name in args.only.split(","):
        if name not in VARIANTS:
            parser.error(f"unknown variant {name!r} (variants: {', '.join(VARIANTS)})")
        cfg = _config(VARIANTS[name], seeds)
        with contextlib.redirect_stdout(sys.stderr):
            result = run_experiment(cfg, CONFIG.parent, args.out, LocalExecutor())
        if result.failed:
            print(f"synth_use_{name}_failed: {len(result.failed)} runs", file=sys.stderr)
            return 1
        _print_deltas(name, args.out / "tables" / "comparisons.csv")
        _print_means(name, result.rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The control every synthetic pool needs (``grid.control``): the same mixture with its synthetic images replaced
by flame-free copies of its own real images.

A mixture R<m>_S<n> trains on more images, more steps and more augmented views than R<m>_S0, so part of what it
gains over R<m>_S0 has nothing to do with the flames (on the shared data 200 such copies gain +2.6 AP50 over
R200_S0: docs/findings.md, "Does a control of flame-free copies explain the gain?"). The control run R<m>_S<n> ``copies``
draws its n synthetic images from a Method 2 pool made of the mixture's own m real training images for that seed
(:func:`fuzzyfire.cutout_pools.own_pool`: the same crops and camera effects as the study's Method 2 pool, each
image keeping its own fire boxes) with no flame added (``negatives`` 1) and no other
background (``own_frames`` 1, no photos or frames of the config). The report compares each mixture with its
control (paired bootstrap, the same images and seeds): what the synthetic *flames* add.

Only Table 2 mixtures with real and synthetic images have a control; R0 mixtures have no real images to copy.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from curate.mix import parse_mixture, real_subset
from fuzzyfire.cutout_pools import PoolKey, own_pool
from fuzzyfire.datasets import DataRef, Datasets

if TYPE_CHECKING:
    from fuzzyfire.experiment_config import ExperimentConfig
    from synth.method2 import Method2Config

#: The pool name of a control run (its ``method``; run folders ``runs/<mixture>-copies``).
CONTROL = "copies"

#: The table of the control runs.
CONTROL_TABLE = "control"


def has_control(mixture: str) -> bool:
    """Whether a Table 2 mixture gets a control run: it has real images to copy and synthetic ones to replace."""
    mix = parse_mixture(mixture)
    return mix.real > 0 and mix.synth > 0


def control_label(mixture: str) -> str:
    """How the tables and comparisons name the control of ``mixture``: ``"R200_S200 copies"``."""
    return f"{mixture} {CONTROL}"


def kept_settings(cfg: Method2Config) -> dict[str, Any]:
    """The Method 2 keys a control keeps from its pool's config ``cfg``, by name: what acts on an image that gets no
    flame (its size, count and seed, the crops and camera)."""
    return {"n": cfg.n, "seed": cfg.seed, "width": cfg.width, "height": cfg.height,
            "images_per_view": cfg.images_per_view, "smoke_class": cfg.smoke_class, "camera": cfg.camera}  # fmt: skip


def control_config(cfg: Method2Config) -> Method2Config:
    """The Method 2 config of a control pool: no flame (every image a negative) on the mixture's own frames only
    (the experiment adds them as labelled frames), with the :func:`kept_settings` of ``cfg``; the places (environments,
    photos, labelled frames), the flame library and the flames' placement and look are the defaults, so the variants
    of a study that differ only in those share one control (and its runs)."""
    return type(cfg)(**kept_settings(cfg), scenes=0, own_frames=1.0, negatives=1.0)


def control_pools(
    cfg: ExperimentConfig, mixtures: Sequence[str], real_train: DataRef, datasets: Datasets, base: Path, out: Path
) -> dict[PoolKey, DataRef]:
    """The copies pool of each (mixture, :data:`CONTROL`, seed) of the Table 2 ``mixtures`` that have a control
    (:func:`has_control`), when ``grid.control`` is on (else none); ``real_train``: the real training split. The
    pools are cached stages (``OUT/data/method2-frames-<hash>``), shared by mixtures that draw the same subset;
    one line printed per pool."""
    m2 = cfg.synth.method2
    if not cfg.grid.control or m2 is None:
        return {}
    real = datasets.get(real_train)
    control = control_config(m2)
    pools: dict[PoolKey, DataRef] = {}
    for seed in cfg.grid.seeds:
        for name in (n for n in dict.fromkeys(mixtures) if has_control(n)):
            _, stage, ref = own_pool(out / "data", control, real_subset(real, parse_mixture(name), seed), base)
            cached = "  (cached)" if stage.cached else ""
            print(f"data   {CONTROL} {name} seed {seed}: control pool {stage.folder}{cached}", flush=True)
            pools[(name, CONTROL, seed)] = ref.with_split(None)
    return pools

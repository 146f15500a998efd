"""Method 2 pools whose flames are each mixture's own real flames (``synth.method2.flames.source: cutouts``), and whose
plumes are its own labelled smoke (``synth.method2.smoke.source: cutouts``, when smoke is studied: each smoke box
matted into a soft sprite, :mod:`synth.smoke.matte`).

For a mixture R<m>_S<n> with m > 0 and a seed, the real training subset is the m real images the mixture trains
on (:func:`curate.mix.real_subset`, drawn from ``real.train_split`` only). Its fire boxes are cut out
(:mod:`synth.flames.cutouts`, at the defaults of ``fuzzyfire synth cutouts``: :func:`cut_settings`) into a stage ``cutouts-<hash>``, and a Method 2 pool
``method2-cutouts-<hash>`` is composited with those flames; the mixture's n synthetic images are drawn from that pool. Both stages live in ``OUT/data`` and are identified
by the subset's content (:func:`ground.data.fingerprint.fingerprint`: image bytes, split and boxes), the mask
rule's parameters and the pool's config, so mixtures and seeds that draw the same subset share them, and a
change of the mask rule makes new cut-outs and pools. Validation and test images never reach a pool.

With ``synth.method2.own_frames`` > 0 an own pool also composites on the mixture's own real training images
(:mod:`synth.places.frames`: each keeps its own fire boxes, flames stand beside them): the subset is written as a
stage ``frames-<hash>`` (COCO, images linked) and becomes the pool's ``labelled_frames``, at that share of the views
(the photo kind's weight, :func:`synth.places.kinds.kind_weights`; the config's places take the rest). The flames
are simulated unless ``flames.source`` says otherwise.

R0_S<n> mixtures have no real images of their own: they keep the experiment's simulated pool (their runs are the
runs of the config without ``flames.source``) and the experiment prints a note saying so. Cutting their flames
from the whole train split instead would make a synthetic-only run train on real pixels; refusing would make
the study's synthetic-only rows (Table 1, Table 2's R0 mixtures) impossible in the same config.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from curate.mix import parse_mixture, real_subset
from fuzzyfire.datasets import DataRef, Datasets
from fuzzyfire.stages import Stage, cached_stage, synth_stage

if TYPE_CHECKING:
    from fuzzyfire.experiment_config import ExperimentConfig
    from ground.data.dataset import Dataset
    from synth.flames.cutouts import CutoutConfig
    from synth.method2 import Method2Config

#: Key of an own pool in :func:`cutout_pools`: (mixture, method, seed).
PoolKey = tuple[str, str, int]


def simulated(cfg: Method2Config) -> Method2Config:
    """``cfg`` with simulated flames and plumes on its own places only (``flames.source`` and ``smoke.source``
    simulated, no ``own_frames``): the experiment's shared pool, which R0 mixtures and the report's samples and gap
    use."""
    flames, smoke = replace(cfg.flames, source="simulated"), replace(cfg.smoke, source="simulated")
    return replace(cfg, flames=flames, smoke=smoke, own_frames=0.0)


def is_own(cfg: Method2Config | None) -> bool:
    """Whether mixtures with real images get pools of their own (own cut-out flames, own smoke or own frames)."""
    return cfg is not None and (bool(cut_classes(cfg)) or cfg.own_frames > 0)


def cut_classes(cfg: Method2Config) -> tuple[str, ...]:
    """The classes an own pool of ``cfg`` cuts out of its mixture's images: fire with ``flames.source: cutouts``,
    smoke with ``smoke.source: cutouts`` when the pool lays plumes."""
    fire = ("fire",) if cfg.flames.source == "cutouts" else ()
    smoke = ("smoke",) if cfg.smoke.source == "cutouts" and cfg.smoke.plumes else ()
    return fire + smoke


def frames_stage(root: Path, subset: Dataset) -> Stage:
    """``subset`` (images and fire boxes) written as a COCO dataset whose images link to the originals: the
    labelled frames of an own pool (:mod:`synth.places.frames`), a cached stage identified by the subset's content."""
    from ground.data.fingerprint import fingerprint
    from ground.data.writer import write_dataset

    identity = {"kind": "frames", "real": fingerprint(subset).to_dict()}
    return cached_stage(root, "frames", identity, lambda out: write_dataset(subset, out, ("coco",), "symlink"))


def cut_settings(category: str = "fire") -> CutoutConfig:
    """The own pools' cut-out settings for ``category``: ``fuzzyfire synth cutouts``' defaults (the grabcut rule
    for fire; smoke boxes are matted)."""
    from synth.flames.cutouts import CutoutConfig

    return CutoutConfig(class_name=category)


#: Version of the cut-out rules beyond the keys in :func:`mask_identity`: 2 = flames windowed (no rectangle), smoke
#: matted (synth.smoke.matte).
CUT_VERSION = 2


def mask_identity(cut: CutoutConfig) -> dict[str, Any]:
    """The cut-out mask rule of ``cut`` and its parameters (in every cut-out stage's identity)."""
    from synth.flames import cutouts
    from synth.smoke import matte

    return {
        "rule": cut.mask,
        "context": cut.context,
        "iterations": cutouts.GRABCUT_ITERATIONS,
        "min_kept": cutouts.MIN_KEPT,
        "window": list(cutouts.FLAME_WINDOW),
        "matte": [matte.KEEP_HAZE, matte.PATCH, matte.MIN_LUMA, matte.MIN_OPACITY, matte.WINDOW_INNER, matte.WARM],
        "version": CUT_VERSION,
    }


def cutout_stage(root: Path, subset: Dataset, classes: Sequence[str] = ("fire",)) -> Stage:
    """The cut-outs of ``subset``'s boxes of ``classes`` (fire and/or smoke; ``fuzzyfire synth cutouts`` layout,
    ``cutouts.json`` naming each one's class and image), as a cached stage; ValueError when a class gives none."""
    import itertools
    import json

    from ground.data.fingerprint import fingerprint
    from synth.flames.cutouts import cutouts, write_cutouts

    settings = [cut_settings(c) for c in classes]
    identity = {
        "kind": "cutouts",
        "real": fingerprint(subset).to_dict(),
        "classes": list(classes),
        "min_side": settings[0].min_side,
        "min_cover": settings[0].min_cover,
        "mask": mask_identity(settings[0]),
    }
    if "smoke" in classes:  # a rule of the smoke mattes beyond mask_identity's: cut-outs of fire alone keep theirs
        from synth.smoke.matte import CENTRE_HAZE

        identity["centre_haze"] = CENTRE_HAZE

    def cut(out: Path) -> int:
        return write_cutouts(itertools.chain.from_iterable(cutouts(subset, s) for s in settings), out)

    stage = cached_stage(root, "cutouts", identity, cut)
    index = json.loads((stage.folder / "cutouts.json").read_text(encoding="utf-8"))
    for s in settings:
        if not any(e["class"] == s.class_name for e in index):
            what = "fire colour" if s.class_name == "fire" else "light smoke to matte"
            raise ValueError(
                f"{s.class_name} cut-outs: the {len(subset.images)} real images of a mixture give none ({s.class_name} "
                f"boxes of at least {s.min_side} px and enough {what}): use {'flames' if s.class_name == 'fire' else 'smoke'}"
                f".source simulated ({stage.folder})"
            )
    return stage


def own_pool(root: Path, cfg: Method2Config, subset: Dataset, base: Path) -> tuple[Stage | None, Stage, DataRef]:
    """(cut-out stage or None, pool stage, pool reference) of the Method 2 pool of the real ``subset``: its flames
    (``flames.source: cutouts``), its plumes (``smoke.source: cutouts``) and/or its images as frames
    (``own_frames``)."""
    classes = cut_classes(cfg)
    cut = cutout_stage(root, subset, classes) if classes else None
    if cfg.own_frames > 0:
        frames = frames_stage(root, subset).folder
        cfg = replace(cfg, labelled_frames=(frames,), photo_share=cfg.own_frames, panorama_share=1 - cfg.own_frames)
    stage, ref = synth_stage(root, cfg, base, cutouts=cut)
    return cut, stage, ref


def _say(message: str) -> None:
    print(message, flush=True)


def cutout_pools(
    cfg: ExperimentConfig, mixtures: Sequence[str], real_train: DataRef, datasets: Datasets, base: Path, out: Path
) -> dict[PoolKey, DataRef]:
    """The own Method 2 pool of each (mixture, ``method2``, seed) of the Method 2 ``mixtures`` with real images, when
    ``synth.method2.flames.source`` is cutouts or ``own_frames`` > 0 (else none: every mixture keeps the
    shared pool);
    ``real_train``: the real training split, the only images cut. Prints one line per pool and a note naming
    the R0 mixtures, which keep simulated flames (module docstring)."""
    m2 = cfg.synth.method2
    if m2 is None or not is_own(m2):
        return {}
    for name in cut_classes(m2):
        if name not in cfg.classes:
            raise ValueError(f"own Method 2 pools cut '{name}' boxes, but classes are {list(cfg.classes)}")
    entries = list(dict.fromkeys(mixtures))
    kept = [name for name in entries if parse_mixture(name).real == 0]
    if kept:
        _say(f"data   method2: {', '.join(kept)} have no real images of their own: the shared simulated pool")
    real = datasets.get(real_train)
    pools: dict[PoolKey, DataRef] = {}
    for seed in cfg.grid.seeds:
        for name in (n for n in entries if n not in kept):
            subset = real_subset(real, parse_mixture(name), seed)
            cut, stage, ref = own_pool(out / "data", m2, subset, base)
            cached = "  (cached)" if stage.cached else ""
            what = f"flames of {cut.folder.name}, " if cut is not None else ""
            _say(f"data   method2 {name} seed {seed}: {what}pool {stage.folder}{cached}")
            pools[(name, "method2", seed)] = ref.with_split(None)
    return pools

"""The flame library a synthetic run draws sprites from: procedural sequences (:mod:`synth.flames`) made on the
fly, or sequence folders on disk (``fuzzyfire synth flames`` output, or a user's RGBA renders), and, with
``source: cutouts | both``, real flames cut out of labelled images (:mod:`synth.cutouts`), which the caller
supplies (``fuzzyfire experiment`` cuts them from each mixture's own real training images:
:mod:`fuzzyfire.cutout_pools`)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np

from synth.clusters import clustered_library
from synth.feather import feathered
from synth.flames import GENERATORS, generate_sequence, sample_params
from synth.sprites import SpriteSequence, load_library, load_rgba_folder, shown_part

#: Where a library's flames come from (``FlameLibraryConfig.source``).
FLAME_SOURCES: tuple[str, ...] = ("simulated", "cutouts", "both")

#: Where a cut-out sprite sat in its source image: (image, x, y) of its top-left, pixels.
Origin = tuple[str, int, int]

#: ``meta["generator"]`` of a cut-out sequence (:func:`cutout_library`).
CUTOUT_GENERATOR = "cutouts"


@dataclass(frozen=True)
class FlameLibraryConfig:
    sequences: int = 12  # procedural sequences to simulate (ignored when ``folders`` is set)
    generator: Literal["fluid", "noise"] = "fluid"
    frames: int = 240  # simulation steps per sequence
    keep_every: int = 12  # keep one frame every K steps
    rare: float = 0.05  # probability that a sequence is a chemical-colour (rare) flame, drawn per sequence
    seed: int = 0
    folders: tuple[Path, ...] = ()  # sequence folders to load instead of simulating
    source: Literal["simulated", "cutouts", "both"] = "simulated"  # simulated (or folders) | real cut-outs | both
    cutout_share: float = 0.5  # source both: share of flames drawn from the cut-outs, 0..1
    cutout_max_fill: float = 1.0  # experiment's cut-outs: none whose mask fills more of its box (synth.cutouts.cut)
    cutout_feather: float = 0.0  # cut-outs faded towards the box sides their flame touches, this share of the box
    cutout_groups: bool = False  # a cut-out comes with the other cut-outs of its image, where they sat (synth.groups)
    cluster: int = 1  # simulated fires of 1..cluster flames side by side on one base, boxed whole (synth.clusters)
    texture: float = 0.0  # simulated flames' inner streaks and soft edge (synth.flames.streaks), 0..1; 0 = flat body
    rising_smoke: bool = False  # simulated flames' smoke only from the flame's middle up (synth.flames.rising)
    exposed: bool = False  # simulated flames coloured as a camera records fire: white cores, red edges (synth.colour)

    def __post_init__(self) -> None:
        if self.generator not in GENERATORS:
            raise ValueError(f"unknown flame generator {self.generator!r}; choose one of {', '.join(GENERATORS)}")
        if self.sequences < 1 or self.frames < 1 or self.keep_every < 1 or not 0.0 <= self.rare <= 1.0:
            raise ValueError(f"invalid flame library config: {self}")
        if self.source not in FLAME_SOURCES:
            raise ValueError(f"unknown flames.source {self.source!r}; choose one of {', '.join(FLAME_SOURCES)}")
        if not 0.0 <= self.texture < 1.0:
            raise ValueError(f"flames.texture must be in [0, 1), got {self.texture}")
        if not 0.0 < self.cutout_max_fill <= 1.0:
            raise ValueError(f"flames.cutout_max_fill must be in (0, 1], got {self.cutout_max_fill}")
        if not 1 <= self.cluster <= 8:
            raise ValueError(f"flames.cluster must be 1..8 flames per fire, got {self.cluster}")
        if self.source == "cutouts" and self.cluster != 1:
            raise ValueError("flames.cluster groups simulated flames into fires: give it with source simulated or both")
        if not 0.0 <= self.cutout_feather <= 0.5:
            raise ValueError(f"flames.cutout_feather must be in [0, 0.5], got {self.cutout_feather}")
        if self.source == "simulated" and self.cutout_feather and not self.folders:
            raise ValueError(
                "flames.cutout_feather softens real cut-outs: give it with source cutouts or both, or with "
                "flames.folders written by fuzzyfire synth cutouts"
            )
        if self.source == "simulated" and self.cutout_groups and not self.folders:
            raise ValueError(
                "flames.cutout_groups pastes real cut-outs with the others of their image: give it with source "
                "cutouts or both, or with flames.folders written by fuzzyfire synth cutouts"
            )
        if not 0.0 <= self.cutout_share <= 1.0:
            raise ValueError(f"flames.cutout_share must be in 0..1, got {self.cutout_share}")
        if self.source != "both" and self.cutout_share != FlameLibraryConfig.cutout_share:
            raise ValueError(f"flames.cutout_share is the cut-outs' share with source both (source is {self.source})")
        if self.source == "cutouts" and self.folders:
            raise ValueError("flames.folders are simulated flames' stand-ins: give them with source simulated or both")


def procedural_library(
    n: int,
    seed: int,
    frames: int,
    keep_every: int,
    rare: float,
    generator: str = "fluid",
    texture: float = 0.0,
    rising_smoke: bool = False,
    exposed: bool = False,
) -> list[SpriteSequence]:
    """``n`` procedural flame sequences named ``<generator>-<seed>-<k>``; sequence k is drawn from
    ``default_rng([seed, k])`` (a chemical palette with probability ``rare``; inner streaks of depth
    ``texture``, :func:`synth.flames.streaks`; ``rising_smoke``: smoke only from the flame's middle up,
    :func:`synth.flames.rising`; ``exposed``: the camera-exposed palette, :func:`synth.flames.exposed_gain`, with
    the same shapes and motion as without it)."""
    seqs = []
    for k in range(n):
        rng = np.random.default_rng([seed, k])
        fixed = {"frames": frames, "keep_every": keep_every, "texture": texture, "rising_smoke": rising_smoke}
        params = sample_params(rng, generator, rare=bool(rng.random() < rare), exposed=exposed, **fixed)
        seqs.append(generate_sequence(f"{generator}-{seed}-{k:03d}", params, rng))
    return seqs


def build_library(cfg: FlameLibraryConfig, cutouts: Sequence[SpriteSequence] = ()) -> list[SpriteSequence]:
    """The sequences ``cfg`` describes: ``source`` simulated: loaded from ``folders`` when given, else simulated;
    cutouts: ``cutouts`` (:func:`cutout_library`); both: ``cutouts`` then the simulated ones. The simulated (or
    loaded) ones as fires of up to ``cfg.cluster`` flames (:func:`synth.clusters.clustered_library`). ValueError when
    ``cutouts`` are missing for a source that needs them or given to one that does not."""
    if cfg.source == "simulated" and cutouts:
        raise ValueError("cut-outs given to a flame library whose source is simulated")
    if cfg.source != "simulated" and not cutouts:
        raise ValueError(
            f"flames.source {cfg.source}: no cut-outs given (fuzzyfire experiment cuts them from each mixture's real "
            "images; for one pool, cut them with fuzzyfire synth cutouts and give flames.folders)"
        )
    if cfg.source == "cutouts":
        return list(cutouts)
    if cfg.folders:
        simulated = _folders(cfg.folders, cfg.cutout_feather, cfg.cutout_groups)
    else:
        args = (cfg.sequences, cfg.seed, cfg.frames, cfg.keep_every, cfg.rare, cfg.generator, cfg.texture)
        simulated = procedural_library(*args, cfg.rising_smoke, cfg.exposed)
    return list(cutouts) + clustered_library(simulated, cfg.cluster, cfg.seed)


def _folders(folders: Sequence[Path], feather: float, groups: bool = False) -> list[SpriteSequence]:
    """The sequences of ``folders`` (:func:`synth.sprites.load_library`); with ``feather`` > 0 or ``groups`` each
    must be a ``fuzzyfire synth cutouts`` output, loaded by :func:`cutout_library` (with that feather; it knows
    where each cut-out sat in its image) — ValueError if not."""
    if not feather and not groups:
        return load_library(list(folders))
    key = "flames.cutout_feather, --cutout-feather" if feather else "flames.cutout_groups, --cutout-groups"
    for folder in folders:
        if not (folder / "cutouts.json").is_file():
            raise ValueError(
                f"{folder}: holds no cutouts.json, so not real cut-outs ({key}); write them with fuzzyfire synth cutouts"
            )
    return [seq for folder in folders for seq in cutout_library(folder, feather=feather)]


def cutout_library(folder: Path, canvas: bool = False, feather: float = 0.0) -> list[SpriteSequence]:
    """The sequence folders of a ``fuzzyfire synth cutouts`` output ``folder`` (:func:`synth.cutouts.write_cutouts`),
    each marked as cut-outs (``meta["generator"]`` = :data:`CUTOUT_GENERATOR`); each sprite cropped to its content
    (as a user's RGBA frames), or with ``canvas`` on the whole box it was cut from (Method 2's ``cutout_box:
    source`` boxes a flame by it). ``feather`` > 0: each sprite first faded towards the box sides its flame
    touches (:func:`synth.feather.feathered`, ``flames.cutout_feather``), on its whole canvas. ``meta["origins"]``:
    per sprite (source image, x, y), the pixel of its source image at the sprite's top-left (from
    ``cutouts.json``; None for a PNG it does not list): which cut-outs share an image, and where each sat."""
    subs = sorted(p for p in folder.iterdir() if p.is_dir())
    seqs = [load_rgba_folder(sub, crop=not canvas and not feather) for sub in subs]
    if feather:
        seqs = [_feathered(seq, feather, crop=not canvas) for seq in seqs]
    boxes = _source_boxes(folder)
    return [
        replace(seq, meta={**seq.meta, "generator": CUTOUT_GENERATOR, "origins": _origins(seq, boxes)}) for seq in seqs
    ]


def _source_boxes(folder: Path) -> dict[str, tuple[str, list[float]]]:
    """``"<sequence>/<png>"`` -> (source image, its box [x, y, w, h] px) of every cut-out in ``folder``'s
    ``cutouts.json`` (none when the folder has no such file)."""
    index = folder / "cutouts.json"
    if not index.is_file():
        return {}
    return {row["png"]: (row["file"], row["box"]) for row in json.loads(index.read_text(encoding="utf-8"))}


def _origins(seq: SpriteSequence, boxes: dict[str, tuple[str, list[float]]]) -> tuple[Origin | None, ...]:
    """Per sprite of ``seq`` (loaded by :func:`synth.sprites.load_rgba_folder`: its kept ``files`` and
    ``offsets``): (source image, x, y) of its top-left in the source image's pixels, or None when unlisted."""
    out: list[Origin | None] = []
    for name, (dx, dy) in zip(seq.meta["files"], seq.meta["offsets"], strict=True):
        found = boxes.get(f"{seq.name}/{name}")
        out.append(None if found is None else (found[0], int(found[1][0]) + dx, int(found[1][1]) + dy))
    return tuple(out)


def _feathered(seq: SpriteSequence, feather: float, crop: bool) -> SpriteSequence:
    """``seq``'s whole-canvas sprites feathered (:func:`synth.feather.feathered`), each cropped to its content when
    ``crop``; a sprite whose flame the feather fades out entirely is left out (a sequence keeps at least one).
    ``meta``'s ``files`` and ``offsets`` follow the sprites kept."""
    sprites, files, offsets = [], [], []
    for sprite, name in zip(seq.sprites, seq.meta["files"], strict=True):
        kept = shown_part(feathered(sprite, feather), crop)
        if kept is not None:
            sprites.append(kept[0])
            files.append(name)
            offsets.append(kept[1])
    if not sprites:
        sprites, files, offsets = [seq.sprites[0]], [seq.meta["files"][0]], [(0, 0)]
    return replace(seq, sprites=tuple(sprites), meta={**seq.meta, "files": files, "offsets": offsets})


def is_cutout(seq: SpriteSequence) -> bool:
    """Whether ``seq`` holds real cut-out flames (:func:`cutout_library`), not simulated ones."""
    return seq.meta.get("generator") == CUTOUT_GENERATOR


def pick_sequence(
    library: Sequence[SpriteSequence], cfg: FlameLibraryConfig, rng: np.random.Generator
) -> SpriteSequence:
    """One sequence of ``library`` for a flame: uniform (one ``rng.integers`` draw, as every pool made before
    ``source`` existed); with ``cfg.source`` both, first a cut-out sequence with probability ``cfg.cutout_share``
    (else a simulated one; ``rng.random``), then uniform within that group (a group left empty takes the other)."""
    if cfg.source != "both":
        return library[int(rng.integers(len(library)))]
    cut = rng.random() < cfg.cutout_share
    group = [s for s in library if is_cutout(s) == cut] or list(library)
    return group[int(rng.integers(len(group)))]

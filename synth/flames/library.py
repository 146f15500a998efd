"""The flame library a synthetic run draws sprites from: procedural sequences (:mod:`synth.flames.simulate`) made on the
fly, or sequence folders on disk (``fuzzyfire synth flames`` output, ``fuzzyfire synth cutouts`` output, or a
user's RGBA renders), or, with ``source: cutouts``, real flames cut out of labelled images (:mod:`synth.flames.cutouts`),
which the caller supplies (``fuzzyfire experiment`` cuts them from each mixture's own real training images:
:mod:`fuzzyfire.cutout_pools`)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from synth.flames.simulate import GENERATORS, generate_sequence, sample_params
from synth.flames.sprites import SpriteSequence, load_library

#: Where a library's flames come from (``FlameLibraryConfig.source``).
FLAME_SOURCES: tuple[str, ...] = ("simulated", "cutouts")


@dataclass(frozen=True)
class FlameLibraryConfig:
    sequences: int = 12  # procedural sequences to simulate (ignored when ``folders`` is set), >= 1
    generator: Literal["fluid", "noise"] = "fluid"  # fluid (stable fluids) | noise (cheaper)
    frames: int = 240  # simulation steps per sequence, >= 1 (the paper: 1024)
    keep_every: int = 12  # keep one frame every K steps, >= 1 (the paper: 12)
    rare: float = 0.05  # probability per sequence of a chemical-colour flame (blue, copper or boron green), 0..1
    seed: int = 0  # library seed
    folders: tuple[Path, ...] = ()  # sequence folders to load instead of simulating (synth flames / cutouts output)
    source: Literal["simulated", "cutouts"] = "simulated"  # simulated (or folders) | cutouts: each mixture's own
    # real flames (fuzzyfire experiment only: fuzzyfire.cutout_pools)
    texture: float = 0.5  # simulated flames' inner streaks and soft edge (synth.flames.simulate.streaks), [0, 1);
    # 0 = a flat body
    exposed: bool = False  # simulated flames coloured as a camera records fire: white cores, red edges
    # (synth.flames.colour)

    def __post_init__(self) -> None:
        if self.generator not in GENERATORS:
            raise ValueError(f"unknown flame generator {self.generator!r}; choose one of {', '.join(GENERATORS)}")
        if self.sequences < 1 or self.frames < 1 or self.keep_every < 1:
            raise ValueError(
                f"flames.sequences, frames and keep_every must be >= 1, got {self.sequences}, {self.frames}, "
                f"{self.keep_every}"
            )
        if not 0.0 <= self.rare <= 1.0:
            raise ValueError(f"flames.rare must be in 0..1, got {self.rare}")
        if self.source not in FLAME_SOURCES:
            raise ValueError(f"unknown flames.source {self.source!r}; choose one of {', '.join(FLAME_SOURCES)}")
        if not 0.0 <= self.texture < 1.0:
            raise ValueError(f"flames.texture must be in [0, 1), got {self.texture}")
        if self.source == "cutouts" and self.folders:
            raise ValueError("flames.folders are simulated flames' stand-ins: give them with source simulated")


def procedural_library(
    n: int,
    seed: int,
    frames: int,
    keep_every: int,
    rare: float,
    generator: str = "fluid",
    texture: float = 0.0,
    exposed: bool = False,
) -> list[SpriteSequence]:
    """``n`` procedural flame sequences named ``<generator>-<seed>-<k>``; sequence k is drawn from
    ``default_rng([seed, k])`` (a chemical palette with probability ``rare``; inner streaks of depth
    ``texture``, :func:`synth.flames.simulate.streaks`; ``exposed``: the camera-exposed palette,
    :func:`synth.flames.simulate.exposed_gain`, with the same shapes and motion as without it)."""
    seqs = []
    for k in range(n):
        rng = np.random.default_rng([seed, k])
        fixed = {"frames": frames, "keep_every": keep_every, "texture": texture}
        params = sample_params(rng, generator, rare=bool(rng.random() < rare), exposed=exposed, **fixed)
        seqs.append(generate_sequence(f"{generator}-{seed}-{k:03d}", params, rng))
    return seqs


def build_library(cfg: FlameLibraryConfig, cutouts: Sequence[SpriteSequence] = ()) -> list[SpriteSequence]:
    """The sequences ``cfg`` describes: ``source`` simulated: loaded from ``folders`` when given, else simulated;
    cutouts: ``cutouts`` (a ``fuzzyfire synth cutouts`` output read by :func:`synth.flames.sprites.load_library`).
    ValueError when ``cutouts`` are missing for source cutouts or
    given to source simulated."""
    if cfg.source == "simulated" and cutouts:
        raise ValueError("cut-outs given to a flame library whose source is simulated")
    if cfg.source == "cutouts":
        if not cutouts:
            raise ValueError(
                "flames.source cutouts: no cut-outs given (fuzzyfire experiment cuts them from each mixture's real "
                "images; for one pool, cut them with fuzzyfire synth cutouts and give flames.folders)"
            )
        return list(cutouts)
    if cfg.folders:
        return load_library(list(cfg.folders))
    args = (cfg.sequences, cfg.seed, cfg.frames, cfg.keep_every, cfg.rare, cfg.generator, cfg.texture)
    return procedural_library(*args, cfg.exposed)


def pick_sequence(library: Sequence[SpriteSequence], rng: np.random.Generator) -> SpriteSequence:
    """One sequence of ``library`` for a flame, uniform (one ``rng.integers`` draw)."""
    return library[int(rng.integers(len(library)))]


def flame_draws(
    library: Sequence[SpriteSequence], max_flames: int, negatives: float, rng: np.random.Generator
) -> Iterator[tuple[SpriteSequence, int]]:
    """The flames of one image as (sequence, frame index): none with probability ``negatives``, else 1 to
    ``max_flames``, each a uniform sequence of ``library`` and frame of it. Drawn lazily, so the draws a caller
    makes for each flame (its size, its place) come between them in ``rng``'s stream, as when written inline."""
    if rng.random() < negatives:
        return
    for _ in range(int(rng.integers(1, max_flames + 1))):
        seq = pick_sequence(library, rng)
        yield seq, int(rng.integers(len(seq.sprites)))

"""The flame library a synthetic run draws sprites from: procedural sequences (:mod:`synth.flames`) made on the
fly, or sequence folders on disk (``fuzzyfire synth flames`` output, or a user's RGBA renders)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from synth.flames import GENERATORS, generate_sequence, sample_params
from synth.sprites import SpriteSequence, load_library


@dataclass(frozen=True)
class FlameLibraryConfig:
    sequences: int = 12  # procedural sequences to simulate (ignored when ``folders`` is set)
    generator: Literal["fluid", "noise"] = "fluid"
    frames: int = 240  # simulation steps per sequence
    keep_every: int = 12  # keep one frame every K steps
    rare: float = 0.05  # fraction of chemical-colour (rare) flames
    seed: int = 0
    folders: tuple[Path, ...] = ()  # sequence folders to load instead of simulating

    def __post_init__(self) -> None:
        if self.generator not in GENERATORS:
            raise ValueError(f"unknown flame generator {self.generator!r}; choose one of {', '.join(GENERATORS)}")
        if self.sequences < 1 or self.frames < 1 or self.keep_every < 1 or not 0.0 <= self.rare <= 1.0:
            raise ValueError(f"invalid flame library config: {self}")


def procedural_library(
    n: int, seed: int, frames: int, keep_every: int, rare: float, generator: str = "fluid"
) -> list[SpriteSequence]:
    """``n`` procedural flame sequences named ``<generator>-<seed>-<k>``; sequence k is drawn from
    ``default_rng([seed, k])`` (a chemical palette with probability ``rare``)."""
    seqs = []
    for k in range(n):
        rng = np.random.default_rng([seed, k])
        params = sample_params(rng, generator, rare=bool(rng.random() < rare), frames=frames, keep_every=keep_every)
        seqs.append(generate_sequence(f"{generator}-{seed}-{k:03d}", params, rng))
    return seqs


def build_library(cfg: FlameLibraryConfig) -> list[SpriteSequence]:
    """The sequences ``cfg`` describes (loaded from ``folders`` when given, else simulated)."""
    if cfg.folders:
        return load_library(list(cfg.folders))
    return procedural_library(cfg.sequences, cfg.seed, cfg.frames, cfg.keep_every, cfg.rare, cfg.generator)

"""The smoke a Method 2 pool lays: its settings (:class:`SmokeConfig`) and the plume sequences it draws from
(:func:`smoke_library`): simulated plumes (:mod:`synth.smoke.plume`) or, with ``source: cutouts``, the mattes of a
mixture's own labelled smoke (:mod:`synth.smoke.matte`, cut by ``fuzzyfire experiment``: :mod:`fuzzyfire.cutout_pools`).
A run's library holds flames and plumes together; :func:`split_library` parts them by each sequence's kind."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from synth.flames.sprites import SpriteSequence, is_smoke
from synth.schema import check_range
from synth.smoke.plume import plume_library

#: Where a pool's plumes come from (``SmokeConfig.source``).
SMOKE_SOURCES: tuple[str, ...] = ("simulated", "cutouts")


@dataclass(frozen=True)
class SmokeConfig:
    """Smoke plumes laid in a Method 2 image (boxed when the pool boxes smoke: ``smoke_class``; an experiment turns
    that on when smoke is a studied class). Both shares 0 = no plumes of their own (a flame sprite's soot stays)."""

    above: float = 0.0  # share of the flames with a plume rising from their tips, 0..1
    alone: float = 0.0  # probability that an image gets a plume without flames (smouldering, or far away), 0..1
    sky: float = 0.5  # share of the plumes without flames that rise into the view's sky from its horizon, when it
    # has sky (a plume over a ridge; a flame in the sky is not plausible, smoke is), 0..1
    height_m: tuple[float, float] = (1.0, 8.0)  # height of a plume standing on the ground, metres [lo, hi]
    source: Literal["simulated", "cutouts"] = "simulated"  # simulated plumes | cutouts: the mixture's own labelled
    # smoke matted into sprites (fuzzyfire experiment only: fuzzyfire.cutout_pools)
    sequences: int = 12  # simulated plume sequences, >= 1
    frames: int = 8  # frames per simulated sequence, >= 1
    seed: int = 0  # plume library seed

    def __post_init__(self) -> None:
        for name, share in (("above", self.above), ("alone", self.alone), ("sky", self.sky)):
            if not 0.0 <= share <= 1.0:
                raise ValueError(f"smoke.{name} must be in 0..1, got {share}")
        if self.source not in SMOKE_SOURCES:
            raise ValueError(f"unknown smoke.source {self.source!r}; choose one of {', '.join(SMOKE_SOURCES)}")
        if self.sequences < 1 or self.frames < 1:
            raise ValueError(f"smoke.sequences and frames must be >= 1, got {self.sequences}, {self.frames}")
        check_range("smoke.height_m", self.height_m, 0.1)

    @property
    def plumes(self) -> bool:
        """Whether images get plumes of their own."""
        return self.above > 0 or self.alone > 0


def smoke_library(cfg: SmokeConfig, cutouts: Sequence[SpriteSequence] = ()) -> list[SpriteSequence]:
    """The plume sequences of ``cfg``: none without plumes; ``source`` simulated: :func:`synth.smoke.plume.plume_library`;
    cutouts: the smoke sequences among ``cutouts`` (a cut-out folder read by :func:`synth.flames.sprites.load_library`;
    ValueError when it holds none)."""
    if not cfg.plumes:
        return []
    if cfg.source == "simulated":
        return plume_library(cfg.sequences, cfg.seed, cfg.frames)
    smoke = [s for s in cutouts if is_smoke(s)]
    if not smoke:
        raise ValueError(
            "smoke.source cutouts: no smoke cut-outs given (fuzzyfire experiment mattes them from each mixture's "
            "labelled smoke; elsewhere use smoke.source simulated)"
        )
    return smoke


def split_library(library: Sequence[SpriteSequence]) -> tuple[list[SpriteSequence], list[SpriteSequence]]:
    """(flame sequences, smoke sequences) of a run's ``library``, each in its order."""
    return [s for s in library if not is_smoke(s)], [s for s in library if is_smoke(s)]

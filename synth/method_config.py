"""What Method 1 and Method 2 settings share: :class:`MethodConfig`, the frozen dataclass both inherit, and the
typed places a pool is made in (:class:`PoolPlaces`), which the generation loop (:mod:`synth.generate`), the
experiment's stages and its leakage check read from either method's config. A key only Method 2 has (its photos,
labelled frames, shares) is read through :meth:`MethodConfig.places`, never by name with a default, so a renamed key
fails where it is read instead of silently taking a default.
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import ClassVar, TypeVar

from synth.compose.effects import CameraConfig
from synth.flames.library import FlameLibraryConfig
from synth.places.kinds import Places, split_places
from synth.places.scenes import DEFAULT_SCENES
from synth.schema import check_range

C = TypeVar("C", bound="MethodConfig")


@dataclass(frozen=True)
class PoolPlaces:
    """The places of a pool besides procedural rooms, as files or folders: ``environments`` (mesh files,
    sidecars, and for Method 2 2:1 panoramas), ``backgrounds`` (fire-free photos), ``labelled_frames`` (labelled
    datasets whose images keep their fire boxes: :mod:`synth.places.frames`); ``background_holdout``: the share of
    ``backgrounds`` photos (by content) never composited on; ``photo_share`` and ``panorama_share``: the weights
    of photo and panorama views (:func:`synth.places.kinds.kind_weights`). Method 1 has environments only."""

    environments: tuple[Path, ...] = ()
    backgrounds: tuple[Path, ...] = ()
    labelled_frames: tuple[Path, ...] = ()
    background_holdout: float = 0.0
    photo_share: float = 0.0
    panorama_share: float = 0.5

    def split(self) -> Places:
        """``environments`` and ``backgrounds`` sorted into meshes, panoramas and photos
        (:func:`synth.places.kinds.split_places`: reads image headers)."""
        return split_places(self.environments, self.backgrounds)


@dataclass(frozen=True)
class MethodConfig:
    """The settings of a synthetic dataset both methods share (each method's config adds its own keys).
    ``method`` names the method (the ``synth:<method>`` source tag and the ``synth <method>`` command);
    ``composited``: flames are composited on each rendered view, standing on its surfaces, and views may be
    photos and panoramas (Method 2), or are flame planes rendered in the 3D scene (Method 1)."""

    method: ClassVar[str]
    composited: ClassVar[bool]
    bringing_places: ClassVar[str]  # the keys that bring places, for messages

    n: int = 100  # images to write, >= 1
    seed: int = 0  # same seed -> byte-identical dataset
    width: int = 640  # image width, pixels, >= 16
    height: int = 480  # image height, pixels, >= 16
    scenes: int | None = None  # procedural environments (7 families), >= 0; null = 48 unless you bring places of
    # your own (then only those)
    environments: tuple[Path, ...] = ()  # mesh files / folders / sidecar YAMLs (synth.places.envfile) and, Method 2
    # only, 2:1 panoramas, rendered first; with files the views go to the environments in consecutive blocks
    # (synth.places.views)
    images_per_view: int = 1  # images made from each rendered view (different flames), >= 1
    max_flames: int = 3  # flames per image: uniform in 1..max_flames, >= 1
    negatives: float = 0.1  # fraction of images without flames, 0..1
    flame_height_m: tuple[float, float] = (0.3, 2.5)  # flame height in the scene, metres [lo, hi]
    min_box_px: int = 4  # visible flames smaller than this on either side are not annotated, pixels, >= 1
    smoke_class: bool = False  # also annotate smoke (class 'smoke': a sprite's alpha >= 0.25, in Method 2 only its
    # part seen at ΔE 5, synth.compose.visibility); an experiment sets it when smoke is a studied class
    camera: CameraConfig = field(default_factory=CameraConfig)  # probabilities of the stronger camera effects
    flames: FlameLibraryConfig = field(default_factory=FlameLibraryConfig)  # the flame library

    def __post_init__(self) -> None:
        if self.scenes is None:
            object.__setattr__(self, "scenes", 0 if self.brings_places() else DEFAULT_SCENES)
        if self.n < 1 or self.scenes < 0 or self.images_per_view < 1 or self.width < 16 or self.height < 16:
            raise ValueError(
                f"n, images_per_view must be >= 1, scenes >= 0, width and height >= 16; got n {self.n}, "
                f"images_per_view {self.images_per_view}, scenes {self.scenes}, size {self.width}x{self.height}"
            )
        if self.scenes == 0 and not self.brings_places():
            raise ValueError(
                f"scenes is 0 and no {self.bringing_places} given: nothing to "
                f"{'composite on' if self.composited else 'render'}"
            )
        if self.max_flames < 1 or self.min_box_px < 1:
            raise ValueError(f"max_flames and min_box_px must be >= 1, got {self.max_flames}, {self.min_box_px}")
        if not 0.0 <= self.negatives <= 1.0:
            raise ValueError(f"negatives must be in 0..1, got {self.negatives}")
        check_range("flame_height_m", self.flame_height_m, 0.01)

    def places(self) -> PoolPlaces:
        """The places of this config (Method 1: its environments; Method 2 overrides with its photos too)."""
        return PoolPlaces(self.environments)

    def brings_places(self) -> bool:
        """Whether the config names places of its own (then ``scenes: null`` renders no procedural room)."""
        return bool(self.environments)

    def place_keys(self) -> tuple[str, ...]:
        """The keys naming files or folders of places: every ``tuple[Path, ...]`` field (a path in them is
        relative to the config's folder; a pool is identified by their content, not their paths)."""
        hints = typing.get_type_hints(type(self))
        return tuple(f.name for f in dataclasses.fields(self) if hints[f.name] == tuple[Path, ...])

    def with_paths(self: C, where: Callable[[Path], Path]) -> C:
        """This config with every path of :meth:`place_keys` replaced by ``where(path)`` (e.g. made absolute)."""
        return replace(self, **{key: tuple(where(Path(p)) for p in getattr(self, key)) for key in self.place_keys()})

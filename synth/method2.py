"""Method 2: render each camera view of a procedural environment once, then composite flame sprites onto it
many times; each flame's box is the box of its final visible mask (after clipping, truncation and occlusion),
restricted to the pixels whose contrast a person would notice (:mod:`synth.compose.visibility`); a flame with too few
such pixels is erased from the image (composited again without it), so no visible flame goes unboxed.

Smoke (``smoke``: :mod:`synth.smoke`): plumes above flames or alone, laid before the flames. When the pool boxes
smoke (``smoke_class``), each plume's and each flame sprite's smoke is judged like a flame at the smoke threshold
(:data:`synth.compose.visibility.SMOKE_DELTA_E`): its box is its seen part, and smoke too faint to see is erased (a
plume is dropped, a flame's soot taken off its sprite), never left unboxed. Plumes draw from their own
``default_rng([seed, 2, i, 3])``.

Image ``i`` uses view ``i // images_per_view`` (on a photo, a photo view of its own: see :mod:`synth.places.views`) and
its own rng ``default_rng([seed, 2, i])``, so any image can be (re)made alone: runs resume and are byte-reproducible.
Auto exposure draws from ``default_rng([seed, 2, i, 2])`` (:func:`metering`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import ClassVar, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ground.data.boxes import mask_to_xywh, xywh_overlaps_any
from synth.compose.composite import BLEND_MODES, Composited, Placement, composite
from synth.compose.effects import Effects, apply_effects, expose, sample_effects, scale_light
from synth.compose.metering import draw_radiance, flame_share, mean_linear_luma, metered_gain
from synth.compose.visibility import SMOKE_DELTA_E, Visibility, delta_e, measure
from synth.flames.library import flame_draws
from synth.flames.sprites import Sprite, SpriteSequence, flame_extent
from synth.method_config import MethodConfig, PoolPlaces
from synth.places import render
from synth.places.views import ViewCache
from synth.smoke.library import SmokeConfig, split_library
from synth.smoke.placement import Plume, plan_plumes
from synth.staging import boxes_from_masks

SITE_MAX_HEIGHT = 0.6  # tallest flame on a photo or panorama site, fraction of the image height
#: A flame's luminous coverage of what is behind its body, drawn per flame in this range (1 = hides it; a more
#: see-through 0.5-0.95 moved the flame gap away from real fire: docs/findings.md, "Does the flame look matter?").
FLAME_OPACITY = (0.85, 1.0)
#: The halo and warm cast a flame spills around its base, drawn per flame in this range (synth.compose.composite).
FLAME_GLOW = (0.1, 0.5)


@dataclass(frozen=True)
class Method2Config(MethodConfig):
    """Method 2 settings (``configs/synth-method2.yaml`` lists every key; ``docs/config.md`` is generated from
    here; the keys both methods share: :class:`synth.method_config.MethodConfig`). ``flames`` describes the library
    a command builds with :func:`synth.flames.library.build_library`; the manifest records the sequences used."""

    method: ClassVar[str] = "method2"
    composited: ClassVar[bool] = True
    bringing_places: ClassVar[str] = "environments, backgrounds, labelled_frames or own_frames are"

    backgrounds: tuple[Path, ...] = ()  # fire-free photos (files / folders) composited on; 2:1 ones are panoramas
    labelled_frames: tuple[Path, ...] = ()  # labelled datasets composited on like photos, each image keeping its
    # own fire boxes, no flame placed over them (synth.places.frames): e.g. your cameras' frames
    own_frames: float = 0.0  # experiment only: share of an own pool's views on its mixture's real training images
    # (fuzzyfire.cutout_pools; they become the pool's labelled_frames), 0..1; 0 = none
    photo_share: float = 0.5  # share of views on a photo (or labelled frame) when 3D scenes are also used, 0..1
    background_holdout: float = 0.0  # share of the photos (by content hash) never composited on: test data, [0, 1);
    # in an experiment, set by the holdout of the test set on the same folder (docs/experiments.md)
    panorama_share: float = 0.5  # weight of panorama views beside photos and renders, 0..1
    images_per_view: int = 8  # images composited on each rendered or panorama view (render once, composite many
    # times), >= 1; each image on a photo or labelled frame has a crop of its own (synth.places.views)
    photo_negatives: float | None = None  # fraction of the images on a fire-free photo (``backgrounds``) without
    # flames: hard negatives of your own kind, 0..1; null = negatives (labelled frames and other places keep that)
    auto_exposure: bool = False  # the camera meters each frame with its flames in view: bright flames lower the
    # exposure of the scene around them (synth.compose.metering)
    smoke: SmokeConfig = field(default_factory=SmokeConfig)  # smoke plumes above flames and alone (synth.smoke)

    def __post_init__(self) -> None:
        super().__post_init__()
        for name, share in (("own_frames", self.own_frames), ("photo_share", self.photo_share),
                            ("panorama_share", self.panorama_share)):  # fmt: skip
            if not 0.0 <= share <= 1.0:
                raise ValueError(f"{name} must be in 0..1, got {share}")
        if not 0.0 <= self.background_holdout < 1.0:
            raise ValueError(f"background_holdout must be in 0..1 (exclusive), got {self.background_holdout}")
        if self.photo_negatives is not None and not 0.0 <= self.photo_negatives <= 1.0:
            raise ValueError(f"photo_negatives must be in 0..1 or null, got {self.photo_negatives}")
        if self.photo_negatives is not None and not self.backgrounds and not self.own_frames:
            raise ValueError(
                "photo_negatives is the share of the backgrounds photos left without flames: give backgrounds"
            )

    def places(self) -> PoolPlaces:
        return PoolPlaces(self.environments, self.backgrounds, self.labelled_frames, self.background_holdout,
                          self.photo_share, self.panorama_share)  # fmt: skip

    def brings_places(self) -> bool:  # own_frames: the experiment adds the mixture's images as labelled frames
        return bool(self.environments or self.backgrounds or self.labelled_frames or self.own_frames > 0)

    @property
    def lays_flames(self) -> bool:
        """Whether an image of the pool may get a flame: ``negatives`` below 1, or ``photo_negatives`` below 1 with
        ``backgrounds`` photos to lay them on."""
        on_photos = self.photo_negatives is not None and self.photo_negatives < 1.0 and bool(self.backgrounds)
        return self.negatives < 1.0 or on_photos


def plan_flames(
    cfg: Method2Config,
    library: Sequence[SpriteSequence],
    depth: NDArray[np.float32],
    yfov: float,
    rng: np.random.Generator,
    avoid: Sequence[Sequence[int]] | None = None,
    negatives: float | None = None,
) -> list[tuple[Placement, str]]:
    """Random flames standing at random pixels, sized by the scene depth there (world height in metres of the flame
    itself, its mask: the sprite, smoke included, is scaled to match); on a site (``avoid`` given: a photo,
    panorama or room, :mod:`synth.places.sites`) only at pixels whose depth is > 0 (the ground) and never over the
    ``avoid`` boxes [x, y, w, h] (:func:`kept_clear`). No flame (an empty list) with probability ``negatives``
    (default ``cfg.negatives``; per view: :func:`negative_share`)."""
    fy = render.intrinsics(yfov, cfg.width, cfg.height)[1, 1]
    out = []
    for seq, frame in flame_draws(library, cfg.max_flames, cfg.negatives if negatives is None else negatives, rng):
        sprite = seq.sprites[frame]
        if avoid is not None:
            spot = site_spot(depth, fy, flame_extent(sprite), cfg, avoid, rng)
            if spot is None:
                continue
            bx, by, hpx = spot
        else:
            bx, by = int(rng.integers(0, cfg.width)), int(rng.integers(cfg.height // 3, cfg.height))
            d = float(depth[min(by, cfg.height - 1), bx]) or 10.0
            hpx = int(np.clip(fy * rng.uniform(*cfg.flame_height_m) / d, 12, 0.9 * cfg.height))
        wpx, spx = sprite_pixels(sprite, hpx)
        out.append((drawn_placement(sprite, (bx - wpx // 2, by - spx, wpx, spx), rng), f"{seq.name}/{frame}"))
    return out


def drawn_placement(sprite: Sprite, rect: tuple[int, int, int, int], rng: np.random.Generator) -> Placement:
    """``sprite`` placed at ``rect`` (x, y, width, height) image pixels with its blend (screen or add), glow
    (:data:`FLAME_GLOW`) and opacity (:data:`FLAME_OPACITY`) drawn from ``rng`` in that order; its dim edge never
    darkens the background (:mod:`synth.compose.composite`)."""
    blend = str(rng.choice(BLEND_MODES))
    glow, opacity = float(rng.uniform(*FLAME_GLOW)), float(rng.uniform(*FLAME_OPACITY))
    return Placement(sprite, *rect, blend, glow, opacity, True, never_darken=True)


def sprite_pixels(sprite: Sprite, flame_px: int) -> tuple[int, int]:
    """(width, height) in image pixels of ``sprite`` scaled so that its flame is ``flame_px`` high."""
    sw, sh = sprite.size
    scale = flame_px / flame_extent(sprite)[1]
    return max(int(round(sw * scale)), 2), max(int(round(sh * scale)), 2)


def site_spot(
    depth: NDArray[np.float32],
    fy: float,
    flame_size: tuple[int, int],
    cfg: Method2Config,
    avoid: Sequence[Sequence[int]],
    rng: np.random.Generator,
    tries: int = 10,
) -> tuple[int, int, int] | None:
    """(base x, base y, height px) of a flame (its mask box ``flame_size`` (w, h) in any unit: only the ratio
    counts) standing on a ground pixel (depth > 0), sized by its depth, no taller than :data:`SITE_MAX_HEIGHT` of
    the image (a spot nearer than that is redrawn: 95 % of fire-cctv-416's boxes are lower), its box
    (:func:`flame_box`) overlapping none of ``avoid`` ([x, y, w, h] px); None when ``tries`` draws find none."""
    ground = np.flatnonzero(depth > 0)
    if not len(ground):
        return None
    for _ in range(tries):
        by, bx = divmod(int(ground[rng.integers(len(ground))]), cfg.width)
        hpx = max(int(fy * rng.uniform(*cfg.flame_height_m) / float(depth[by, bx])), 12)
        if hpx <= SITE_MAX_HEIGHT * cfg.height and not xywh_overlaps_any(flame_box(bx, by, hpx, flame_size), avoid):
            return bx, by, hpx
    return None


def flame_box(bx: int, by: int, hpx: int, flame_size: tuple[int, int]) -> list[int]:
    """[x, y, w, h] pixels of a flame standing at base (bx, by), ``hpx`` high, shaped like ``flame_size`` (w, h in
    any unit): the box :func:`site_spot` keeps clear of what it avoids."""
    wpx = max(int(round(hpx * flame_size[0] / flame_size[1])), 2)
    return [bx - wpx // 2, by - hpx, wpx, hpx]


def kept_clear(meta: dict) -> list:
    """Boxes [x, y, w, h] of a view where no flame may go: a photo site's people and a labelled frame's own fires
    (:mod:`synth.places.frames`)."""
    return [*meta.get("people", []), *meta.get("frame_boxes", [])]


class Shown(NamedTuple):
    """What :func:`visible_composite` kept: the camera's ``image`` (H, W, 3) uint8, the ``result`` composite (plumes'
    layers first, then the flames'), the ``flames`` kept (a sublist of the planned ones, soot taken off where it was
    too faint) and their ``seen`` :class:`~synth.compose.visibility.Visibility`, the ``plumes`` kept, and ``smoke``:
    per layer of ``result`` the visibility of its smoke (None: no smoke, or smoke not judged)."""

    image: NDArray[np.uint8]
    result: Composited
    flames: list[tuple[Placement, str]]
    seen: list[Visibility]
    plumes: list[Plume]
    smoke: list[Visibility | None]


def _boxable(v: Visibility | None, min_box_px: int) -> bool:
    return v is not None and v.visible and min(mask_to_xywh(v.part)[2:]) >= min_box_px


def without_smoke(p: Placement) -> Placement:
    """``p`` whose sprite's smoke layer is erased (a flame's soot too faint to see)."""
    return replace(p, sprite=replace(p.sprite, over=np.zeros_like(p.sprite.over)))


def visible_composite(
    scene: NDArray[np.uint8],
    planned: Sequence[tuple[Placement, str]],
    effects,
    min_box_px: int,
    meter: Callable[[NDArray[np.uint8], list[Placement]], NDArray[np.uint8]] | None = None,
    plumes: Sequence[Plume] = (),
    judge_smoke: bool = False,
) -> Shown:
    """Composite ``plumes`` then ``planned`` flames on the exposed ``scene`` and take it through the camera
    (``effects``), erasing every flame that cannot be seen (:mod:`synth.compose.visibility`: contrast against the
    plate, the scene through the same camera without flames) or whose seen part is smaller than ``min_box_px``, and
    compositing again without it until every flame left is seen (erasing one can unhide another). With
    ``judge_smoke`` the smoke is judged the same way at the smoke threshold: an unseen plume is dropped, a flame's
    unseen soot erased. ``meter(scene, placements)``: the scene as the camera exposes it with those flames in view
    (:mod:`synth.compose.metering`; the plate is that scene too), redone for the flames left after each erasure."""
    plate = apply_effects(scene, effects) if meter is None else None
    shown, kept_plumes = list(planned), list(plumes)
    while True:
        lit = scene if meter is None else meter(scene, [p for p, _ in shown])
        if meter is not None:
            plate = apply_effects(lit, effects)
        result = composite(lit, [q.placement for q in kept_plumes] + [p for p, _ in shown])
        image = apply_effects(result.image, effects)
        delta = delta_e(image, plate)
        first = len(kept_plumes)
        seen = [measure(delta, m) for m in result.flames[first:]]
        smoke = [measure(delta, m, SMOKE_DELTA_E) if judge_smoke and m.any() else None for m in result.smoke]
        keep = [k for k, v in enumerate(seen) if _boxable(v, min_box_px)]
        plumes_kept = [q for q, v in zip(kept_plumes, smoke) if not judge_smoke or _boxable(v, min_box_px)]
        faint = {k for k in keep if smoke[first + k] is not None and not _boxable(smoke[first + k], min_box_px)}
        if len(keep) == len(shown) and len(plumes_kept) == len(kept_plumes) and not faint:
            return Shown(image, result, shown, seen, kept_plumes, smoke)
        shown = [(without_smoke(shown[k][0]) if k in faint else shown[k][0], shown[k][1]) for k in keep]
        kept_plumes = plumes_kept


def negative_share(cfg: Method2Config, view_meta: dict) -> float:
    """The probability that an image on the view of ``view_meta`` gets no flame: ``cfg.photo_negatives`` on a
    fire-free photo (a ``backgrounds`` photo, not a labelled frame) when set, else ``cfg.negatives``."""
    photo = "photo" in view_meta and "frame_boxes" not in view_meta
    return cfg.photo_negatives if photo and cfg.photo_negatives is not None else cfg.negatives


@dataclass(frozen=True)
class Meter:
    """A camera's auto exposure for one image's scene (:mod:`synth.compose.metering`): the scene's ``mean`` linear
    luminance (read once), its flames' ``radiance``; called with the scene and the placements in view, returns the
    scene at the exposure it meters."""

    radiance: float
    mean: float
    width: int
    height: int

    def gain(self, placements: Sequence[Placement]) -> float:
        share = flame_share(placements, self.width, self.height)
        return metered_gain(self.mean, share, self.radiance) if share else 1.0

    def __call__(self, scene: NDArray[np.uint8], placements: list[Placement]) -> NDArray[np.uint8]:
        return scale_light(scene, self.gain(placements))


def metering(cfg: Method2Config, i: int, scene: NDArray[np.uint8]) -> Meter:
    """Image ``i``'s :class:`Meter` of ``scene``, its radiance drawn from its own rng ``default_rng([seed, 2, i, 2])``
    (turning ``auto_exposure`` on keeps every other draw)."""
    radiance = draw_radiance(np.random.default_rng([cfg.seed, 2, i, 2]))
    return Meter(radiance, mean_linear_luma(scene), scene.shape[1], scene.shape[0])


def make_image(cfg: Method2Config, i: int, library: Sequence[SpriteSequence], views: ViewCache):
    """Image ``i``: ((H, W, 3) uint8, kept fire masks, record dict (boxes xywh, metadata), kept smoke masks or
    None when smoke is not a class). A flame nobody could see is erased, not left unboxed
    (:func:`visible_composite`); a kept flame's mask and box are its seen part."""
    background, depth, view_meta = views.image_background(i, cfg.images_per_view)
    flame_library, plume_library = split_library(library)
    rng = np.random.default_rng([cfg.seed, 2, i])
    avoid = kept_clear(view_meta) if view_meta.get("site") else None
    yfov = view_meta["camera"]["yfov"]
    planned = plan_flames(cfg, flame_library, depth, yfov, rng, avoid, negative_share(cfg, view_meta))
    effects: Effects = sample_effects(rng, cfg.camera)
    scene = expose(background, effects)
    meter = metering(cfg, i, scene) if cfg.auto_exposure else None
    plumes = []
    if cfg.smoke.plumes and plume_library:
        fy = float(render.intrinsics(yfov, cfg.width, cfg.height)[1, 1])
        smoke_rng = np.random.default_rng([cfg.seed, 2, i, 3])
        labelled = [*view_meta.get("frame_boxes", []), *view_meta.get("frame_smoke_boxes", [])]  # no plume over them
        plumes = plan_plumes(cfg.smoke, plume_library, [p for p, _ in planned], scene, depth, fy, smoke_rng, labelled)
    shown = visible_composite(scene, planned, effects, cfg.min_box_px, meter, plumes, cfg.smoke_class)
    kept, boxes, index = boxes_from_masks([v.part for v in shown.seen], cfg.min_box_px)
    flames = [flame_record(shown.flames[k][0], shown.flames[k][1], shown.seen[k]) for k in index]
    meta = {**view_meta, "flames": flames, "erased": len(planned) - len(shown.flames), "effects": effects.to_json()}
    if plumes:
        meta["plumes"] = [q.record() for q in shown.plumes]
        meta["plumes_erased"] = len(plumes) - len(shown.plumes)
    if meter is not None:
        meta["exposure_gain"] = round(meter.gain([p for p, _ in shown.flames]), 4)
    boxes += view_meta.get("frame_boxes", [])  # a labelled frame's own fires, after the flames (no mask: audit)
    record = {"width": cfg.width, "height": cfg.height, "boxes": boxes, "meta": meta}
    if not cfg.smoke_class:
        return shown.image, kept, record, None
    parts = [v.part for v in shown.smoke if v is not None]
    smoke, record["smoke_boxes"], _ = boxes_from_masks(parts, cfg.min_box_px)
    record["smoke_boxes"] += view_meta.get("frame_smoke_boxes", [])  # a frame's own smoke, last (no mask: audit)
    return shown.image, kept, record, smoke


def flame_record(p: Placement, name: str, seen) -> dict:
    """A kept flame in the manifest: sprite, blend, glow, opacity, contrast, seen share."""
    return {
        "flame": name,
        "blend": p.blend,
        "glow": round(p.glow, 4),
        "opacity": round(p.opacity, 4),
        "contrast": round(seen.contrast, 2),
        "seen": round(seen.seen / max(seen.pixels, 1), 4),
    }

"""Method 2: render each camera view of a procedural environment once, then composite flame sprites onto it
many times; each flame's box is the box of its final visible mask (after clipping, truncation and occlusion),
restricted to the pixels whose contrast a person would notice (:mod:`synth.visibility`); a flame with too few
such pixels is erased from the image (composited again without it), so no visible flame goes unboxed.

Image ``i`` uses view ``i // images_per_view`` (on a photo, a photo view of its own: see :mod:`synth.views`) and
its own rng ``default_rng([seed, 2, i])``, so any image can be (re)made alone: runs resume and are byte-reproducible.
Distractors (:mod:`synth.distractors`), decoy pastes (:mod:`synth.decoys`) and the flames' paste edges and looks
(:mod:`synth.blend`) draw from a second rng, ``default_rng([seed, 2, i, 1])``: turning them on keeps the flames,
views and camera effects of every image, and the default config draws nothing from it. Auto exposure draws from
``default_rng([seed, 2, i, 2])`` (:func:`metering`), ``flame_jitter`` from ``default_rng([seed, 2, i, 3])`` (:func:`varied`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from curate.core.boxes import mask_to_xywh
from synth import render
from synth.blend import BlendConfig, sample_style
from synth.composite import Placement, composite, scaled_layers
from synth.decoys import plan_decoys
from synth.distractors import DistractorConfig, draw_distractors, overlaps, plan_distractors
from synth.effects import CameraConfig, Effects, apply_effects, expose, sample_effects, scale_light
from synth.generate import generate
from synth.groups import group_index, grouped
from synth.jitter import draw_jitter, jittered, stretched_width
from synth.library import FlameLibraryConfig, is_cutout, pick_sequence
from synth.metering import draw_radiance, flame_share, mean_linear_luma, metered_gain
from synth.photo_regions import Region
from synth.schema import check_range, check_streets
from synth.sprites import Sprite, SpriteSequence, flame_extent, flame_rect, mask_span
from synth.staging import boxes_from_masks
from synth.swap import best_fit, erased, spanning
from synth.views import ViewCache
from synth.visibility import delta_e, measure

SITE_MAX_HEIGHT = 0.6  # tallest flame on a photo or panorama site, fraction of the image height
ANCHOR_FOOT = 0.06  # a frame-anchored flame's foot: within this fraction of the image height of its fire's foot
ANCHOR_SCALE = (0.6, 1.5)  # its height: this range (log-uniform) times its fire's box height


@dataclass(frozen=True)
class Method2Config:
    """Method 2 settings (``configs/synth-method2.yaml`` documents every key). ``flames`` describes the library
    a command builds with :func:`synth.library.build_library`; the manifest records the sequences used."""

    n: int = 100  # images
    seed: int = 0
    width: int = 640
    height: int = 480
    scenes: int = 48  # procedural environments (0 = only the files of ``environments``)
    environments: tuple[Path, ...] = ()  # mesh files / folders / sidecars (synth.envfile), rendered first; with
    # files the views go to the environments in consecutive blocks (synth.views)
    streets: int = 0  # procedural streets laid out from building kits (synth.streets), after the files; 0 = none
    kits: tuple[Path, ...] = ()  # kit folders (synth.kits), or folders of them, for the streets
    backgrounds: tuple[Path, ...] = ()  # fire-free photos (files / folders) composited on instead of renders
    frames: tuple[Path, ...] = ()  # labelled datasets whose images are photos keeping their fire boxes (synth.frames)
    own_frames: float = 0.0  # experiment: share of an own pool's views on its mixture's real training images
    # (fuzzyfire.cutout_pools; they become the pool's frames); 0 = none
    photo_share: float = 0.5  # fraction of views on a photo (or frame) when there are also 3D environments
    background_holdout: float = 0.0  # share of the photos (chosen by content hash) never composited on: test data
    panorama_share: float = 0.5  # weight of panorama views (environments that are 2:1 images) beside photos and renders
    stand: Literal["surfaces", "anywhere"] = "surfaces"  # renders: flames stand on up-facing surfaces (floors, tables:
    # synth.standing), or anywhere in the lower 2/3 (pools made before this key)
    images_per_view: int = 8  # images composited on each rendered or panorama view (each image on a photo or frame
    # has a crop of its own: synth.views)
    max_flames: int = 3  # flames per image: uniform in 1..max_flames
    negatives: float = 0.1  # fraction of images without flames
    photo_negatives: float | None = None  # fraction of the images on a fire-free photo (``backgrounds``) without
    # flames: hard negatives of the user's own kind; None = ``negatives`` (frames and other places keep that)
    flame_height_m: tuple[float, float] = (0.3, 2.5)  # flame height in the scene, metres
    frame_swap: float = 0.0  # share of the images on a labelled frame (frames, own_frames) whose own fires are
    # erased and other flames of the library drawn in their boxes (synth.swap); 0 = frames keep their fires
    frame_anchored: bool = False  # on a labelled frame with fires, each flame stands where one of the frame's fires
    # stands (its foot within 6 % of the image height of that fire's foot) and is sized like it (0.6-1.5x its
    # height): :func:`anchored_spot`; off = placed by the frame's estimated ground like a photo's (pools made before)
    separate_flames: bool = False  # on a site (photo, frame, panorama) each flame keeps clear of the flames placed
    # before it: no two flames' mask boxes overlap, one that would is not drawn (5 % of fire-cctv-416's train box
    # pairs in an image overlap, 20 % of a cut-out pool's flame pairs did); off = pools made before this key
    flame_jitter: bool = False  # each flame mirrored or not, its width stretched 0.75-1.33x, hue and saturation
    # turned a little (synth.jitter): one cut-out pasted twice is two flames; off = pools made before this key
    flame_heights: Literal["uniform", "log"] = "uniform"  # how a height is drawn in flame_height_m: uniform in metres
    # (pools made before this key), or uniform in its logarithm (as many 0.3-0.9 m flames as 0.9-2.5 m: more small,
    # far flames, like the common set's boxes, whose heights in pixels are about log-uniform: :func:`flame_height`)
    flame_opacity: tuple[float, float] = (0.85, 1.0)  # luminous coverage of a flame's body (1 = hides what is behind)
    flame_glow: tuple[float, float] = (0.1, 0.5)  # halo and warm cast a flame spills (synth.composite), per flame
    closeup: float = 0.0  # fraction of fire images framed as a close-up: one flame of closeup_height x the image
    closeup_height: tuple[float, float] = (0.4, 1.0)  # close-up flame height, fraction of the image height
    min_box_px: int = 4  # visible flames smaller than this (either side) are dropped
    cutout_max_upscale: float | None = None  # a real cut-out is never drawn larger than this x its own pixels
    # (its height drawn by depth is capped: no blurred blob from a 15 px flame); None = no cap
    cutout_box: Literal["mask", "source"] = "mask"  # a real cut-out flame's box: its seen flame pixels (mask), or
    # the annotator's box it was cut from, moved and scaled with it (source: :func:`source_box`); simulated: mask
    smoke_class: bool = False
    light: bool = True  # flames light their surroundings (a warm cast around each flame)
    auto_exposure: bool = False  # the camera meters the frame with its flames: bright flames lower the exposure of
    # the scene around them (synth.metering); off = the photo's own exposure (pools made before this key)
    never_darken: bool = False  # a flame's dim edge reddens a bright background, never outlines it darker (composite)
    opaque_body: bool = False  # with never_darken: the flame's bright body still hides a bright background (no pale
    # translucent film over a sunlit wall or road); only the dim edge keeps never_darken's cap (composite)
    camera: CameraConfig = field(default_factory=CameraConfig)  # probabilities of the stronger camera effects
    flames: FlameLibraryConfig = field(default_factory=FlameLibraryConfig)
    blend: BlendConfig = field(default_factory=BlendConfig)  # how flames are blended (synth.blend); decoy pastes
    distractors: DistractorConfig = field(default_factory=DistractorConfig)  # fire-like things, no box

    def __post_init__(self) -> None:
        if self.n < 1 or self.scenes < 0 or self.images_per_view < 1 or self.width < 16 or self.height < 16:
            raise ValueError(f"invalid Method 2 config: {self}")
        places = self.environments or self.backgrounds or self.frames or self.streets or self.own_frames > 0
        if self.scenes == 0 and not places:  # own_frames: the experiment adds the mixture's images as frames
            raise ValueError(
                "scenes is 0 and no environments, streets, backgrounds, frames or own_frames are given: nothing to "
                "composite on"
            )
        if not 0.0 <= self.own_frames <= 1.0:
            raise ValueError(f"own_frames must be in 0..1, got {self.own_frames}")
        if not 0.0 <= self.frame_swap <= 1.0:
            raise ValueError(f"frame_swap must be in 0..1, got {self.frame_swap}")
        check_streets(self.streets, self.kits)
        if not 0.0 <= self.background_holdout < 1.0:
            raise ValueError(f"background_holdout must be in 0..1 (exclusive), got {self.background_holdout}")
        if self.cutout_max_upscale is not None and self.cutout_max_upscale < 0.1:
            raise ValueError(f"cutout_max_upscale must be >= 0.1 or null, got {self.cutout_max_upscale}")
        if self.cutout_box not in ("mask", "source"):
            raise ValueError(f"cutout_box must be mask or source, got {self.cutout_box!r}")
        if self.stand not in ("surfaces", "anywhere"):
            raise ValueError(f"stand must be surfaces or anywhere, got {self.stand!r}")
        if not 0.0 <= self.panorama_share <= 1.0:
            raise ValueError(f"panorama_share must be in 0..1, got {self.panorama_share}")
        if not 0.0 <= self.photo_share <= 1.0:
            raise ValueError(f"photo_share must be in 0..1, got {self.photo_share}")
        if self.max_flames < 1 or not 0.0 <= self.negatives <= 1.0 or self.min_box_px < 1:
            raise ValueError(f"invalid Method 2 config: {self}")
        if self.distractors.photo and not self.backgrounds:
            raise ValueError(
                f"distractors of kind {', '.join(self.distractors.photo_kinds)} are cut from the pool's fire-free "
                "photos: give backgrounds"
            )
        if self.photo_negatives is not None and not 0.0 <= self.photo_negatives <= 1.0:
            raise ValueError(f"photo_negatives must be in 0..1 or null, got {self.photo_negatives}")
        check_range("flame_height_m", self.flame_height_m, 0.01)
        if self.flame_heights not in ("uniform", "log"):
            raise ValueError(f"flame_heights must be uniform or log, got {self.flame_heights!r}")
        check_range("closeup_height", self.closeup_height, 0.05)
        check_range("flame_glow", self.flame_glow, 0.0)
        if not 0.0 <= self.closeup <= 1.0:
            raise ValueError(f"closeup must be in 0..1, got {self.closeup}")
        if not 0.0 <= self.flame_opacity[0] <= self.flame_opacity[1] <= 1.0:
            raise ValueError(f"flame_opacity must be a range in 0..1, got {self.flame_opacity}")


def plan_flames(
    cfg: Method2Config,
    library: Sequence[SpriteSequence],
    depth: NDArray[np.float32],
    yfov: float,
    rng: np.random.Generator,
    avoid: Sequence[Sequence[int]] | None = None,
    negatives: float | None = None,
    anchors: Sequence[Sequence[float]] = (),
) -> list[tuple[Placement, str]]:
    """Random flames standing at random pixels, sized by the scene depth there (world height in metres of the flame
    itself, its mask: the sprite, smoke included, is scaled to match); on a
    site (``avoid`` given: a photo or panorama, :mod:`synth.sites`) only at pixels whose depth is > 0 (the ground)
    and never over the ``avoid`` boxes [x, y, w, h] (:func:`kept_clear`); or,
    for a ``cfg.closeup`` share of the fire images, one flame filling ``cfg.closeup_height`` of the frame with
    its base near the bottom edge (a fire seen from close by; the part outside the frame is cut off). On a site with
    ``cfg.frame_anchored`` and a labelled frame's fire boxes as ``anchors`` ([x, y, w, h] px) a flame stands where
    one of them stands, sized like it (:func:`anchored_spot`; by the ground as on a photo when none fits). With
    ``cfg.separate_flames`` each flame also keeps clear of the flames before it (:func:`mask_box`). With
    ``cfg.flames.cutout_groups`` a real cut-out brings the other cut-outs of its image (:func:`synth.groups.grouped`;
    beyond ``max_flames``, none over ``avoid``). No flame (an empty list) with probability ``negatives`` (default
    ``cfg.negatives``; per view: :func:`negative_share`)."""
    if rng.random() < (cfg.negatives if negatives is None else negatives):
        return []
    closeup = cfg.closeup > 0 and rng.random() < cfg.closeup
    fy = render.intrinsics(yfov, cfg.width, cfg.height)[1, 1]
    keep_clear = list(avoid) if avoid is not None else None  # grows by each flame with separate_flames
    taken: list[list[int]] = []  # the flames' mask boxes so far (separate_flames)
    groups = group_index(library) if cfg.flames.cutout_groups else None
    out = []
    for _ in range(1 if closeup else int(rng.integers(1, cfg.max_flames + 1))):
        seq = pick_sequence(library, cfg.flames, rng)
        frame = int(rng.integers(len(seq.sprites)))
        sprite = seq.sprites[frame]
        flame_size = flame_extent(sprite)
        if closeup:
            bx, by = int(rng.integers(cfg.width // 4, 3 * cfg.width // 4 + 1)), int(cfg.height * rng.uniform(0.85, 1.1))
            hpx = int(round(cfg.height * rng.uniform(*cfg.closeup_height)))
        elif avoid is not None:
            spot = anchored_spot(anchors, flame_size, cfg, keep_clear, rng) if cfg.frame_anchored and anchors else None
            spot = spot or site_spot(depth, fy, flame_size, cfg, keep_clear, rng)
            if spot is None:
                continue
            bx, by, hpx = spot
        else:
            bx, by = int(rng.integers(0, cfg.width)), int(rng.integers(cfg.height // 3, cfg.height))
            d = float(depth[min(by, cfg.height - 1), bx]) or 10.0
            hpx = int(np.clip(fy * flame_height(cfg, rng) / d, 12, 0.9 * cfg.height))
        hpx = capped_height(cfg, seq, sprite, hpx)
        wpx, spx = sprite_pixels(sprite, hpx)
        place = drawn_placement(cfg, sprite, (bx - wpx // 2, by - spx, wpx, spx), rng)
        if cfg.separate_flames and keep_clear is not None:
            box = mask_box(place)
            if overlaps(box, taken):  # site_spot's box is centred on the base; a sprite's flame may not be
                continue
            taken.append(box)
            keep_clear.append(box)
        if groups is None:
            out.append((place, f"{seq.name}/{frame}"))
        else:  # the anchor, then the rest of its image's fire, none over what the view keeps clear
            first, *rest = grouped(place, f"{seq.name}/{frame}", groups, cfg.width, cfg.height)
            out += [first, *(m for m in rest if not overlaps(mask_box(m[0]), avoid or ()))]
    return out


def drawn_placement(
    cfg: Method2Config, sprite: Sprite, rect: tuple[int, int, int, int], rng: np.random.Generator
) -> Placement:
    """``sprite`` placed at ``rect`` (x, y, width, height) image pixels with its blend, glow and opacity drawn from
    ``rng`` in that order (one ``choice`` of ``cfg.blend.modes``, then two ``uniform`` draws: the draws of pools
    made before), and ``cfg``'s light, never-darken and opaque-body settings."""
    blend = str(rng.choice(cfg.blend.modes))  # (screen, add) by default
    glow, opacity = float(rng.uniform(*cfg.flame_glow)), float(rng.uniform(*cfg.flame_opacity))
    return Placement(
        sprite, *rect, blend, glow, opacity, cfg.light, never_darken=cfg.never_darken, opaque_body=cfg.opaque_body
    )


def flame_height(cfg: Method2Config, rng: np.random.Generator) -> float:
    """A flame's height in the scene, metres, in ``cfg.flame_height_m``: uniform, or log-uniform when
    ``cfg.flame_heights`` is ``log``; one draw from ``rng`` either way (the other draws of a pool stay put)."""
    lo, hi = cfg.flame_height_m
    if cfg.flame_heights == "log":
        return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    return float(rng.uniform(lo, hi))


def capped_height(cfg: Method2Config, seq: SpriteSequence, sprite: Sprite, flame_px: int) -> int:
    """``flame_px``, the height in image pixels drawn for a flame, capped for a real cut-out at
    ``cfg.cutout_max_upscale`` x the height of its flame in its own pixels (never below 2); as drawn otherwise."""
    if cfg.cutout_max_upscale is None or not is_cutout(seq):
        return flame_px
    return max(min(flame_px, int(cfg.cutout_max_upscale * flame_extent(sprite)[1])), 2)


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
    counts) standing on a ground pixel (depth > 0), sized by its depth, no
    taller than :data:`SITE_MAX_HEIGHT` of the image (a spot nearer than that is redrawn: 95 % of fire-cctv-416's
    boxes are lower) and overlapping none of ``avoid`` ([x, y, w, h] px); None when ``tries`` draws find none."""
    ground = np.flatnonzero(depth > 0)
    if not len(ground):
        return None

    def draw() -> tuple[int, int, int] | None:
        by, bx = divmod(int(ground[rng.integers(len(ground))]), cfg.width)
        hpx = max(int(fy * flame_height(cfg, rng) / float(depth[by, bx])), 12)
        return (bx, by, hpx) if hpx <= SITE_MAX_HEIGHT * cfg.height else None

    return clear_spot(draw, flame_size, avoid, tries)


def clear_spot(
    draw: Callable[[], tuple[int, int, int] | None],
    flame_size: tuple[int, int],
    avoid: Sequence[Sequence[int]],
    tries: int,
) -> tuple[int, int, int] | None:
    """The first of ``tries`` spots (base x, base y, height px) from ``draw`` (None: a spot it rejects) whose flame
    box (:func:`flame_box`, shaped like ``flame_size``) overlaps none of ``avoid`` ([x, y, w, h] px); None when no
    draw gives one."""
    for _ in range(tries):
        spot = draw()
        if spot is not None and not overlaps(flame_box(*spot, flame_size), avoid):
            return spot
    return None


def anchored_spot(
    anchors: Sequence[Sequence[float]],
    flame_size: tuple[int, int],
    cfg: Method2Config,
    avoid: Sequence[Sequence[int]],
    rng: np.random.Generator,
    tries: int = 10,
) -> tuple[int, int, int] | None:
    """(base x, base y, height px) of a flame standing beside one of a labelled frame's fires ``anchors`` ([x, y, w,
    h] px): the frame shows where fire stands in its view and how large it looks there. Its foot row is that fire's
    bottom edge moved by up to :data:`ANCHOR_FOOT` of the image height, its height the fire's box height times
    :data:`ANCHOR_SCALE` (log-uniform, capped at :data:`SITE_MAX_HEIGHT` of the image), its column anywhere in the
    image; overlapping none of ``avoid``. None when ``tries`` draws find no such spot."""
    lo, hi = np.log(ANCHOR_SCALE[0]), np.log(ANCHOR_SCALE[1])

    def draw() -> tuple[int, int, int]:
        _, y, _, h = anchors[int(rng.integers(len(anchors)))]
        foot = y + h + rng.uniform(-ANCHOR_FOOT, ANCHOR_FOOT) * cfg.height
        by = int(np.clip(round(foot), 1, cfg.height))
        hpx = int(np.clip(round(h * np.exp(rng.uniform(lo, hi))), 12, SITE_MAX_HEIGHT * cfg.height))
        return int(rng.integers(0, cfg.width)), by, hpx

    return clear_spot(draw, flame_size, avoid, tries)


def mask_box(p: Placement) -> list[int]:
    """[x, y, w, h] image pixels covering the flame mask of placement ``p`` (its sprite's mask box scaled to the
    placement, rounded outwards)."""
    span = mask_span(p.sprite)
    if span is None:
        return [p.x, p.y, p.width, p.height]
    c0, r0, c1, r1 = span
    sx, sy = p.width / p.sprite.size[0], p.height / p.sprite.size[1]
    x0, y0 = p.x + int(np.floor(c0 * sx)), p.y + int(np.floor(r0 * sy))
    x1, y1 = p.x + int(np.ceil((c1 + 1) * sx)), p.y + int(np.ceil((r1 + 1) * sy))
    return [x0, y0, x1 - x0, y1 - y0]


def flame_box(bx: int, by: int, hpx: int, flame_size: tuple[int, int]) -> list[int]:
    """[x, y, w, h] pixels of a flame standing at base (bx, by), ``hpx`` high, shaped like ``flame_size`` (w, h in
    any unit): the box :func:`site_spot` keeps clear of what it avoids."""
    wpx = max(int(round(hpx * flame_size[0] / flame_size[1])), 2)
    return [bx - wpx // 2, by - hpx, wpx, hpx]


def kept_clear(meta: dict) -> list:
    """Boxes [x, y, w, h] of a view where no flame or distractor may go: a photo site's people and a labelled
    frame's own fires (:mod:`synth.frames`)."""
    return [*meta.get("people", []), *meta.get("frame_boxes", [])]


def visible_composite(
    scene: NDArray[np.uint8],
    planned: Sequence[tuple[Placement, str]],
    effects,
    min_box_px: int,
    meter: Callable[[NDArray[np.uint8], list[Placement]], NDArray[np.uint8]] | None = None,
):
    """Composite ``planned`` on the exposed ``scene`` and take it through the camera (``effects``), erasing every
    flame that cannot be seen (:mod:`synth.visibility`: contrast against the plate, the scene through the same
    camera without flames) or whose seen part is smaller than ``min_box_px``, and compositing again without it
    until every flame left is seen (erasing one can unhide another). ``meter(scene, placements)``: the scene as
    the camera exposes it with those flames in view (:mod:`synth.metering`; the plate is that scene too), redone
    for the flames left after each erasure. Returns (image (H, W, 3) uint8, the composite, the flames kept (a
    sublist of ``planned``), their :class:`synth.visibility.Visibility`)."""
    plate = apply_effects(scene, effects) if meter is None else None
    shown = list(planned)
    while True:
        lit = scene if meter is None else meter(scene, [p for p, _ in shown])
        if meter is not None:
            plate = apply_effects(lit, effects)
        result = composite(lit, [p for p, _ in shown])
        image = apply_effects(result.image, effects)
        delta = delta_e(image, plate)
        seen = [measure(delta, m) for m in result.flames]
        keep = [k for k, v in enumerate(seen) if v.visible and min(mask_to_xywh(v.part)[2:]) >= min_box_px]
        if len(keep) == len(shown):
            return image, result, shown, seen
        shown = [shown[k] for k in keep]


def dressed_scene(
    cfg: Method2Config, background, depth, meta: dict, planned, library, effects: Effects, fy: float, rng,
    regions: Sequence[Region] = (),
):  # fmt: skip
    """The exposed scene flames are composited on, with this image's distractors (reflective ones before the
    low-light exposure, light sources after it) and decoy pastes, none overlapping a planned flame or what
    :func:`kept_clear` keeps clear (a photo site's people, a labelled frame's fires; boxes [x, y, w, h] in
    ``meta``); and
    the metadata they add (``distractors``, ``decoys``: kind or blend and box [x, y, w, h]; only when on).
    ``regions``: the regions of the pool's photos that the photo kinds of distractors are cut from."""
    avoid = [*([p.x, p.y, p.width, p.height] for p, _ in planned), *kept_clear(meta)]
    items = (
        plan_distractors(cfg.distractors, background, depth, meta, fy, avoid, rng, regions=regions)
        if cfg.distractors.share
        else []
    )
    scene = draw_distractors(expose(draw_distractors(background, items, False), effects), items, True)
    added: dict = {"distractors": [d.to_json() for d in items]} if cfg.distractors.share else {}
    if cfg.blend.decoys:
        decoys = plan_decoys(cfg.blend, scene, library, [*avoid, *(d.box for d in items)], rng)
        scene = composite(scene, decoys).image
        added["decoys"] = [{"blend": d.blend, "box": [d.x, d.y, d.width, d.height]} for d in decoys]
    return scene, added


def styled(cfg: Method2Config, planned, scene, rng) -> list[tuple[Placement, str]]:
    """``planned`` with each flame's paste edge and look (tint, blur, grain) drawn for ``scene`` (unchanged, and
    nothing drawn, with the default blend)."""
    if cfg.blend.default:
        return list(planned)
    out = []
    for p, name in planned:
        emission = scaled_layers(p.sprite, p.width, p.height)[1]
        colour = np.round(emission * 255.0).astype(np.uint8)
        edge, look = sample_style(cfg.blend, p.blend, scene, (p.x, p.y, p.width, p.height), colour, rng)
        out.append((replace(p, edge=edge, look=look), name))
    return out


def varied(planned: list[tuple[Placement, str]], rng: np.random.Generator) -> list[tuple[Placement, str]]:
    """``planned`` with each flame jittered (:mod:`synth.jitter`: four draws of ``rng`` per flame): its sprite
    mirrored and recoloured, its placement stretched in width about its centre (base and height kept)."""
    out = []
    for p, name in planned:
        j = draw_jitter(rng)
        width = stretched_width(p.width, j)
        out.append((replace(p, sprite=jittered(p.sprite, j), x=p.x + (p.width - width) // 2, width=width), name))
    return out


def swapped_boxes(cfg: Method2Config, view_meta: dict, rng: np.random.Generator) -> list:
    """The fire boxes [x, y, w, h] px of a labelled frame's view that this image swaps (:mod:`synth.swap`): all of
    them with probability ``cfg.frame_swap`` (one ``rng.random`` draw, only on a frame with fires), else none."""
    boxes = view_meta.get("frame_boxes") or []
    if not cfg.frame_swap or not boxes or rng.random() >= cfg.frame_swap:
        return []
    return [list(b) for b in boxes]


def swap_flames(
    cfg: Method2Config, library: Sequence[SpriteSequence], boxes: Sequence, rng: np.random.Generator
) -> list[tuple[Placement, str]]:
    """One flame per box [x, y, w, h] px: the library frame shaped most like it (:func:`synth.swap.best_fit`), its
    flame mask's box stretched onto the box (:func:`synth.swap.spanning`), its look drawn by
    :func:`drawn_placement`; all from ``rng``."""
    out = []
    for box in boxes:
        seq, frame = best_fit(library, cfg.flames, max(box[2], 1e-3) / max(box[3], 1e-3), rng)
        sprite = seq.sprites[frame]
        out.append((drawn_placement(cfg, sprite, spanning(sprite, box), rng), f"{seq.name}/{frame}"))
    return out


def negative_share(cfg: Method2Config, view_meta: dict) -> float:
    """The probability that an image on the view of ``view_meta`` gets no flame: ``cfg.photo_negatives`` on a
    fire-free photo (a ``backgrounds`` photo, not a labelled frame) when set, else ``cfg.negatives``."""
    photo = "photo" in view_meta and "frame_boxes" not in view_meta
    return cfg.photo_negatives if photo and cfg.photo_negatives is not None else cfg.negatives


@dataclass(frozen=True)
class Meter:
    """A camera's auto exposure for one image's scene (:mod:`synth.metering`): the scene's ``mean`` linear
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
    (:func:`visible_composite`); a kept flame's mask and box are its seen part. Distractors and decoys are part of
    the scene (and of the plate the flames' visibility is measured against); they get no box."""
    background, depth, view_meta = views.image_background(i, cfg.images_per_view)
    swap_rng = np.random.default_rng([cfg.seed, 2, i, 4])
    swapped = swapped_boxes(cfg, view_meta, swap_rng)
    if swapped:  # the frame's fires erased; the flames drawn in their boxes are boxed by what is seen of them
        background = erased(background, swapped)
        view_meta = {**view_meta, "frame_boxes": [], "swapped": len(swapped)}
    rng = np.random.default_rng([cfg.seed, 2, i])
    avoid = [*kept_clear(view_meta), *swapped] if view_meta.get("site") else None
    yfov = view_meta["camera"]["yfov"]
    anchors = view_meta.get("frame_boxes") or ()
    planned = plan_flames(cfg, library, depth, yfov, rng, avoid, negative_share(cfg, view_meta), anchors)
    planned = [*swap_flames(cfg, library, swapped, swap_rng), *planned]
    effects = sample_effects(rng, cfg.camera)
    if cfg.flame_jitter:
        planned = varied(planned, np.random.default_rng([cfg.seed, 2, i, 3]))
    extra = np.random.default_rng([cfg.seed, 2, i, 1])
    fy = float(render.intrinsics(yfov, cfg.width, cfg.height)[1, 1])
    photos = views.photos if cfg.distractors.photo else None
    regions = photos.regions(cfg.distractors.photo_kinds) if photos is not None else ()
    scene, added = dressed_scene(cfg, background, depth, view_meta, planned, library, effects, fy, extra, regions)
    planned = styled(cfg, planned, scene, extra)
    meter = metering(cfg, i, scene) if cfg.auto_exposure else None
    image, result, shown, seen = visible_composite(scene, planned, effects, cfg.min_box_px, meter)
    kept, boxes, index = boxes_from_masks([v.part for v in seen], cfg.min_box_px)
    if cfg.cutout_box == "source":
        boxes = annotator_boxes(library, [shown[k] for k in index], kept, boxes)
    flames = [flame_record(shown[k][0], shown[k][1], seen[k]) for k in index]
    meta = {**view_meta, "flames": flames, "erased": len(planned) - len(shown), **added, "effects": effects.to_json()}
    if meter is not None:
        meta["exposure_gain"] = round(meter.gain([p for p, _ in shown]), 4)
    boxes += view_meta.get("frame_boxes", [])  # a labelled frame's own fires, after the flames (no mask: audit)
    record = {"width": cfg.width, "height": cfg.height, "boxes": boxes, "meta": meta}
    if not cfg.smoke_class:
        return image, kept, record, None
    smoke, record["smoke_boxes"], _ = boxes_from_masks(result.smoke, cfg.min_box_px)
    return image, kept, record, smoke


def annotator_boxes(
    library: Sequence[SpriteSequence], flames: Sequence[tuple[Placement, str]], parts: Sequence, boxes: list
) -> list:
    """``boxes`` ([x, y, w, h] of the kept ``flames``, each (placement, "<sequence>/<frame>"), whose seen parts are
    the (H, W) bool ``parts``, all in one order) with every real cut-out's box replaced by :func:`source_box`."""
    cut = {seq.name for seq in library if is_cutout(seq)}
    return [
        source_box(p, part) if name.rsplit("/", 1)[0] in cut else box
        for (p, name), part, box in zip(flames, parts, boxes, strict=True)
    ]


def source_box(p: Placement, part: NDArray[np.bool_]) -> list[int]:
    """[x, y, w, h] image pixels (integers, inside the (H, W) image of ``part``) of a cut-out flame boxed as its
    annotator boxed it: the box of its seen pixels ``part`` (H, W) bool, grown on each side by the margin between
    the sprite's flame mask and its canvas (the real box it was cut from, kept by
    :func:`synth.library.cutout_library` with ``canvas``), scaled as the placement scales the sprite. A flame seen
    whole gets its placed canvas (clipped to the image); a partly hidden one keeps the margins of its seen sides."""
    sw, sh = p.sprite.size
    c0, r0, c1, r1 = flame_rect(p.sprite)  # a kept flame has mask pixels
    sx, sy = p.width / sw, p.height / sh
    x, y, w, h = (int(v) for v in mask_to_xywh(part))
    height, width = part.shape
    x0, y0 = max(int(round(x - c0 * sx)), 0), max(int(round(y - r0 * sy)), 0)
    x1 = min(int(round(x + w + (sw - 1 - c1) * sx)), width)
    y1 = min(int(round(y + h + (sh - 1 - r1) * sy)), height)
    return [x0, y0, x1 - x0, y1 - y0]


def flame_record(p: Placement, name: str, seen) -> dict:
    """A kept flame in the manifest: sprite, blend, glow, opacity, contrast, seen share (and, when not the
    default, its paste edge and look)."""
    out = {
        "flame": name,
        "blend": p.blend,
        "glow": round(p.glow, 4),
        "opacity": round(p.opacity, 4),
        "contrast": round(seen.contrast, 2),
        "seen": round(seen.seen / max(seen.pixels, 1), 4),
    }
    if p.edge:
        out["edge"] = round(p.edge, 3)
    if not p.look.neutral:
        out["look"] = p.look.to_json()
    return out


def run_method2(
    cfg: Method2Config,
    library: Sequence[SpriteSequence],
    out: Path,
    overwrite: bool = False,
    platform: str | None = None,
    workers: int = 1,
):
    """Generate (or resume) ``cfg.n`` images and write the dataset to ``out`` (in ``workers`` processes: the
    same bytes); returns the WriteResult."""
    return generate("method2", cfg, make_image, library, out, overwrite, platform, workers)

"""Method 1 (the paper's first method): flame image planes placed in the 3D scene relative to the camera and
rendered with it; boxes computed two ways.

Placement: the camera follows the environment's camera rules (area, height, look-at target, limited pitch, no
roll: :mod:`synth.places.camera`). Each plane stands on the surface seen at a random pixel of the lower two thirds of
the view, ``clearance_m`` in front of it (towards the camera), upright (a horizontal view of a vertical flame),
turned to face the camera up to ``yaw_jitter_deg``, ``flame_height_m`` tall with the sprite's aspect; the
plane's texture is the sprite flattened to straight-alpha RGBA (:func:`synth.flames.sprites.flatten_rgba`).

Boxes (all in pixels, row 0 at the top):
- ``paper``: the box of the plane's four projected corners, clipped to the image (the paper's way; it
  includes the plane's transparent margin, its smoke, and parts hidden behind scene geometry);
- ``visible``: the box of the flame's visible mask = the plane's segmentation pass (scene geometry occludes)
  ∧ the sprite's flame mask warped by the plane's homography ∧ not behind an opaque part (alpha >= 0.5 or
  flame) of a nearer plane (per-pixel depths from the segmentation passes).

Image ``i`` uses view ``i // images_per_view`` (:mod:`synth.places.views`) and ``default_rng([seed, 3, i])``, so any
image can be (re)made alone: runs resume and are byte-reproducible.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.data.boxes import clip_xyxy, mask_to_xywh, points_to_xyxy, xyxy_to_xywh
from synth.compose.effects import Effects, apply_effects, expose, sample_effects
from synth.flames.library import flame_draws
from synth.flames.sprites import Sprite, SpriteSequence, flatten_rgba
from synth.method_config import MethodConfig
from synth.places import render
from synth.places.scenes import translate
from synth.places.views import View, ViewCache
from synth.schema import check_range
from synth.staging import boxes_from_masks

BOX_MODES: tuple[str, ...] = ("paper", "visible")


@dataclass(frozen=True)
class Method1Config(MethodConfig):
    """Method 1 settings (``configs/synth-method1.yaml`` documents every key; the keys both methods share:
    :class:`synth.method_config.MethodConfig`). ``flames`` describes the library a command builds with
    :func:`synth.flames.library.build_library`; the manifest records the sequences used."""

    method: ClassVar[str] = "method1"
    composited: ClassVar[bool] = False
    bringing_places: ClassVar[str] = "environments are"

    distance_m: tuple[float, float] = (1.0, 25.0)  # plane distance from the camera
    clearance_m: tuple[float, float] = (0.05, 0.5)  # plane stands this far in front of the surface it is on
    yaw_jitter_deg: float = 25.0  # plane rotation about the vertical away from facing the camera
    box_mode: Literal["visible", "paper"] = "visible"  # written annotation: accurate, or projected corners
    effects: bool = True  # camera effects (white balance, blur, noise, JPEG) as in Method 2
    light: bool = True  # flames light their surroundings (a point light per flame)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.box_mode not in BOX_MODES:
            raise ValueError(f"unknown box mode {self.box_mode!r}; choose one of {', '.join(BOX_MODES)}")
        if self.flames.source != "simulated":
            raise ValueError(f"flames.source {self.flames.source}: cut-out flames are for Method 2 pools only")
        if self.yaw_jitter_deg < 0:
            raise ValueError(f"yaw_jitter_deg must be >= 0, got {self.yaw_jitter_deg}")
        check_range("distance_m", self.distance_m, 0.2)
        check_range("clearance_m", self.clearance_m, 0.0)


@dataclass(frozen=True)
class Plane:
    """A flame image plane: ``width`` x ``height`` metres, bottom edge centred at the pose origin, facing +Z."""

    sprite: Sprite
    flame_id: str
    pose: NDArray[np.float64]  # (4, 4) plane-to-world
    width: float
    height: float

    def corners(self) -> NDArray[np.float64]:
        """(4, 3) world corners: top-left, top-right, bottom-right, bottom-left (as the texture's corners)."""
        local = render.quad_corners(self.width, self.height)
        return local @ self.pose[:3, :3].T + self.pose[:3, 3]

    def to_json(self) -> dict:
        return {
            "pose": np.round(self.pose, 6).tolist(),
            "width_m": round(self.width, 6),
            "height_m": round(self.height, 6),
        }


FLAME_LIGHT = 6.0  # point-light intensity per metre of flame height at full brightness


def _stand(cfg: Method1Config, view: View, k: NDArray[np.float64], rng: np.random.Generator):
    """A random base point on the surface seen in the lower two thirds of the view, moved ``clearance_m`` towards
    the camera; None when the pixel shows sky or lies outside ``distance_m``."""
    u, v = rng.uniform(0, cfg.width), rng.uniform(cfg.height / 3, cfg.height)
    d = float(view.depth[min(int(v), cfg.height - 1), min(int(u), cfg.width - 1)])
    if d <= 0:
        return None
    eye = view.camera.pose[:3, 3]
    hit = render.unproject(np.array([[u, v]]), np.array([d]), view.camera.pose, k)[0]
    ray = (hit - eye) / np.linalg.norm(hit - eye)
    base = hit - ray * rng.uniform(*cfg.clearance_m)
    return base if cfg.distance_m[0] <= np.linalg.norm(base - eye) <= cfg.distance_m[1] else None


def place_plane(cfg: Method1Config, sprite: Sprite, view: View, rng: np.random.Generator, tries: int = 10):
    """A plane for ``sprite`` obeying the placement rules (module docstring), or None after ``tries``."""
    k = render.intrinsics(view.camera.yfov, cfg.width, cfg.height)
    eye = view.camera.pose[:3, 3]
    for _ in range(tries):
        base = _stand(cfg, view, k, rng)
        height = float(rng.uniform(*cfg.flame_height_m))
        width = height * sprite.size[0] / sprite.size[1]
        if base is None:
            continue
        to_eye = eye - base
        yaw = np.degrees(np.arctan2(to_eye[0], to_eye[2])) + rng.uniform(-cfg.yaw_jitter_deg, cfg.yaw_jitter_deg)
        plane = Plane(sprite, "", translate(*base, yaw_deg=float(yaw)), width, height)
        if render.project(plane.corners(), view.camera.pose, k)[:, 2].min() > 0.1:
            return plane
    return None


def place_planes(cfg: Method1Config, library: Sequence[SpriteSequence], view: View, rng: np.random.Generator):
    """Up to ``max_flames`` planes (none for a negative image) with random sprites of the library."""
    planes = []
    for seq, frame in flame_draws(library, cfg.max_flames, cfg.negatives, rng):
        plane = place_plane(cfg, seq.sprites[frame], view, rng)
        if plane is not None:
            planes.append(Plane(plane.sprite, f"{seq.name}/{frame}", plane.pose, plane.width, plane.height))
    return planes


def render_planes(renderer: render.Renderer, view: View, planes: Sequence[Plane], light: bool = True):
    """Render the view with the planes: ((H, W, 3) uint8 RGB, per plane ((H, W) bool coverage, (H, W) float32
    depth)). A plane's coverage comes from a segmentation pass with the other planes hidden, so scene geometry
    (and only it) occludes it; its depth is valid where it is covered. With ``light`` each plane is also a point
    light (:func:`flame_light`)."""
    pr = renderer.pyrender
    scene, cam = view.scene, view.camera
    nodes, lights = [], []
    for p in planes:
        quad = render.textured_quad(pr, p.width, p.height, render.rgba_material(pr, flatten_rgba(p.sprite)))
        nodes.append(scene.add(quad, pose=p.pose))
        if light:
            colour, intensity = flame_light(p)
            at = p.pose @ translate(0.0, 0.4 * p.height, 0.1)  # inside the flame, just in front of its plane
            lights.append(scene.add(pr.PointLight(color=colour, intensity=intensity), pose=at))
    try:
        with render.camera_at(renderer, scene, cam.pose, cam.yfov):
            rgb, _ = renderer.color_depth(scene)
            passes = []
            for node in nodes:
                for other in nodes:
                    other.mesh.is_visible = other is node
                ids, depth = renderer.segment_depth(scene, {node: 1})
                passes.append((ids == 1, depth))
    finally:
        for node in nodes + lights:
            scene.remove_node(node)
    return rgb, passes


def flame_light(plane: Plane) -> tuple[NDArray[np.float64], float]:
    """The point light a flame casts on its surroundings: (RGB colour with max 1, intensity). Colour is the
    sprite's mean emission over its flame mask; intensity grows with the flame's height and with this frame's
    brightness, so a sequence's frames flicker."""
    sprite = plane.sprite
    emission = sprite.emission[sprite.mask] if sprite.mask.any() else sprite.emission.reshape(-1, 3)
    mean = emission.astype(np.float64).mean(axis=0) / 255.0
    colour = mean / max(float(mean.max()), 1e-6)
    return colour, float(FLAME_LIGHT * plane.height * mean.max())


def plane_layers(plane: Plane, corners_uv: NDArray[np.float64], width: int, height: int) -> NDArray[np.bool_]:
    """(H, W, 3) bool: the sprite's flame mask, its opaque part (alpha >= 0.5 or flame) and its smoke mask
    (:meth:`Sprite.smoke_mask`) warped into the image by the homography taking the sprite's corners to the plane's
    projected corners ``corners_uv`` (4, 2)."""
    sp = plane.sprite
    sw, sh = sp.size
    src = np.array([[0, 0], [sw, 0], [sw, sh], [0, sh]], np.float32) - 0.5  # texel edges, cv2 centre convention
    homography = cv2.getPerspectiveTransform(src, corners_uv.astype(np.float32) - 0.5)
    opaque = sp.mask | (flatten_rgba(sp)[..., 3] >= 128)
    layers = np.stack([sp.mask, opaque, sp.smoke_mask()], axis=-1).astype(np.float32)
    warped = cv2.warpPerspective(layers, homography, (width, height), flags=cv2.INTER_LINEAR)
    return warped >= 0.5


def visible_masks(layers: Sequence[NDArray[np.bool_]], passes, channel: int = 0) -> list[NDArray[np.bool_]]:
    """Per plane: (H, W) bool visible flame (``channel`` 0) or smoke (2) = covered ∧ layer ∧ not behind an opaque
    part of a nearer plane (for smoke: nor behind its smoke, so smoke masks stay disjoint)."""
    out = []
    for k, (cover_k, depth_k) in enumerate(passes):
        visible = cover_k & layers[k][..., channel]
        for j, (cover_j, depth_j) in enumerate(passes):
            if j != k:
                hides = layers[j][..., 1] | (layers[j][..., 2] if channel == 2 else False)
                visible &= ~(cover_j & hides & (depth_j < depth_k))
        out.append(visible)
    return out


def paper_box(corners_uv: NDArray[np.float64], width: int, height: int) -> NDArray[np.float64]:
    """(4,) xywh: the box of the projected corners (4, 2), clipped to the image (the paper's annotation)."""
    return xyxy_to_xywh(clip_xyxy(points_to_xyxy(corners_uv)[None], width, height))[0]


def _box_json(box: NDArray[np.float64] | None) -> list[float] | None:
    return None if box is None else [round(float(v), 3) for v in box]


def annotate(cfg: Method1Config, planes: Sequence[Plane], paper: Sequence, masks: Sequence[NDArray[np.bool_]]):
    """Order the flames for writing: first those with a visible box of at least ``min_box_px`` (annotated in
    both modes; their masks are kept, instance k = k-th), then those only the paper's box sees (annotated in
    paper mode only, no mask). Returns (kept masks, record fields)."""
    big = [min(b[2], b[3]) >= cfg.min_box_px for b in (mask_to_xywh(m) for m in masks)]
    seen = [i for i, ok in enumerate(big) if ok]
    paper_only = [i for i, ok in enumerate(big) if not ok and min(paper[i][2], paper[i][3]) >= cfg.min_box_px]
    order = seen + paper_only
    modes = {
        "paper": [_box_json(paper[i]) for i in order],
        "visible": [_box_json(mask_to_xywh(masks[i])) for i in seen] + [None] * len(paper_only),
    }
    flames = [
        {
            "flame": planes[i].flame_id,
            "plane": planes[i].to_json(),
            "paper_box": modes["paper"][n],
            "visible_box": modes["visible"][n],
        }
        for n, i in enumerate(order)
    ]
    boxes = modes["visible"][: len(seen)] if cfg.box_mode == "visible" else modes["paper"]
    return [masks[i] for i in seen], {"boxes": boxes, "box_modes": modes, "flames": flames}


def make_image(cfg: Method1Config, i: int, library: Sequence[SpriteSequence], views: ViewCache):
    """Image ``i``: ((H, W, 3) uint8, kept fire masks, record dict (boxes xywh, both box modes, metadata), kept
    smoke masks or None when smoke is not a class)."""
    view = views.view(i // cfg.images_per_view)
    rng = np.random.default_rng([cfg.seed, 3, i])
    planes = place_planes(cfg, library, view, rng)
    rgb, passes = render_planes(views.renderer, view, planes, cfg.light)
    k = render.intrinsics(view.camera.yfov, cfg.width, cfg.height)
    corners = [render.project(p.corners(), view.camera.pose, k)[:, :2] for p in planes]
    layers = [plane_layers(p, c, cfg.width, cfg.height) for p, c in zip(planes, corners)]
    masks = visible_masks(layers, passes)
    paper = [paper_box(c, cfg.width, cfg.height) for c in corners]
    kept, fields = annotate(cfg, planes, paper, masks)
    effects = sample_effects(rng, cfg.camera) if cfg.effects else Effects()
    drawn = [cover & layer[..., 1] for (cover, _), layer in zip(passes, layers)]  # visible opaque flame parts
    flames_drawn = np.logical_or.reduce(drawn) if drawn else None
    image = apply_effects(expose(rgb, effects, flames_drawn), effects)
    meta: dict[str, Any] = {**view.meta(), "flames": fields["flames"], "box_mode": cfg.box_mode}
    meta["effects"] = effects.to_json()
    record = {"width": cfg.width, "height": cfg.height, "boxes": fields["boxes"], "box_modes": fields["box_modes"]}
    record["meta"] = meta
    if not cfg.smoke_class:
        return image, kept, record, None
    smoke, record["smoke_boxes"], _ = boxes_from_masks(visible_masks(layers, passes, 2), cfg.min_box_px)
    return image, kept, record, smoke

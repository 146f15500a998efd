"""Distractors: fire-like things that are not fire, drawn procedurally on a background and never boxed (hard
negatives for the detector).

Kinds (:data:`KINDS`): ``lamp`` (a bare bulb with bloom and star streaks, or a glowing lamp shade), ``sun`` (a low
sun disc above the horizon with a sunset gradient over the sky; only where the view shows sky), ``cone`` (a traffic
cone with reflective bands), ``cloth`` (a red or orange cloth with folds), ``clothing`` (an orange or red jacket,
hi-vis strips), ``taillights`` (a car's pair of red rear lights, often with the dark car body and plate between
them) and ``glare`` (an anamorphic glare streak, or a lamp's reflection on a glossy floor). Two more kinds are not
drawn but cut from the pool's own fire-free photos (:data:`PHOTO_KINDS`, not in the default kinds;
:mod:`synth.photo_regions`): ``photo``, a fire-coloured region (an orange lamp shade, a lit window, a red sofa),
and ``lights``, a light source with its warm glow (a white-hot lamp shade, a street light, a window at night),
each pasted anywhere in the image at 0.7-1.3 x its height share of its photo, mirrored half the time. Each is drawn as a
:class:`synth.sprites.Sprite` with an empty flame mask (reflective parts in ``over``, light in ``emission``) in
image pixels; objects standing on the ground are sized by the view's depth like flames.

Frames: image pixels, row 0 at the top; boxes [x, y, w, h]. A distractor's box is the box of every pixel it
changes (glow included), and it never overlaps the boxes it is told to avoid (the flames' placements).
Randomness only through the explicit ``rng``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.core.imageio import unit_to_u8
from synth.colour import blackbody_rgb, srgb_encode
from synth.photo_regions import RULES, Region
from synth.sites import sky_like
from synth.sprites import Sprite

KINDS: tuple[str, ...] = ("lamp", "sun", "cone", "cloth", "clothing", "taillights", "glare")
PHOTO_KIND = "photo"  # cut from the pool's fire-free photos (Method 2 with backgrounds only), not drawn
PHOTO_KINDS: tuple[str, ...] = RULES  # the kinds cut from photos, each by its rule of synth.photo_regions
ALL_KINDS: tuple[str, ...] = (*KINDS, *PHOTO_KINDS)
PHOTO_SCALE = (0.7, 1.3)  # a photo region's height in the image: this x its height share of its photo
EMISSIVE_KINDS: tuple[str, ...] = ("lamp", "sun", "taillights", "glare")  # light: drawn after low-light exposure
OUTDOOR_KINDS: tuple[str, ...] = ("sun", "taillights")  # never drawn in a rendered room (:func:`kinds_here`)
#: Height range in metres of the kinds that stand on the ground (sized by depth like flames).
GROUND_HEIGHT_M: dict[str, tuple[float, float]] = {
    "cone": (0.45, 0.9),
    "cloth": (0.3, 1.0),
    "clothing": (0.5, 0.9),
    "taillights": (0.25, 0.45),  # the lights' height above the ground does not matter: this is their pair's height
}
Layers = tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]]  # over rgb, over alpha, light


@dataclass(frozen=True)
class DistractorConfig:
    """Distractors of Method 2 (``configs/synth-method2.yaml`` documents every key); share 0 = none (the
    default, pools made before distractors existed)."""

    share: float = 0.0  # fraction of images that carry distractors, 0..1
    max: int = 2  # distractors per such image: uniform in 1..max
    kinds: tuple[str, ...] = KINDS  # kinds drawn uniformly

    def __post_init__(self) -> None:
        if not 0.0 <= self.share <= 1.0:
            raise ValueError(f"distractors.share must be in 0..1, got {self.share}")
        if self.max < 1:
            raise ValueError(f"distractors.max must be >= 1, got {self.max}")
        if not self.kinds or any(k not in ALL_KINDS for k in self.kinds):
            raise ValueError(
                f"distractors.kinds must be a non-empty list of {', '.join(ALL_KINDS)}, got {list(self.kinds)}"
            )

    @property
    def photo(self) -> bool:
        """Whether images may carry distractors cut from the pool's fire-free photos (:data:`PHOTO_KINDS`)."""
        return bool(self.photo_kinds)

    @property
    def photo_kinds(self) -> tuple[str, ...]:
        """The :data:`PHOTO_KINDS` images may carry (none when ``share`` is 0), in :data:`PHOTO_KINDS`' order."""
        return tuple(k for k in PHOTO_KINDS if k in self.kinds) if self.share > 0 else ()


@dataclass(frozen=True)
class Distractor:
    """A drawn distractor: its layers as a sprite with an empty flame mask, its top-left (x, y) in image pixels;
    one of :data:`PHOTO_KINDS` also names the photo it was cut from."""

    kind: str
    sprite: Sprite
    x: int
    y: int
    photo: str = ""

    @property
    def emissive(self) -> bool:
        return self.kind in EMISSIVE_KINDS

    @property
    def box(self) -> list[int]:
        """[x, y, w, h] image pixels of the sprite (may reach outside the image)."""
        return [self.x, self.y, *self.sprite.size]

    def to_json(self) -> dict:
        return {"kind": self.kind, "box": self.box, **({"photo": self.photo} if self.photo else {})}


# --- drawing primitives: float32 canvases, pixel centres at integer + 0.5 -------------------------------------


def _grid(h: int, w: int) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    return x + 0.5, y + 0.5


def gaussian(h: int, w: int, cx: float, cy: float, sx: float, sy: float, angle: float = 0.0) -> NDArray[np.float32]:
    """(h, w) Gaussian of peak 1 at (cx, cy), sigmas ``sx`` along ``angle`` (radians) and ``sy`` across it."""
    x, y = _grid(h, w)
    c, s = np.cos(angle), np.sin(angle)
    u, v = (x - cx) * c + (y - cy) * s, -(x - cx) * s + (y - cy) * c
    return np.exp(-0.5 * ((u / sx) ** 2 + (v / sy) ** 2)).astype(np.float32)


def polygon(h: int, w: int, points: NDArray[np.float64], scale: int = 4) -> NDArray[np.float32]:
    """(h, w) anti-aliased coverage of the polygon ``points`` (N, 2) (x, y) pixels (filled at ``scale`` x, then
    averaged)."""
    big = np.zeros((h * scale, w * scale), np.uint8)
    cv2.fillPoly(big, [np.round(points * scale).astype(np.int32)], 255, lineType=cv2.LINE_AA)
    return cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0


def ellipse(h: int, w: int, cx: float, cy: float, rx: float, ry: float) -> NDArray[np.float32]:
    """(h, w) anti-aliased coverage of an axis-aligned ellipse."""
    x, y = _grid(h, w)
    d = np.sqrt(((x - cx) / rx) ** 2 + ((y - cy) / ry) ** 2)
    return np.clip((1.0 - d) * min(rx, ry) + 0.5, 0.0, 1.0).astype(np.float32)


def warm(kelvin: float) -> NDArray[np.float32]:
    """(3,) display sRGB colour (max 1) of a black body at ``kelvin``."""
    return srgb_encode(blackbody_rgb(kelvin)).astype(np.float32)


def _shaded(alpha: NDArray[np.float32], colour: NDArray[np.float32], shade: NDArray[np.float32]) -> Layers:
    h, w = alpha.shape
    rgb = np.clip(colour[None, None, :] * shade[..., None], 0.0, 1.0).astype(np.float32)
    return rgb, alpha, np.zeros((h, w, 3), np.float32)


def side_light(h: int, w: int, rng: np.random.Generator) -> NDArray[np.float32]:
    """(h, w) shading of a round object lit from one side: 0.45..1 across its width, a little darker at the bottom."""
    x, y = _grid(h, w)
    side = rng.uniform(-0.5, 0.5)
    across = np.cos(np.clip((x / w - 0.5 - side * 0.3) * np.pi, -np.pi / 2, np.pi / 2))
    return (0.45 + 0.55 * across * (1.0 - 0.25 * y / h)).astype(np.float32)


# --- the kinds: each returns its layers (over rgb (h, w, 3), over alpha (h, w), light (h, w, 3)), 0..1 -----------


def draw_lamp(size: float, rng: np.random.Generator) -> Layers:
    """A bare bulb (a warm white core, bloom and, half the time, star streaks) or a lamp shade glowing warm with the
    bulb's light spilling below it. ``size``: the bulb's radius, pixels."""
    r = max(size, 1.5)
    s = int(2 * np.ceil(7 * r) + 1)
    c = s / 2
    colour = warm(rng.uniform(2200.0, 3600.0))
    core = ellipse(s, s, c, c, r, r)
    bloom = 0.5 * gaussian(s, s, c, c, 1.6 * r, 1.6 * r) + 0.22 * gaussian(s, s, c, c, 3.8 * r, 3.8 * r)
    light = core[..., None] * (0.5 * colour + 0.5) + (bloom * rng.uniform(0.6, 1.0))[..., None] * colour
    rgb, alpha = np.zeros((s, s, 3), np.float32), np.zeros((s, s), np.float32)
    if rng.random() < 0.5:
        for angle in rng.uniform(0, np.pi, int(rng.integers(2, 5))):
            light += (0.35 * gaussian(s, s, c, c, 4.5 * r, 0.22 * r, float(angle)))[..., None] * colour
    else:  # a shade: a trapezoid over the bulb, lit from inside, brightest at its rim
        top, bottom, height = 1.4 * r * rng.uniform(0.8, 1.2), 2.6 * r * rng.uniform(0.9, 1.3), 3.2 * r
        pts = np.array(
            [[c - top, c - height], [c + top, c - height], [c + bottom, c + 0.4 * r], [c - bottom, c + 0.4 * r]]
        )
        alpha = polygon(s, s, pts)
        _, y = _grid(s, s)
        glow = np.clip(0.55 + 0.45 * (y - (c - height)) / (height + 0.4 * r), 0.0, 1.0)
        rgb = np.clip((0.6 * colour + 0.35)[None, None, :] * glow[..., None], 0, 1).astype(np.float32)
        light = light * (1.0 - 0.6 * alpha[..., None] * (y < c)[..., None])
    return rgb, alpha, np.clip(light, 0.0, 1.0).astype(np.float32)


def draw_cone(size: float, rng: np.random.Generator) -> Layers:
    """A traffic cone ``size`` pixels tall: an orange tapered body with two white reflective bands on a square
    base, lit from one side."""
    h = max(int(round(size)), 8)
    w = max(int(round(0.72 * h)), 6)
    c = w / 2
    tip, foot, base_top = 0.07 * w, 0.36 * w, 0.86 * h
    body = polygon(h, w, np.array([[c - tip, 0], [c + tip, 0], [c + foot, base_top], [c - foot, base_top]]))
    base = polygon(
        h, w, np.array([[0.02 * w, base_top], [0.98 * w, base_top], [0.98 * w, h - 0.5], [0.02 * w, h - 0.5]])
    )
    orange = np.array([rng.uniform(0.9, 1.0), rng.uniform(0.28, 0.45), rng.uniform(0.02, 0.1)], np.float32)
    _, y = _grid(h, w)
    bands = ((y > 0.3 * h) & (y < 0.41 * h)) | ((y > 0.55 * h) & (y < 0.66 * h) & (rng.random() < 0.7))
    colour = np.where(bands[..., None], np.float32(0.88), orange[None, None, :])
    colour = np.where((base > body)[..., None], orange * 0.55, colour)
    alpha = np.maximum(body, base)
    rgb = np.clip(colour * side_light(h, w, rng)[..., None], 0.0, 1.0).astype(np.float32)
    return rgb, alpha, np.zeros((h, w, 3), np.float32)


def _blob(h: int, w: int, rng: np.random.Generator, wobble: float = 0.13) -> NDArray[np.float32]:
    """(h, w) coverage of a random smooth blob filling the canvas (an ellipse with a few low harmonics)."""
    theta = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    radius = np.ones_like(theta)
    for k in (2, 3, 4):
        radius += rng.uniform(0, wobble) * np.cos(k * theta + rng.uniform(0, 2 * np.pi))
    radius /= radius.max()
    pts = np.stack([w / 2 + 0.48 * w * radius * np.cos(theta), h / 2 + 0.48 * h * radius * np.sin(theta)], axis=1)
    return polygon(h, w, pts)


def _folds(h: int, w: int, rng: np.random.Generator) -> NDArray[np.float32]:
    """(h, w) shading of soft cloth folds, 0.6..1: random noise smoothed at a quarter of the object's size."""
    noise = cv2.GaussianBlur(rng.normal(0.0, 1.0, (h, w)).astype(np.float32), (0, 0), sigmaX=max(h, w) / 7)
    noise /= max(float(np.abs(noise).max()), 1e-6)
    return (0.8 + 0.2 * noise).astype(np.float32)


def _red_orange(rng: np.random.Generator) -> NDArray[np.float32]:
    """A saturated red, crimson or orange (display sRGB)."""
    hue = rng.choice(3)
    options = [(0.8, 0.08, 0.08), (0.62, 0.04, 0.12), (0.97, 0.42, 0.08)]
    return (np.asarray(options[hue], np.float32) * rng.uniform(0.8, 1.05)).clip(0, 1).astype(np.float32)


def draw_cloth(size: float, rng: np.random.Generator) -> Layers:
    """A red, crimson or orange cloth ``size`` pixels tall: a soft blob with folds."""
    h = max(int(round(size)), 8)
    w = max(int(round(h * rng.uniform(0.8, 1.8))), 8)
    alpha = _blob(h, w, rng)
    return _shaded(alpha, _red_orange(rng), _folds(h, w, rng) * side_light(h, w, rng) ** 0.7)


def draw_clothing(size: float, rng: np.random.Generator) -> Layers:
    """An orange or red jacket ``size`` pixels tall seen from the front: torso, sleeves, a dark collar and, half the
    time, silver hi-vis strips."""
    h = max(int(round(size)), 10)
    w = max(int(round(0.9 * h)), 9)
    c = w / 2
    torso = polygon(
        h, w, np.array([[c - 0.3 * w, 0.05 * h], [c + 0.3 * w, 0.05 * h], [c + 0.27 * w, h - 1], [c - 0.27 * w, h - 1]])
    )
    sleeve = [np.array([[c + s * 0.28 * w, 0.06 * h], [c + s * 0.48 * w, 0.5 * h], [c + s * 0.42 * w, 0.9 * h],
                        [c + s * 0.3 * w, 0.88 * h], [c + s * 0.3 * w, 0.3 * h]]) for s in (-1, 1)]  # fmt: skip
    alpha = np.maximum(torso, np.maximum(polygon(h, w, sleeve[0]), polygon(h, w, sleeve[1])))
    colour = np.array([1.0, 0.45, 0.05], np.float32) if rng.random() < 0.6 else _red_orange(rng)
    shade = _folds(h, w, rng) * side_light(h, w, rng) ** 0.6
    rgb, alpha, light = _shaded(alpha, colour, shade)
    _, y = _grid(h, w)
    if rng.random() < 0.5:
        strips = ((y > 0.55 * h) & (y < 0.62 * h)) | ((y > 0.75 * h) & (y < 0.82 * h))
        rgb = np.where(strips[..., None], np.float32(0.8) * shade[..., None], rgb)
    collar = ellipse(h, w, c, 0.05 * h, 0.12 * w, 0.08 * h)
    rgb = rgb * (1.0 - 0.8 * collar[..., None])
    return rgb.astype(np.float32), alpha, light


def draw_taillights(size: float, rng: np.random.Generator) -> Layers:
    """A car's rear lights: two red lamps ``size`` pixels apart (centre to centre) with a red glow and, most of
    the time, the car's rear around them (:func:`car_rear`)."""
    d = max(size, 8.0)
    lw, lh = d * rng.uniform(0.1, 0.16), d * rng.uniform(0.05, 0.09)
    pad = 3.0 * lw
    w, h = int(np.ceil(d + 2 * pad)), int(np.ceil(2 * pad + 6 * lh))
    cy = pad + 3 * lh
    red = np.array([1.0, rng.uniform(0.05, 0.2), rng.uniform(0.03, 0.12)], np.float32)
    light = np.zeros((h, w, 3), np.float32)
    for cx in (pad, pad + d):
        lamp = ellipse(h, w, cx, cy, lw, lh)
        glow = 0.45 * gaussian(h, w, cx, cy, 1.4 * lw, 1.4 * lw) + 0.15 * gaussian(h, w, cx, cy, 3 * lw, 2 * lw)
        core = gaussian(h, w, cx, cy, 0.5 * lw, 0.5 * lh)
        light += lamp[..., None] * red + glow[..., None] * red + (0.5 * core)[..., None] * np.float32(1.0)
    rgb, alpha = np.zeros((h, w, 3), np.float32), np.zeros((h, w), np.float32)
    if rng.random() < 0.7:
        rgb, alpha = car_rear(h, w, pad, d, cy, lw, lh, rng)
    return rgb, alpha, np.clip(light, 0.0, 1.0).astype(np.float32)


def car_rear(
    h: int, w: int, pad: float, d: float, cy: float, lw: float, lh: float, rng: np.random.Generator
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """(h, w, 3) colour and (h, w) alpha of a car seen from behind around lights at x = ``pad`` and ``pad + d``,
    row ``cy``: painted body, dark rear window above, dark bumper, a pale plate and the two tyres below."""
    left, right = pad - 1.6 * lw, pad + d + 1.6 * lw
    top, bottom = cy - 2.0 * lh, cy + 3.2 * lh
    inset = 0.12 * (right - left)
    body = polygon(h, w, np.array([[left + 0.3 * lw, top], [right - 0.3 * lw, top], [right, cy], [right, bottom],
                                   [left, bottom], [left, cy]]))  # fmt: skip
    glass = polygon(h, w, np.array([[left + inset + 0.1 * d, top - 2.6 * lh], [right - inset - 0.1 * d, top - 2.6 * lh],
                                    [right - inset * 0.4, top + 0.5], [left + inset * 0.4, top + 0.5]]))  # fmt: skip
    plate = polygon(h, w, np.array([[w / 2 - 0.13 * d, cy + 0.9 * lh], [w / 2 + 0.13 * d, cy + 0.9 * lh],
                                    [w / 2 + 0.13 * d, cy + 2.1 * lh], [w / 2 - 0.13 * d, cy + 2.1 * lh]]))  # fmt: skip
    _, y = _grid(h, w)
    paint = rng.uniform(0.05, 0.6) * np.asarray(rng.uniform(0.5, 1.0, 3), np.float32)
    shade = np.clip(1.05 - 0.5 * (y - top) / max(bottom - top, 1.0), 0.4, 1.1)
    rgb = paint[None, None, :] * shade[..., None]
    rgb = np.where((y > cy + 2.4 * lh)[..., None], np.float32(0.06), rgb)  # bumper
    rgb = np.where((glass > body)[..., None], np.float32(0.08) + 0.1 * paint, rgb)
    rgb = np.where((plate > 0.5)[..., None], np.float32(0.8), rgb)
    tyres = [polygon(h, w, np.array([[x0, bottom - 0.5 * lh], [x0 + 1.6 * lw, bottom - 0.5 * lh],
                                     [x0 + 1.6 * lw, bottom + 1.3 * lh], [x0, bottom + 1.3 * lh]]))
             for x0 in (left + 0.4 * lw, right - 2.0 * lw)]  # fmt: skip
    tyre = np.maximum(*tyres)
    rgb = np.where((tyre > body)[..., None], np.float32(0.04), rgb)
    return np.clip(rgb, 0, 1).astype(np.float32), np.maximum(np.maximum(body, glass), tyre).astype(np.float32)


def draw_glare(size: float, rng: np.random.Generator) -> Layers:
    """Glare: an anamorphic streak (a thin line of light ``size`` pixels long through a bright point, nearly
    horizontal) or a light's reflection on a glossy floor (a vertical warm smear ``size`` tall, rippled)."""
    colour = warm(rng.uniform(2500.0, 6500.0))
    if rng.random() < 0.5:
        w, h = int(size) | 1, max(int(0.2 * size), 9) | 1
        angle = rng.normal(0.0, 0.05)
        line = gaussian(h, w, w / 2, h / 2, size / 4.5, rng.uniform(0.6, 1.6), angle)
        point = gaussian(h, w, w / 2, h / 2, 0.04 * size + 1, 0.04 * size + 1)
        light = (0.7 * line + point)[..., None] * (0.5 * colour + 0.5)
    else:
        h, w = int(size) | 1, max(int(0.25 * size), 7) | 1
        _, y = _grid(h, w)
        ripple = 0.7 + 0.3 * np.sin(y / rng.uniform(1.5, 4.0) + rng.uniform(0, 6))
        smear = gaussian(h, w, w / 2, 0.3 * h, 0.1 * w + 1.0, h / 3.5) * ripple * rng.uniform(0.45, 0.85)
        light = smear[..., None] * colour
    return np.zeros((h, w, 3), np.float32), np.zeros((h, w), np.float32), np.clip(light, 0, 1).astype(np.float32)


def open_sky(rgb: NDArray[np.uint8]) -> NDArray[np.bool_]:
    """(H, W) bool: :func:`synth.sites.sky_like` pixels connected to the top row (8-connectivity)."""
    n, labels = cv2.connectedComponents(sky_like(rgb).astype(np.uint8), connectivity=8)
    top = np.unique(labels[0])
    return np.isin(labels, top[top > 0])


def blue(rgb: NDArray[np.uint8], where: NDArray[np.bool_]) -> bool:
    """Whether the pixels ``where`` of ``rgb`` are blue on average (CIE b* below -5)."""
    lab = cv2.cvtColor(rgb, cv2.COLOR_RGB2LAB)[where].astype(np.float32)
    return bool(lab.size) and float(lab[:, 2].mean()) - 128.0 < -5.0


def draw_sun(background: NDArray[np.uint8], horizon: float, rng: np.random.Generator) -> Layers | None:
    """A low sun on the whole image (H, W): a sunset gradient laid over the sky above the ``horizon`` row (sky =
    :func:`open_sky`, softened) and a sun disc with bloom just above the horizon; None when under 30 % of the
    image above the horizon or 40 % of its top row is open sky, or that sky is not blue (indoors: a white ceiling;
    a sky at sunset already), or the horizon is too close to the top for the disc."""
    h, w = background.shape[:2]
    r = w * rng.uniform(0.012, 0.028)
    cy = horizon - rng.uniform(0.6, 3.5) * r
    if cy < 2 * r or horizon >= h:
        return None
    x, y = _grid(h, w)
    above = np.clip((horizon - y) / 3.0, 0.0, 1.0)
    sky = open_sky(background)
    if sky[: int(horizon)].mean() < 0.3 or sky[0].mean() < 0.4 or not blue(background, sky):
        return None
    sky = cv2.GaussianBlur(sky.astype(np.float32), (0, 0), sigmaX=max(2.0, 0.02 * w)) * above
    cx = w * rng.uniform(0.1, 0.9)
    up = np.clip((horizon - y) / max(horizon, 1.0), 0.0, 1.0)
    orange, violet = np.array([1.0, 0.5, 0.15], np.float32), np.array([0.72, 0.42, 0.55], np.float32)
    rgb = (orange * (1 - up[..., None]) + violet * up[..., None]).astype(np.float32)
    near = np.exp(-(((x - cx) / (0.45 * w)) ** 2))
    alpha = (sky * rng.uniform(0.45, 0.8) * (1.0 - up) ** 1.5 * (0.55 + 0.45 * near)).astype(np.float32)
    colour = warm(rng.uniform(1900.0, 2800.0))
    disc = ellipse(h, w, cx, cy, r, r) * above
    bloom = 0.6 * gaussian(h, w, cx, cy, 2 * r, 2 * r) + 0.3 * gaussian(h, w, cx, cy, 6 * r, 5 * r)
    light = disc[..., None] * (0.75 * colour + 0.25) + (bloom * above)[..., None] * colour
    return rgb, alpha, np.clip(light, 0.0, 1.0).astype(np.float32)


#: The kinds drawn at a size in pixels (radius, height, length or lamp spacing), by their drawing function.
DRAWERS: dict[str, Callable[[float, np.random.Generator], Layers]] = {
    "lamp": draw_lamp,
    "cone": draw_cone,
    "cloth": draw_cloth,
    "clothing": draw_clothing,
    "taillights": draw_taillights,
    "glare": draw_glare,
}
#: Size range as a fraction of the image height where no depth says better (lamp: bulb radius).
SIZE_SHARE: dict[str, tuple[float, float]] = {
    "lamp": (0.006, 0.02),
    "cone": (0.06, 0.25),
    "cloth": (0.06, 0.25),
    "clothing": (0.1, 0.3),
    "taillights": (0.08, 0.3),
    "glare": (0.08, 0.4),
}
TAILLIGHT_SPACING_M = (1.1, 1.5)  # metres between a car's rear lights
TAILLIGHT_HEIGHT_M = (0.6, 1.0)  # metres above the ground


def horizon_row(meta: dict, height: int, fy: float) -> float | None:
    """The horizon's row (pixels from the top) of a view, from its metadata: a photo's ``horizon`` (share of the
    height), a panorama view's ``pitch`` (degrees, negative = down) or a render's camera pose (y up, looking
    along -z); None when the metadata tells none of them."""
    if "horizon" in meta:
        return float(meta["horizon"]) * height
    if "pitch" in meta:
        return height / 2 + fy * float(np.tan(np.radians(meta["pitch"])))
    pose = meta.get("camera", {}).get("pose")
    if pose is None:
        return None
    forward_up = -float(np.asarray(pose)[1, 2])
    return height / 2 + fy * float(np.tan(np.arcsin(np.clip(forward_up, -1.0, 1.0))))


def anchor(kind: str, depth: NDArray[np.float32], fy: float, rng: np.random.Generator) -> tuple[float, float, float]:
    """(size px, centre x, bottom y) of a distractor of ``kind`` (``size`` as :data:`DRAWERS` take it): a ground
    kind on a random ground pixel (depth > 0) sized by its depth, else anywhere (lamps in the upper two thirds)."""
    h, w = depth.shape
    ground = np.flatnonzero(depth > 0)
    if kind in GROUND_HEIGHT_M and len(ground):
        by, bx = divmod(int(ground[rng.integers(len(ground))]), w)
        d = float(depth[by, bx])
        if kind == "taillights":
            spacing = min(fy * rng.uniform(*TAILLIGHT_SPACING_M) / d, 0.35 * w)
            return spacing, bx, by - spacing * rng.uniform(*TAILLIGHT_HEIGHT_M) / TAILLIGHT_SPACING_M[1]
        return min(fy * rng.uniform(*GROUND_HEIGHT_M[kind]) / d, 0.5 * h), bx, by
    size = h * rng.uniform(*SIZE_SHARE[kind])
    top = 2 * h / 3 if kind == "lamp" else h
    return size, rng.uniform(0, w), rng.uniform(0.1 * h, top)


def _cropped(kind: str, layers: Layers, x: int, y: int, photo: str = "") -> Distractor | None:
    """The layers cut to the pixels they change (alpha or light >= 1/255) as a :class:`Distractor` (cut from
    ``photo``, if any)."""
    rgb, alpha, light = layers
    shown = (alpha >= 1 / 255) | (light.max(axis=-1) >= 1 / 255)
    rows, cols = np.flatnonzero(shown.any(axis=1)), np.flatnonzero(shown.any(axis=0))
    if not rows.size:
        return None
    cut = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    over = np.concatenate([rgb[cut], alpha[cut][..., None]], axis=-1)
    as_u8 = [unit_to_u8(v) for v in (over, light[cut])]
    sprite = Sprite(as_u8[0], as_u8[1], np.zeros(alpha[cut].shape, bool))
    return Distractor(kind, sprite, x + int(cols[0]), y + int(rows[0]), photo)


def draw_region(region: Region, height: int, rng: np.random.Generator) -> Layers:
    """A fire-like photo ``region`` as layers ``height`` px tall (aspect kept; mirrored with probability 0.5):
    its pixels laid over with its alpha, no light of its own."""
    rgba = region.rgba[:, ::-1] if rng.random() < 0.5 else region.rgba
    h = max(int(height), 2)
    w = max(int(round(h * rgba.shape[1] / rgba.shape[0])), 1)
    interp = cv2.INTER_AREA if h < rgba.shape[0] else cv2.INTER_LINEAR
    f = cv2.resize(np.ascontiguousarray(rgba), (w, h), interpolation=interp).astype(np.float32) / 255.0
    return f[..., :3], np.ascontiguousarray(f[..., 3]), np.zeros((h, w, 3), np.float32)


def place_region(
    regions: Sequence[Region], height: int, width: int, rng: np.random.Generator, kind: str = PHOTO_KIND
) -> Distractor | None:
    """A ``kind`` (one of :data:`PHOTO_KINDS`) distractor: a random one of ``regions`` at :data:`PHOTO_SCALE` x its
    height share of an image ``height`` x ``width`` px (8 px .. 0.6 of the height), wholly inside it at a random
    spot."""
    region = regions[int(rng.integers(len(regions)))]
    size = int(np.clip(region.height_share * height * rng.uniform(*PHOTO_SCALE), 8, 0.6 * height))
    layers = draw_region(region, size, rng)
    h, w = layers[1].shape
    x, y = int(rng.integers(0, max(width - w, 0) + 1)), int(rng.integers(0, max(height - h, 0) + 1))
    return _cropped(kind, layers, x, y, region.photo)


def make_distractor(
    kind: str, background: NDArray[np.uint8], depth: NDArray[np.float32], fy: float, horizon: float | None,
    rng: np.random.Generator, regions: Sequence[Region] = (),
) -> Distractor | None:  # fmt: skip
    """One distractor of ``kind`` for the (H, W, 3) ``background`` with its (H, W) ``depth`` (metres, 0 = not
    ground), focal length ``fy`` (pixels) and ``horizon`` row (None: unknown; no sun then); None when the kind does
    not fit this view (a sun without sky, a photo kind without ``regions`` of its rule)."""
    if kind in PHOTO_KINDS:
        mine = [r for r in regions if r.kind == kind]
        return place_region(mine, *background.shape[:2], rng, kind) if mine else None
    if kind == "sun":
        layers = draw_sun(background, horizon, rng) if horizon is not None else None
        return None if layers is None else _cropped(kind, layers, 0, 0)
    size, cx, bottom = anchor(kind, depth, fy, rng)
    layers = DRAWERS[kind](max(size, 2.0), rng)
    h, w = layers[1].shape
    top = bottom - h / 2 if kind in ("lamp", "glare", "taillights") else bottom - h
    return _cropped(kind, layers, int(round(cx - w / 2)), int(round(top)))


def overlaps(box: Sequence[float], others: Sequence[Sequence[float]]) -> bool:
    """Whether the [x, y, w, h] ``box`` intersects any of ``others`` (same frame)."""
    x, y, w, h = box
    return any(x < ox + ow and ox < x + w and y < oy + oh and oy < y + h for ox, oy, ow, oh in others)


def kinds_here(kinds: Sequence[str], meta: dict) -> tuple[str, ...]:
    """``kinds`` that fit a view: in a rendered room (metadata with a camera pose, not a kit street) without the
    :data:`OUTDOOR_KINDS` (no car rear over a bathroom sink); photos, panoramas and streets keep every kind."""
    room = "pose" in meta.get("camera", {}) and meta.get("kind") != "street"
    return tuple(k for k in kinds if not (room and k in OUTDOOR_KINDS))


def plan_distractors(
    cfg: DistractorConfig, background: NDArray[np.uint8], depth: NDArray[np.float32], meta: dict, fy: float,
    avoid: Sequence[Sequence[float]], rng: np.random.Generator, tries: int = 8, regions: Sequence[Region] = (),
) -> list[Distractor]:  # fmt: skip
    """The distractors of one image: none for a ``1 - cfg.share`` of images, else 1..``cfg.max`` of random kinds
    (each redrawn up to ``tries`` times), none overlapping the ``avoid`` boxes [x, y, w, h] (the flames) nor each
    other, all inside the image at least in part. ``regions``: the regions the :data:`PHOTO_KINDS` are cut from
    (:mod:`synth.photo_regions`; each kind takes those of its rule)."""
    if rng.random() >= cfg.share:
        return []
    kinds = kinds_here(cfg.kinds, meta)
    h, w = background.shape[:2]
    horizon = horizon_row(meta, h, fy)
    out: list[Distractor] = []
    for _ in range(int(rng.integers(1, cfg.max + 1)) if kinds else 0):
        for _ in range(tries):
            d = make_distractor(kinds[int(rng.integers(len(kinds)))], background, depth, fy, horizon, rng, regions)
            if d is None or not overlaps(d.box, [[0, 0, w, h]]):
                continue
            if not overlaps(d.box, [*avoid, *(o.box for o in out)]):
                out.append(d)
                break
    return out


def draw_distractors(image: NDArray[np.uint8], items: Sequence[Distractor], emissive: bool) -> NDArray[np.uint8]:
    """(H, W, 3) uint8 ``image`` with the ``items`` that are (``emissive``) or are not light sources drawn on it:
    their ``over`` laid over, their light screened on (:func:`synth.composite.composite`, no glow, no cast)."""
    from synth.composite import Placement, composite

    chosen = [d for d in items if d.emissive == emissive]
    if not chosen:
        return image
    placements = [Placement(d.sprite, d.x, d.y, *d.sprite.size, "screen", 0.0, 0.0, False) for d in chosen]
    return composite(image, placements).image

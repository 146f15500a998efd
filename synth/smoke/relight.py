"""A labelled frame's own smoke re-lit in place (``smoke.relight``): the same smoke, where its annotator saw and
boxed it, in a new colour and density, so its boxes stay the frame's own.

Smoke is read as :mod:`synth.smoke.matte` reads it (Koschmieder's law, ``I = J (1 - a) + A a``: opacity ``a``,
smoke colour ``A`` estimated from the box, kept off the fire), over the box's *reach*: the box widened by
:data:`MARGIN` of its size on each side, within the frame, since smoke goes on past a box drawn around it. The
change fades out by an elliptical window over the reach, except on a side the reach shares with the frame: there
the smoke goes on out of view and so does the change (a fog that fills the frame is re-lit whole). What is behind
the smoke is recovered as ``J = (I - A a) / max(1 - a, CLEAR_FLOOR)`` (clipped to 0..1: where the smoke is nearly
opaque ``J`` is poorly known, but it then weighs little), and the reach is recomposed as ``I' = J (1 - a') + A' a'``
with ``a' = min(k a, MAX_OPACITY)``: density ``k`` from :data:`DENSITY`, and a new colour ``A'``, a grey of ``A``'s
own luma times a ratio from :data:`COLOURS` (white steam, grey, dark grey: the smoke stays lit as its frame lit it,
dark in a dark frame), tinted by up to :data:`TINT` per channel.

Left as it was: a box that cannot be matted (black soot, too little haze); a box whose haze does not fade before
the reach's windowed sides (its rim at least :data:`EDGE` as hazy as its core; black bars not counted), where the
window would cut an ellipse of grey or white out of the haze, as around black smoke in the sky, which the dark
channel prior reads as haze (He et al. name the limit; seen on fire-smoke-608); and a box whose re-lit smoke would
not be seen: its pixels of opacity ``a'`` at least :data:`SEEN_OPACITY` must differ from ``J`` by a median ΔE of
:data:`synth.compose.visibility.SMOKE_DELTA_E` or more (the threshold the plumes are boxed at).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ground.image.imageio import unit_to_u8
from synth.compose.light import REC601
from synth.compose.ramps import window
from synth.compose.visibility import SMOKE_DELTA_E, delta_e
from synth.smoke.matte import PATCH, WINDOW_INNER, dark_channel, haze

Box = tuple[int, int, int, int]  # x, y, w, h px

MARGIN = 0.25  # the reach: the box widened by this share of its width and height on each side
CLEAR_FLOOR = 0.25  # 1 - a is at least this when what is behind the smoke is recovered
MAX_OPACITY = 0.97  # a re-lit smoke's opacity stays below this
DENSITY = (0.8, 1.3)  # the opacity's factor k [lo, hi]
COLOURS: dict[str, tuple[float, float]] = {"white": (0.95, 1.1), "grey": (0.6, 0.85), "dark": (0.4, 0.6)}
# the new colour's luma over the old colour's luma, [lo, hi] per colour (each colour equally likely)
TINT = 0.03  # the new colour's channels differ from its grey by up to this share each
SEEN_OPACITY = 0.25  # the pixels whose contrast decides whether re-lit smoke is seen
EDGE = 0.7  # a box is re-lit only when the haze on its reach's rim is under this share of the haze in its core
BLACK = 0.12  # luma (0..1) below which a pixel is not counted in that comparison


def reach(box: Box, width: int, height: int) -> tuple[Box, NDArray[np.float32]]:
    """The reach of integer ``box`` in a ``width`` x ``height`` frame (x, y, w, h px: the box widened by
    :data:`MARGIN`, within the frame) and its (h, w) float32 window: elliptical, but open (1 up to the edge) on each
    side the reach shares with the frame."""
    x, y, w, h = box
    dx, dy = int(round(MARGIN * w)), int(round(MARGIN * h))
    x0, y0, x1, y1 = max(x - dx, 0), max(y - dy, 0), min(x + w + dx, width), min(y + h + dy, height)
    rw, rh = x1 - x0, y1 - y0
    left, top = (rw if x0 == 0 else 0), (rh if y0 == 0 else 0)  # an open side: the window's fall lies past it
    right, bottom = (rw if x1 == width else 0), (rh if y1 == height else 0)
    shape = window(rh + top + bottom, rw + left + right, WINDOW_INNER)[top : top + rh, left : left + rw]
    return (x0, y0, rw, rh), np.ascontiguousarray(shape)


def fades_out(rgb: NDArray[np.uint8], region: Box, airlight: NDArray[np.float32], shape: NDArray[np.float32]) -> bool:
    """Whether the haze of integer ``region`` (x, y, w, h px) of the (H, W, 3) uint8 RGB image fades before the
    sides its window ``shape`` (h, w) closes: the mean dark channel over the smoke's colour ``airlight`` (3,) 0..1
    (:mod:`synth.smoke.matte`) where the window is below half (its rim) is under :data:`EDGE` of its mean where
    the window is whole (its core); pixels darker than :data:`BLACK` (a frame's black bars) not counted. True when
    the window closes no side."""
    x, y, w, h = region
    crop = rgb[y : y + h, x : x + w].astype(np.float32) / 255.0
    raw = dark_channel(crop / np.maximum(airlight, 0.05), max(int(PATCH * min(w, h)) | 1, 3))
    lit = crop @ REC601 >= BLACK
    core, rim = (shape >= 1.0) & lit, (shape < 0.5) & lit
    if not rim.any():
        return True
    return bool(core.any()) and float(raw[rim].mean()) < EDGE * float(raw[core].mean())


def relight_box(
    rgb: NDArray[np.uint8], box: Box, fires: Sequence[Box], rng: np.random.Generator
) -> tuple[Box, NDArray[np.uint8], dict] | None:
    """The reach (x, y, w, h px) of integer ``box`` of the (H, W, 3) uint8 RGB image, its (h, w, 3) uint8 RGB crop
    with the smoke re-lit (module docstring), and a record of the colour drawn; None when the box is left as it
    was. ``fires``: the image's fire boxes (x, y, w, h px), untouched. Draws the colour, ratio, tint and density
    from ``rng`` whenever the box's smoke is matted."""
    own = haze(rgb, box, fires)
    if own is None:
        return None
    region, shape = reach(box, rgb.shape[1], rgb.shape[0])
    got = haze(rgb, region, fires, shape=shape, airlight=own.airlight)
    if got is None or not fades_out(rgb, region, own.airlight, shape):
        return None
    colour = list(COLOURS)[int(rng.integers(len(COLOURS)))]
    ratio = float(rng.uniform(*COLOURS[colour]))
    tint = rng.uniform(-TINT, TINT, 3).astype(np.float32)
    density = float(rng.uniform(*DENSITY))
    x, y, w, h = region
    image = rgb[y : y + h, x : x + w].astype(np.float32) / 255.0
    a = got.opacity[..., None]
    behind = np.clip((image - got.airlight * a) / np.maximum(1.0 - a, CLEAR_FLOOR), 0.0, 1.0)
    grey = float(got.airlight @ REC601) * ratio
    new_colour = np.clip(grey * (1.0 + tint), 0.0, 1.0).astype(np.float32)
    new_a = np.minimum(density * a, MAX_OPACITY)
    relit = unit_to_u8(behind * (1.0 - new_a) + new_colour * new_a)
    seen = new_a[..., 0] >= SEEN_OPACITY
    if not seen.any() or float(np.median(delta_e(relit, unit_to_u8(behind))[seen])) < SMOKE_DELTA_E:
        return None
    return region, relit, {"colour": colour, "ratio": round(ratio, 3), "density": round(density, 3)}


def relight_frame(
    rgb: NDArray[np.uint8],
    smoke_boxes: Sequence[Sequence[float]],
    fire_boxes: Sequence[Sequence[float]],
    rng: np.random.Generator,
) -> tuple[NDArray[np.uint8], list[dict | None]]:
    """A copy of the (H, W, 3) uint8 RGB frame with each of its ``smoke_boxes`` (x, y, w, h px, its labels) re-lit
    in turn (:func:`relight_box`; ``fire_boxes`` x, y, w, h px left untouched), and per box its record or None where
    it was left as it was. The boxes stay the frame's labels."""
    out = rgb.copy()
    height, width = rgb.shape[:2]
    fires = [_pixels(b, width, height) for b in fire_boxes]
    records: list[dict | None] = []
    for b in smoke_boxes:
        box = _pixels(b, width, height)
        got = relight_box(out, box, fires, rng) if box[2] >= 3 and box[3] >= 3 else None
        if got is not None:
            (x, y, w, h), relit, _ = got
            out[y : y + h, x : x + w] = relit
        records.append(None if got is None else got[2])
    return out, records


def _pixels(box: Sequence[float], width: int, height: int) -> Box:
    """Box (x, y, w, h) px rounded to whole pixels and clipped to a ``width`` x ``height`` image."""
    x0, y0 = max(int(round(box[0])), 0), max(int(round(box[1])), 0)
    x1, y1 = min(int(round(box[0] + box[2])), width), min(int(round(box[1] + box[3])), height)
    return x0, y0, max(x1 - x0, 0), max(y1 - y0, 0)

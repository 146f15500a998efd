"""A labelled smoke box of a real image as a soft-alpha sprite: smoke has no edge, so it is matted, not cut.

Smoke is modelled as haze is (Koschmieder's law): ``I = J t + A (1 - t)`` per pixel, ``J`` what is behind it, ``A``
the smoke's colour, ``t`` its transmission, so the sprite's opacity is ``1 - t``. The opacity comes from the *dark
channel prior* of He, Sun & Tang (2009, "Single image haze removal using dark channel prior", CVPR): in a clear
patch some channel is near black, so ``1 - t = w * min over the patch and channels of I / A`` (``w`` =
:data:`KEEP_HAZE`); the patch is :data:`PATCH` of the box's shorter side, and the blocky result is refined by a
guided filter on the image (He, Sun & Tang 2013). ``A`` is the mean of the box's pixels of highest dark channel (the
top :data:`CORE_SHARE`), as He et al. estimate the airlight. The prior needs light smoke: a box whose ``A`` has a
luma below :data:`MIN_LUMA` (black soot, which darkens what is behind it like a shadow) or whose smoke covers less
than :data:`MIN_OPACITY` on average is not matted. Nor is a box whose haze lies around its centre rather than in it
(mean haze inside half the way from the box's centre to its edge below :data:`CENTRE_HAZE` of the mean beyond): the
prior reads a bright background as haze (He et al. name the sky as its limit), and around dark grey smoke against
the sky or a hazy landscape its "smoke" is that background, with a hole where the smoke is. An annotator centres a
box on the smoke; a fog that fills the box is as dense at its centre as at its sides. Warm fire-coloured pixels and
the image's fire boxes get opacity 0, softly and a little beyond them (a flame inside a plume is no smoke, and would
be pasted unlabelled).

The sprite shows no rectangle and no halo of its source frame: where it is opaque its RGB is the image's (the
smoke's own texture), where it is thin it is ``A`` (never the background behind it), and its opacity is multiplied
by an elliptical window, 1 inside :data:`WINDOW_INNER` of the way from the box's centre to its edge and 0 on it (a
labelled box is drawn loosely around smoke; no straight side may show).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.image.imageio import unit_to_u8
from synth.compose.light import REC601
from synth.compose.ramps import smoothstep, window
from synth.flames.firepixels import fire_mask

KEEP_HAZE = 0.95  # He et al.'s w: a little haze is left, so distant objects keep their depth
PATCH = 0.06  # dark-channel patch, x the box's shorter side (at least 3 px, odd)
CORE_SHARE = 0.01  # share of the box's pixels of highest dark channel whose mean is the smoke's colour A
MIN_LUMA = 0.35  # smoke darker than this (luma of A, 0..1) is not matted: the prior needs light smoke
MIN_OPACITY = 0.15  # mean opacity inside the window a matted box needs
OWN_TEXTURE = (0.45, 0.85)  # opacity over which the sprite's RGB goes from A to the image's own pixels
WARM = 0.15  # a fire-coloured pixel (synth.flames.firepixels.fire_mask) kept out of a matte is also this much redder
# than blue (R - B, 0..1): white smoke passes the fire rule's bright-core test
CENTRE_HAZE = 0.85  # least ratio of the haze at a box's centre to the haze near its sides (module docstring)
WINDOW_INNER = 0.55  # the elliptical window is 1 inside this share of the way from the box's centre to its edge


def dark_channel(image: NDArray[np.float32], patch: int) -> NDArray[np.float32]:
    """(h, w) minimum over the channels and a ``patch`` x ``patch`` square of the (h, w, 3) float ``image``."""
    return cv2.erode(image.min(axis=-1), np.ones((patch, patch), np.uint8))


def centred(haze: NDArray[np.float32]) -> bool:
    """Whether the (h, w) ``haze`` of a box is at least :data:`CENTRE_HAZE` as dense inside half the way from the
    box's centre to its edge (an ellipse) as between there and the edge."""
    h, w = haze.shape
    v, u = np.linspace(-1.0, 1.0, h), np.linspace(-1.0, 1.0, w)
    r = np.hypot(u[None, :], v[:, None])
    centre, sides = haze[r < 0.5], haze[(r >= 0.5) & (r < 1.0)]
    if not centre.size or not sides.size:
        return True
    return float(centre.mean()) >= CENTRE_HAZE * float(sides.mean())


def matte(
    rgb: NDArray[np.uint8], box: tuple[int, int, int, int], fires: Sequence[tuple[int, int, int, int]] = ()
) -> tuple[NDArray[np.uint8], float] | None:
    """The (h, w, 4) uint8 straight-alpha RGBA smoke sprite of integer box (x, y, w, h) of the (H, W, 3) uint8 RGB
    image and its mean opacity inside the window, or None when the box cannot be matted (dark smoke, too little of
    it, or haze around the box's centre rather than in it): module docstring. ``fires``: the image's fire boxes (x,
    y, w, h px), opacity 0 inside them."""
    x, y, w, h = box
    crop = rgb[y : y + h, x : x + w]
    image = crop.astype(np.float32) / 255.0
    patch = max(int(PATCH * min(w, h)) | 1, 3)
    raw_dark = dark_channel(image, patch)
    top = raw_dark >= np.quantile(raw_dark, 1.0 - CORE_SHARE)
    airlight = image[top].mean(axis=0)
    if float(airlight @ REC601) < MIN_LUMA:
        return None
    haze = KEEP_HAZE * dark_channel(image / np.maximum(airlight, 0.05)[None, None, :], patch)
    if not centred(haze):
        return None
    guide = cv2.cvtColor(crop, cv2.COLOR_RGB2GRAY).astype(np.float32) / 255.0
    alpha = cv2.ximgproc.guidedFilter(guide, np.clip(haze, 0.0, 1.0).astype(np.float32), 2 * patch, 1e-3)
    warm = image[..., 0] - image[..., 2] > WARM  # a flame's white core passes the fire rule, and so would white smoke
    clear = (fire_mask(crop) & warm).astype(np.float32)
    for fx, fy, fw, fh in fires:
        clear[max(fy - y, 0) : max(fy + fh - y, 0), max(fx - x, 0) : max(fx + fw - x, 0)] = 1.0
    soft = np.clip(2.0 * cv2.GaussianBlur(clear, (0, 0), patch / 2.0), 0.0, 1.0)
    clear = np.maximum(clear, soft)  # the fire, and softly beyond it
    shape = window(h, w, WINDOW_INNER)
    alpha = np.clip(alpha, 0.0, 1.0) * shape * (1.0 - clear)
    opacity = float((alpha * shape).sum() / max(float(shape.sum()), 1e-6))
    if opacity < MIN_OPACITY:
        return None
    own = smoothstep(alpha, *OWN_TEXTURE)[..., None]
    colour = own * image + (1.0 - own) * airlight[None, None, :]
    return np.dstack([unit_to_u8(colour), unit_to_u8(alpha)]), opacity

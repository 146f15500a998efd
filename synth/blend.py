"""How a sprite's layers are laid onto the image: the blend modes beyond the emissive ``screen`` / ``add`` of
:mod:`synth.composite`, and their per-flame settings.

Modes (one drawn per flame from :attr:`BlendConfig.modes`):

- ``screen``, ``add``: the flame is light (the composite's own path: coverage, then emission added / screened);
- ``alpha``: the sprite flattened to straight-alpha RGBA (:func:`synth.sprites.flatten_rgba`) pasted with a
  feathered edge: alpha ramps from 0 at the support's edge to full over ``edge`` pixels inside it;
- ``blur``: the same RGBA with a Gaussian-blurred edge: alpha blurred by ``edge`` (sigma, pixels), the colour kept
  sharp inside (alpha >= 0.5) and spread outward (normalised blur of the premultiplied colour), so the edge
  spills softly over the background while the body keeps its detail;
- ``poisson``: Poisson image editing (``cv2.seamlessClone``, normal clone) of the RGBA laid over the local mean
  background colour, in a window around the sprite: the gradients of the flame, the boundary of the
  background (colours shift; the box is still taken from the final visible mask).

Every function takes and returns float32 images in [0, 1]; randomness only through an explicit ``rng``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.core.imageio import unit_to_u8
from synth.harmonise import Look, sample_look
from synth.schema import check_range

EMISSIVE_MODES: tuple[str, ...] = ("screen", "add")
PASTE_MODES: tuple[str, ...] = ("alpha", "blur", "poisson")
ALL_MODES: tuple[str, ...] = EMISSIVE_MODES + PASTE_MODES
SUPPORT_ALPHA = 0.02  # alpha above which a pixel belongs to a sprite's support (what a paste covers)
POISSON_MARGIN = 4  # pixels of background around the support in the Poisson window


@dataclass(frozen=True)
class BlendConfig:
    """How flames are blended (``configs/synth-method2.yaml`` documents every key). The default is the blend of
    pools made before this config existed (``screen`` or ``add``, nothing matched)."""

    modes: tuple[str, ...] = EMISSIVE_MODES  # one drawn uniformly per flame
    feather_px: tuple[float, float] = (1.0, 4.0)  # alpha: feather width; blur: edge sigma, pixels [lo, hi]
    harmonise: bool = False  # tint each flame towards the local background light (synth.harmonise)
    match_noise: bool = False  # blur and grain each flame like the background around it (synth.harmonise)
    decoys: float = 0.0  # share of images with 1-2 decoy pastes of background patches (synth.decoys), 0..1

    def __post_init__(self) -> None:
        if not self.modes or any(m not in ALL_MODES for m in self.modes):
            raise ValueError(f"blend.modes must be a non-empty list of {', '.join(ALL_MODES)}, got {list(self.modes)}")
        check_range("blend.feather_px", self.feather_px, 0.0)
        if not 0.0 <= self.decoys <= 1.0:
            raise ValueError(f"blend.decoys must be a share in 0..1, got {self.decoys}")

    @property
    def default(self) -> bool:
        """Whether this is today's blend (no extra randomness is drawn)."""
        return self == BlendConfig()


def feather(alpha: NDArray[np.float32], width: float) -> NDArray[np.float32]:
    """(h, w) alpha times a ramp from 0 at the edge of its support (alpha > :data:`SUPPORT_ALPHA`) to 1 at
    ``width`` pixels inside it (the L2 distance transform); ``width`` 0 keeps it as is (a hard edge)."""
    if width <= 0:
        return alpha
    support = np.pad(alpha > SUPPORT_ALPHA, 1).astype(np.uint8)  # the sprite's border counts as outside
    dist = cv2.distanceTransform(support, cv2.DIST_L2, 3)[1:-1, 1:-1]
    return (alpha * np.clip(dist / width, 0.0, 1.0)).astype(np.float32)


def paste(
    img: NDArray[np.float32], rgb: NDArray[np.float32], alpha: NDArray[np.float32], mode: str, edge: float
) -> NDArray[np.float32]:
    """``img`` (h, w, 3) with ``rgb`` (h, w, 3) at straight ``alpha`` (h, w) laid over it in paste ``mode``
    (``alpha``, ``blur`` or ``poisson``; module docstring) with ``edge`` pixels of feather / blur. All three have
    the same (h, w): the caller pads the sprite so a blurred edge or a Poisson window fits (:func:`margin`)."""
    if mode == "alpha":
        a = feather(alpha, edge)[..., None]
        return img * (1.0 - a) + rgb * a
    if mode == "blur":
        if edge <= 0:
            return img * (1.0 - alpha[..., None]) + rgb * alpha[..., None]
        a = cv2.GaussianBlur(alpha, (0, 0), sigmaX=edge)[..., None]
        spread = cv2.GaussianBlur(rgb * alpha[..., None], (0, 0), sigmaX=edge) / np.maximum(a, 1e-6)
        colour = np.where(alpha[..., None] >= 0.5, rgb, spread)  # sharp inside, the edge colour spread outside
        return img * (1.0 - a) + colour * a
    if mode == "poisson":
        return poisson(img, rgb, alpha)
    raise ValueError(f"{mode!r} is not a paste mode; choose one of {', '.join(PASTE_MODES)}")


def margin(mode: str, edge: float) -> int:
    """Pixels of background a paste in ``mode`` needs around the sprite (blur spill, Poisson boundary)."""
    if mode == "blur":
        return int(np.ceil(3.0 * edge))
    return POISSON_MARGIN if mode == "poisson" else 0


def poisson(img: NDArray[np.float32], rgb: NDArray[np.float32], alpha: NDArray[np.float32]) -> NDArray[np.float32]:
    """Poisson clone (``cv2.seamlessClone``, normal clone) of ``rgb`` at ``alpha`` over the mean colour of ``img``
    into ``img`` (all (h, w)), inside the support dilated by 2 px and kept :data:`POISSON_MARGIN` // 2 px off the
    window's border. The clone's mask box is made odd-sized so its centre is exact in every OpenCV version."""
    h, w = alpha.shape
    support = cv2.dilate((alpha > SUPPORT_ALPHA).astype(np.uint8), np.ones((5, 5), np.uint8))
    inset = POISSON_MARGIN // 2
    mask = np.zeros((h, w), np.uint8)
    mask[inset : h - inset, inset : w - inset] = support[inset : h - inset, inset : w - inset]
    if mask.sum() == 0 or h < 2 * inset + 3 or w < 2 * inset + 3:
        return img
    x, y, bw, bh = cv2.boundingRect(mask)
    if bw % 2 == 0:  # widen the box by one column (inside the window: the inset leaves room)
        mask[y, x + bw if x + bw < w - 1 else x - 1] = 1
    if bh % 2 == 0:
        mask[y + bh if y + bh < h - 1 else y - 1, x] = 1
    x, y, bw, bh = cv2.boundingRect(mask)
    back = img.reshape(-1, 3).mean(axis=0)
    src = back * (1.0 - alpha[..., None]) + rgb * alpha[..., None]
    as_u8 = [unit_to_u8(v) for v in (src, img)]
    out = cv2.seamlessClone(as_u8[0], as_u8[1], mask * 255, (x + bw // 2, y + bh // 2), cv2.NORMAL_CLONE)
    return np.where(mask[..., None] > 0, out.astype(np.float32) / 255.0, img)


def sample_edge(cfg: BlendConfig, mode: str, rng: np.random.Generator) -> float:
    """A flame's edge in pixels: feather width (``alpha``) or blur sigma (``blur``) from ``cfg.feather_px``; 0 for
    the other modes (no draw, so adding a mode to the list keeps the other flames' draws)."""
    return float(rng.uniform(*cfg.feather_px)) if mode in ("alpha", "blur") else 0.0


def sample_style(
    cfg: BlendConfig,
    mode: str,
    scene: NDArray[np.uint8],
    rect: tuple[int, int, int, int],
    sprite_rgb: NDArray[np.uint8],
    rng: np.random.Generator,
) -> tuple[float, Look]:
    """(edge, look) of a sprite pasted in ``mode`` at ``rect`` [x, y, w, h] on the (H, W, 3) uint8 ``scene``
    (``sprite_rgb`` (h, w, 3) uint8: its colour at the placed size, for the blur match): :func:`sample_edge` and
    :func:`synth.harmonise.sample_look` as ``cfg`` asks (a neutral look, no draws, when it asks for neither)."""
    edge = sample_edge(cfg, mode, rng)
    if not (cfg.harmonise or cfg.match_noise):
        return edge, Look()
    return edge, sample_look(scene, rect, sprite_rgb, cfg.harmonise, cfg.match_noise, rng)

"""A sprite made to look like it was filmed with its background: tinted by the local light, blurred as much as
the background's edges are blurred and grained with the background's noise.

Estimators (on (h, w, 3) uint8 RGB, grey = OpenCV's luma):

- :func:`light_tint`: the local mean colour's cast (each channel over the channels' mean) raised to a strength;
- :func:`noise_sigma`: Immerkær's fast noise estimate (1996): the mean absolute response of the Laplacian-difference
  kernel [[1, -2, 1], [-2, 4, -2], [1, -2, 1]] times sqrt(pi / 2) / 6, in 0..255 grey units, over the smoother
  half of the pixels;
- :func:`edge_blur`: the re-blur estimate of edge sharpness (Zhuo & Sim 2011): at the strongest edges the ratio
  ``r`` of gradient magnitudes before and after a Gaussian blur of sigma ``s0`` gives the edge's own blur
  ``s0 / sqrt(r^2 - 1)`` (pixels), less the estimate of a perfect step (:data:`SOBEL_FLOOR`) in quadrature.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

_IMMERKAER = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)
REBLUR_SIGMA = 1.0  # s0 of the re-blur estimate, pixels
SOBEL_FLOOR = 0.83  # what the estimate reports for a perfect step (the Sobel's own blur), removed in quadrature
MAX_BLUR = 4.0  # largest edge blur reported, pixels
TINT_RANGE = (0.6, 1.5)  # per-channel tint gains are clipped to this


@dataclass(frozen=True)
class Look:
    """What a sprite gets to match its background: per-channel ``tint`` gains, extra Gaussian ``soften`` (sigma,
    pixels of the image) and ``grain`` (noise sigma, 0..255) drawn with ``grain_seed``."""

    tint: tuple[float, float, float] = (1.0, 1.0, 1.0)
    soften: float = 0.0
    grain: float = 0.0
    grain_seed: int = 0

    @property
    def neutral(self) -> bool:
        return self.tint == (1.0, 1.0, 1.0) and self.soften == 0.0 and self.grain == 0.0

    def to_json(self) -> dict:
        return {
            "tint": [round(t, 4) for t in self.tint],
            "soften": round(self.soften, 3),
            "grain": round(self.grain, 3),
        }


def _grey(rgb: NDArray[np.uint8]) -> NDArray[np.float32]:
    return cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32)


def light_tint(rgb: NDArray[np.uint8], strength: float) -> tuple[float, float, float]:
    """Per-channel gains (clipped to :data:`TINT_RANGE`) carrying ``strength`` (0..1) of the colour cast of the
    (h, w, 3) uint8 region ``rgb``: ``(mean_c / mean) ** strength``."""
    mean = rgb.reshape(-1, 3).astype(np.float64).mean(axis=0) + 1.0
    gains = np.clip((mean / mean.mean()) ** strength, *TINT_RANGE)
    return tuple(float(g) for g in gains)  # type: ignore[return-value]


def noise_sigma(rgb: NDArray[np.uint8]) -> float:
    """Immerkær's noise sigma of the (h, w, 3) uint8 region over its smoother half (pixels whose gradient
    magnitude is at most the median: texture would count as noise); 0 for regions under 5 x 5."""
    grey = _grey(rgb)
    if min(grey.shape) < 5:
        return 0.0
    response = np.abs(cv2.filter2D(grey, -1, _IMMERKAER))[1:-1, 1:-1]
    gradient = np.hypot(cv2.Sobel(grey, cv2.CV_32F, 1, 0), cv2.Sobel(grey, cv2.CV_32F, 0, 1))[1:-1, 1:-1]
    smooth = gradient <= np.median(gradient)
    return float(response[smooth].mean() * np.sqrt(np.pi / 2) / 6.0)


def edge_blur(rgb: NDArray[np.uint8], top: float = 0.05) -> float:
    """Blur sigma (pixels, 0..:data:`MAX_BLUR`) of the strongest ``top`` share of edges of the (h, w, 3) region,
    by the re-blur estimate (module docstring); 0 when the region has no edges."""
    grey = _grey(rgb)
    if min(grey.shape) < 8:
        return 0.0

    def magnitude(g: NDArray[np.float32]) -> NDArray[np.float32]:
        return np.hypot(cv2.Sobel(g, cv2.CV_32F, 1, 0), cv2.Sobel(g, cv2.CV_32F, 0, 1))[2:-2, 2:-2]

    sharp, soft = magnitude(grey), magnitude(cv2.GaussianBlur(grey, (0, 0), sigmaX=REBLUR_SIGMA))
    cut = np.quantile(sharp, 1.0 - top)
    edges = (sharp >= cut) & (sharp > 8.0)
    if edges.sum() < 8:
        return 0.0
    ratio = float(np.median(sharp[edges] / np.maximum(soft[edges], 1e-3)))
    if ratio <= 1.0 + 1e-3:
        return MAX_BLUR
    raw = REBLUR_SIGMA / np.sqrt(ratio**2 - 1.0)
    return float(min(np.sqrt(max(raw**2 - SOBEL_FLOOR**2, 0.0)), MAX_BLUR))


def apply_look(layer: NDArray[np.float32], weight: NDArray[np.float32], look: Look) -> NDArray[np.float32]:
    """A sprite's (h, w, 3) float32 colour ``layer`` (0..1) tinted, softened and, where its (h, w) ``weight``
    (coverage 0..1) is, grained as ``look`` says; a new array."""
    out = layer * np.asarray(look.tint, np.float32)
    if look.soften > 0:
        out = cv2.GaussianBlur(out, (0, 0), sigmaX=look.soften)
    if look.grain > 0:
        noise = np.random.default_rng(look.grain_seed).normal(0.0, look.grain / 255.0, out.shape).astype(np.float32)
        out = out + noise * weight[..., None]
    return np.clip(out, 0.0, 1.0).astype(np.float32)


def sample_look(
    background: NDArray[np.uint8],
    rect: tuple[int, int, int, int],
    sprite_rgb: NDArray[np.uint8],
    harmonise: bool,
    match_noise: bool,
    rng: np.random.Generator,
) -> Look:
    """The :class:`Look` of a sprite placed at ``rect`` [x, y, w, h] (pixels, may reach outside) on the (H, W, 3)
    uint8 ``background``, measured in the window of twice the rect's size around it: ``harmonise`` tints it with
    a strength drawn in 0.3..0.7; ``match_noise`` softens it so its edges are as blurred as the background's
    (``sqrt(bg^2 - sprite^2)``, ``sprite_rgb`` its (h, w, 3) colour at the placed size) and grains it with the
    background's noise sigma."""
    x, y, w, h = rect
    hh, ww = background.shape[:2]
    x0, y0 = max(x - w // 2, 0), max(y - h // 2, 0)
    x1, y1 = min(x + w + w // 2, ww), min(y + h + h // 2, hh)
    if x0 >= x1 or y0 >= y1:
        return Look()
    region = background[y0:y1, x0:x1]
    tint = light_tint(region, float(rng.uniform(0.3, 0.7))) if harmonise else (1.0, 1.0, 1.0)
    if not match_noise:
        return Look(tint)
    soften = float(np.sqrt(max(edge_blur(region) ** 2 - edge_blur(sprite_rgb) ** 2, 0.0)))
    return Look(tint, soften, noise_sigma(region), int(rng.integers(2**31)))

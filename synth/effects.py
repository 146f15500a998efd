"""Whole-image camera effects sampled per image: white balance, blur, sensor noise, JPEG compression.
All take and return (H, W, 3) uint8 RGB; randomness only through the explicit ``rng``."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Effects:
    wb_gains: tuple[float, float, float] = (1.0, 1.0, 1.0)
    blur_sigma: float = 0.0  # Gaussian blur, pixels
    noise_sigma: float = 0.0  # additive Gaussian noise, 0..255 units
    jpeg_quality: int = 0  # 0 = no JPEG round trip
    noise_seed: int = 0

    def to_json(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


def sample_effects(rng: np.random.Generator) -> Effects:
    """Random mild camera effects (each present with some probability)."""
    gains = tuple(float(g) for g in np.exp(rng.normal(0, 0.06, 3))) if rng.random() < 0.7 else (1.0, 1.0, 1.0)
    return Effects(
        wb_gains=gains,
        blur_sigma=float(rng.uniform(0.3, 1.5)) if rng.random() < 0.4 else 0.0,
        noise_sigma=float(rng.uniform(1.0, 6.0)) if rng.random() < 0.5 else 0.0,
        jpeg_quality=int(rng.integers(40, 95)) if rng.random() < 0.6 else 0,
        noise_seed=int(rng.integers(2**31)),
    )


def apply_effects(img: NDArray[np.uint8], e: Effects) -> NDArray[np.uint8]:
    out = img.astype(np.float32) * np.asarray(e.wb_gains, np.float32)
    if e.blur_sigma > 0:
        out = cv2.GaussianBlur(out, (0, 0), sigmaX=e.blur_sigma)
    if e.noise_sigma > 0:
        out = out + np.random.default_rng(e.noise_seed).normal(0, e.noise_sigma, out.shape).astype(np.float32)
    res = np.clip(np.round(out), 0, 255).astype(np.uint8)
    if e.jpeg_quality:
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(res, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, e.jpeg_quality])
        assert ok, "JPEG encoding of an in-memory image cannot fail"
        res = cv2.cvtColor(cv2.imdecode(buf, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
    return res

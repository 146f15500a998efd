"""Camera effects sampled per image: white balance, low light (the scene, not the flames, is under-exposed),
defocus, motion blur, Gaussian blur, lens vignetting, a low-resolution CCTV look, sensor noise and JPEG
compression. Each is present with a probability of :class:`CameraConfig`; randomness only through the explicit
``rng``. Images are (H, W, 3) uint8 RGB; effects never move content, so boxes from masks stay exact.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.compose.light import to_display, to_linear


@dataclass(frozen=True)
class CameraConfig:
    """Probability (0..1) of each effect beyond the mild ones every image may get (white balance, blur, noise,
    JPEG)."""

    low_light: float = 0.1  # the scene at 15-45 % exposure, flames at full: night, flames over-exposed
    defocus: float = 0.1  # disk blur of radius 1.5-4 px
    motion_blur: float = 0.1  # line blur of 5-15 px at a random angle
    vignette: float = 0.3  # corners darkened by 15-45 %
    cctv: float = 0.15  # downscaled to 35-60 % and back, stronger JPEG (quality 25-55)

    def __post_init__(self) -> None:
        for name, p in asdict(self).items():
            if not 0.0 <= p <= 1.0:
                raise ValueError(f"camera.{name} must be a probability in 0..1, got {p}")


@dataclass(frozen=True)
class Effects:
    wb_gains: tuple[float, float, float] = (1.0, 1.0, 1.0)
    blur_sigma: float = 0.0  # Gaussian blur, pixels
    noise_sigma: float = 0.0  # additive Gaussian noise, 0..255 units
    jpeg_quality: int = 0  # 0 = no JPEG round trip
    noise_seed: int = 0
    exposure: float = 1.0  # scene exposure (< 1: low light; applied by :func:`expose` before flames are added)
    defocus_px: float = 0.0  # disk blur radius
    motion_px: int = 0  # motion blur length
    motion_deg: float = 0.0  # motion direction
    vignette: float = 0.0  # darkening at the corners, 0..1
    downscale: float = 1.0  # CCTV: resolution factor before upscaling back

    def to_json(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


def sample_effects(rng: np.random.Generator, camera: CameraConfig | None = None) -> Effects:
    """Random camera effects (each present with some probability). The mild effects are drawn first, in the
    order images made before ``camera`` existed drew them; ``camera=None`` draws only those."""
    gains = tuple(float(g) for g in np.exp(rng.normal(0, 0.06, 3))) if rng.random() < 0.7 else (1.0, 1.0, 1.0)
    mild = Effects(
        wb_gains=gains,
        blur_sigma=float(rng.uniform(0.3, 1.5)) if rng.random() < 0.4 else 0.0,
        noise_sigma=float(rng.uniform(1.0, 6.0)) if rng.random() < 0.5 else 0.0,
        jpeg_quality=int(rng.integers(40, 95)) if rng.random() < 0.6 else 0,
        noise_seed=int(rng.integers(2**31)),
    )
    if camera is None:
        return mild
    u = rng.random(5)  # one draw per effect, then its parameters: adding an effect later keeps the others
    low = u[0] < camera.low_light
    cctv = u[4] < camera.cctv
    return replace(
        mild,
        noise_sigma=max(mild.noise_sigma, float(rng.uniform(4.0, 10.0))) if low else mild.noise_sigma,
        jpeg_quality=int(rng.integers(25, 55)) if cctv else mild.jpeg_quality,
        exposure=float(rng.uniform(0.15, 0.45)) if low else 1.0,
        defocus_px=float(rng.uniform(1.5, 4.0)) if u[1] < camera.defocus else 0.0,
        motion_px=int(rng.integers(5, 16)) if u[2] < camera.motion_blur else 0,
        motion_deg=float(rng.uniform(0, 180)),
        vignette=float(rng.uniform(0.15, 0.45)) if u[3] < camera.vignette else 0.0,
        downscale=float(rng.uniform(0.35, 0.6)) if cctv else 1.0,
    )


def expose(img: NDArray[np.uint8], e: Effects, keep: NDArray[np.bool_] | None = None) -> NDArray[np.uint8]:
    """The scene at ``e.exposure`` (:func:`scale_light`); pixels where ``keep`` (H, W) is True (flames already
    drawn) stay as they are. Identity at exposure 1."""
    dark = scale_light(img, e.exposure)
    return dark if keep is None or dark is img else np.where(keep[..., None], img, dark)


def scale_light(img: NDArray[np.uint8], gain: float) -> NDArray[np.uint8]:
    """(H, W, 3) uint8 ``img`` with its light scaled by ``gain`` <= 1 in linear light (sRGB-ish gamma 2.2): an
    exposure ``gain`` times the one it was taken at. ``img`` itself at gain 1 or more."""
    if gain >= 1.0:
        return img
    return to_display(to_linear(img) * gain)


def _disk(radius: float) -> NDArray[np.float32]:
    r = int(np.ceil(radius))
    y, x = np.mgrid[-r : r + 1, -r : r + 1]
    k = (x * x + y * y <= radius * radius).astype(np.float32)
    return k / k.sum()


def _line(length: int, degrees: float) -> NDArray[np.float32]:
    k = np.zeros((length, length), np.float32)
    c = (length - 1) / 2
    d = np.array([np.cos(np.radians(degrees)), np.sin(np.radians(degrees))])
    for t in np.linspace(-c, c, 2 * length):
        k[int(round(c + t * d[1])), int(round(c + t * d[0]))] = 1.0
    return k / k.sum()


def apply_effects(img: NDArray[np.uint8], e: Effects) -> NDArray[np.uint8]:
    """The image through the camera: white balance, defocus, motion blur, blur, vignette, CCTV resolution,
    noise, JPEG (low light is :func:`expose`, applied to the scene before flames are added)."""
    h, w = img.shape[:2]
    out = img.astype(np.float32) * np.asarray(e.wb_gains, np.float32)
    if e.defocus_px > 0:
        out = cv2.filter2D(out, -1, _disk(e.defocus_px), borderType=cv2.BORDER_REFLECT)
    if e.motion_px > 1:
        out = cv2.filter2D(out, -1, _line(e.motion_px, e.motion_deg), borderType=cv2.BORDER_REFLECT)
    if e.blur_sigma > 0:
        out = cv2.GaussianBlur(out, (0, 0), sigmaX=e.blur_sigma)
    if e.vignette > 0:
        y, x = np.mgrid[0:h, 0:w].astype(np.float32)
        r2 = ((x - w / 2) / (w / 2)) ** 2 + ((y - h / 2) / (h / 2)) ** 2
        out = out * (1.0 - e.vignette * np.clip(r2 / 2, 0, 1))[..., None]
    if e.downscale < 1.0:
        small = (max(int(w * e.downscale), 8), max(int(h * e.downscale), 8))
        out = cv2.resize(cv2.resize(out, small, interpolation=cv2.INTER_AREA), (w, h), interpolation=cv2.INTER_LINEAR)
    if e.noise_sigma > 0:
        out = out + np.random.default_rng(e.noise_seed).normal(0, e.noise_sigma, out.shape).astype(np.float32)
    res = np.clip(np.round(out), 0, 255).astype(np.uint8)
    if e.jpeg_quality:
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(res, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, e.jpeg_quality])
        assert ok, "JPEG encoding of an in-memory image cannot fail"
        res = cv2.cvtColor(cv2.imdecode(buf, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
    return res

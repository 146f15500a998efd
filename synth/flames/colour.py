"""Flame colours from physics: black-body (Planck) spectra and metal-salt emission lines integrated against
the CIE 1931 2-degree colour-matching functions, converted to sRGB.

The colour-matching functions use the multi-lobe Gaussian fit of Wyman, Sloan & Shirley (JCGT 2013);
XYZ -> linear sRGB uses the IEC 61966-2-1 matrix (D65 white).

Every palette is an (N, 3) float32 array of *display* (sRGB-encoded) colours in [0, 1], indexed by a
normalised flame temperature in [0, 1] (0 = cold, no light; 1 = hottest core).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from synth.compose.ramps import smoothstep

_H, _C, _K = 6.62607015e-34, 2.99792458e8, 1.380649e-23
WAVELENGTHS_NM: NDArray[np.float64] = np.arange(380.0, 781.0, 2.0)
_XYZ_TO_SRGB = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])

#: Emission lines (nm, relative strength) of the chemical flames we render; a faint black-body continuum is added.
CHEMICAL_LINES: dict[str, tuple[tuple[float, float], ...]] = {
    "copper": ((510.6, 1.0), (515.3, 0.8), (521.8, 0.9), (578.2, 0.2)),  # Cu: green
    "boron": ((518.0, 0.6), (548.0, 1.0), (580.0, 0.3)),  # BO2 bands: bright green
    "methane": ((431.4, 1.0), (436.5, 0.4), (473.7, 0.3), (516.5, 0.25)),  # CH + C2 Swan: blue core
    "sodium": ((589.0, 1.0), (589.6, 0.5)),  # Na D lines: yellow
    "lithium": ((670.8, 1.0), (610.4, 0.15)),  # Li: crimson
    "strontium": ((606.0, 0.8), (640.8, 0.5), (650.0, 1.0), (460.7, 0.1)),  # SrOH/SrCl bands: red
    "potassium": ((766.5, 1.0), (769.9, 0.5), (404.4, 0.5)),  # K: lilac (the violet 404 nm line shows)
}
PALETTES: tuple[str, ...] = ("blackbody", *CHEMICAL_LINES)


def _lobe(lam: NDArray[np.float64], mu: float, s1: float, s2: float) -> NDArray[np.float64]:
    s = np.where(lam < mu, s1, s2)
    return np.exp(-0.5 * ((lam - mu) / s) ** 2)


def cie_cmf(lam_nm: ArrayLike) -> NDArray[np.float64]:
    """(N,) wavelengths in nm -> (N, 3) CIE 1931 x-bar, y-bar, z-bar (Wyman et al. 2013 fit)."""
    lam = np.asarray(lam_nm, dtype=np.float64)
    x = 1.056 * _lobe(lam, 599.8, 37.9, 31.0) + 0.362 * _lobe(lam, 442.0, 16.0, 26.7)
    x -= 0.065 * _lobe(lam, 501.1, 20.4, 26.2)
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=-1)


def planck(lam_nm: ArrayLike, kelvin: ArrayLike) -> NDArray[np.float64]:
    """Spectral radiance B(lambda, T) in W sr^-1 m^-3; broadcasts ``lam_nm`` against ``kelvin``."""
    lam = np.asarray(lam_nm, dtype=np.float64) * 1e-9
    t = np.asarray(kelvin, dtype=np.float64)
    return 2.0 * _H * _C**2 / lam**5 / np.expm1(_H * _C / (lam * _K * t))


def spectrum_to_linear_rgb(spectrum: NDArray[np.float64]) -> NDArray[np.float64]:
    """(..., len(WAVELENGTHS_NM)) spectra -> (..., 3) linear sRGB (unnormalised, may be negative)."""
    xyz = spectrum @ cie_cmf(WAVELENGTHS_NM)
    return xyz @ _XYZ_TO_SRGB.T


def chromaticity(rgb_linear: NDArray[np.float64]) -> NDArray[np.float64]:
    """(..., 3) linear RGB -> (..., 3) colour of the same hue, clipped at 0 and scaled so its max is 1."""
    rgb = np.clip(rgb_linear, 0.0, None)
    return rgb / np.maximum(rgb.max(axis=-1, keepdims=True), 1e-12)


def srgb_encode(linear: ArrayLike) -> NDArray[np.float64]:
    """Linear [0, 1] -> sRGB-encoded [0, 1] (IEC 61966-2-1 transfer curve)."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def blackbody_rgb(kelvin: ArrayLike) -> NDArray[np.float64]:
    """(...) temperatures in K -> (..., 3) linear sRGB chromaticity of a black body (max channel = 1)."""
    t = np.asarray(kelvin, dtype=np.float64)
    spectra = planck(WAVELENGTHS_NM, t[..., None])
    return chromaticity(spectrum_to_linear_rgb(spectra))


def line_spectrum_rgb(lines: tuple[tuple[float, float], ...], width_nm: float = 4.0) -> NDArray[np.float64]:
    """(3,) linear sRGB chromaticity of emission lines ``(nm, strength)`` broadened by a Gaussian."""
    lam = WAVELENGTHS_NM
    spec = sum(s * np.exp(-0.5 * ((lam - mu) / width_nm) ** 2) for mu, s in lines)
    return chromaticity(spectrum_to_linear_rgb(np.asarray(spec)))


def _intensity(t: NDArray[np.float64], exposure: float) -> NDArray[np.float64]:
    """Radiant exitance ~ T^4 through an exposure curve: 0 at t = 0, ~1 at the core."""
    return 1.0 - np.exp(-exposure * t**4)


def flame_palette(
    kind: str = "blackbody",
    n: int = 256,
    t_min: float = 900.0,
    t_max: float = 3000.0,
    exposure: float = 9.0,
    peak: float = 1.0,
) -> NDArray[np.float32]:
    """(n, 3) float32 sRGB-encoded colours for normalised temperature ``i / (n - 1)``.

    ``blackbody``: chromaticity of Planck's law at ``t_min + t (t_max - t_min)`` kelvin (red -> orange ->
    yellow-white), brightness ~ T^4. A chemical ``kind`` (see :data:`CHEMICAL_LINES`) colours the mid
    temperatures with its line spectrum and keeps a whiter core. ``peak`` scales the linear colour at the core;
    above 1 channels clip as in an over-exposed camera, so hot regions turn yellow, then white.
    """
    if kind not in PALETTES:
        raise ValueError(f"unknown flame palette {kind!r}; choose one of {', '.join(PALETTES)}")
    t = np.linspace(0.0, 1.0, n)
    body = blackbody_rgb(t_min + t * (t_max - t_min))
    if kind != "blackbody":
        hue = line_spectrum_rgb(CHEMICAL_LINES[kind])
        white = np.clip(t**3 * 0.6, 0.0, 1.0)[:, None]
        body = chromaticity((1 - white) * hue[None, :] + white * np.ones(3) * 0.9 + 0.05 * body)
    rgb = body * _intensity(t, exposure)[:, None] * peak
    return srgb_encode(rgb).astype(np.float32)


#: The camera-exposed palette (:func:`exposed_palette`): a sooty fire's black body at 900-1600 K (hotter is not
#: what wood, fuel or a house burns at: a 3000 K body's colour is the pale yellow of a lamp), each channel rolling
#: off as the sensor saturates (``1 - exp(-ROLL_OFF x)``), and past saturation the core blooming to white: the
#: white mix goes smoothly from 0 to 1 as the brightest channel's exposed value goes from 2 to 6.
EXPOSED_T_MAX = 1600.0
ROLL_OFF = 1.3
BLOOM = (2.0, 6.0)


def exposed_palette(
    gain: float, exposure: float = 9.0, n: int = 256, t_min: float = 900.0, t_max: float = EXPOSED_T_MAX
) -> NDArray[np.float32]:
    """(n, 3) float32 sRGB-encoded colours for normalised temperature ``i / (n - 1)`` of a black-body flame as a
    camera records it: the linear colour ``blackbody_rgb(T) * (1 - exp(-exposure t^4)) * gain`` (``gain`` > 0: the
    camera's exposure, in units of the display palette's full scale) through a per-channel roll-off and a bloom to
    white (:data:`ROLL_OFF`, :data:`BLOOM`). Dim gas is red, brighter orange, then yellow as green saturates, and a
    core bright enough is white, as fires are in photographs (``fuzzyfire synth colour``: the shared real train
    flames have a quarter of their pixels near-white and the colourful ones at hue 31 degrees, the display palette's
    composited flames 1 % and 39 degrees; docs/findings.md, "Does the flame look matter?")."""
    if gain <= 0:
        raise ValueError(f"gain must be > 0, got {gain}")
    t = np.linspace(0.0, 1.0, n)
    x = blackbody_rgb(t_min + t * (t_max - t_min)) * _intensity(t, exposure)[:, None] * gain
    rolled = 1.0 - np.exp(-ROLL_OFF * x)
    white = smoothstep(x.max(axis=-1, keepdims=True), *BLOOM)
    return srgb_encode((1.0 - white) * rolled + white).astype(np.float32)

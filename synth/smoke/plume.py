"""Simulated smoke plumes: time sequences of soft-alpha smoke sprites that rise, spread, drift and thin.

The plume follows the shape of a turbulent buoyant plume (Morton, Taylor & Turner 1956, "Turbulent gravitational
convection from maintained and instantaneous sources", Proc. R. Soc. A 234): its half-width grows linearly with
height, ``b(z) = b0 + spread z`` (the entrainment law b = 6/5 alpha z with alpha ~ 0.1 gives spread ~ 0.12; a visible
plume edge reads wider: :func:`sample_plume` draws a growth of 0.18-0.28 of the canvas width over its height,
a canvas 4/3 times taller than wide, from a half-width of 0.06-0.1 at the source), its centreline bends downwind (``wind z^1.5``: a
plume in a cross wind bends over), and its density thins with height (``exp(-z / thinning)``). Inside this envelope
the smoke is *advected noise* (Perlin & Neyret 2001, "Flow noise", SIGGRAPH Technical Sketches): fractal value noise
scrolled upwards frame by frame at the plume's rise speed and warped sideways by a slower noise (the billows), so
the frames of a sequence are the same plume moving, as the flame sequences are a flame burning. No fluid is solved:
a 96 x 128 grid of eight frames takes ~10 ms, so a library is made on the fly.

A frame is a :class:`synth.flames.sprites.Sprite` with an empty flame mask and no emission: its ``over`` layer is
the smoke, straight-alpha RGBA whose RGB is a white shading (self-shadowed billows darker) that the compositor tints
with the plume's colour and the scene's light (:mod:`synth.smoke.placement`). Rows grow downwards; the plume's
source is at the bottom row, centred.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.image.imageio import unit_to_u8
from synth.compose.ramps import smoothstep
from synth.flames.sprites import SMOKE_KIND, Sprite, SpriteSequence


@dataclass(frozen=True)
class PlumeParams:
    """One plume sequence. ``rows`` x ``cols`` grid cells (one output pixel each); fractions are of the grid."""

    rows: int = 128
    cols: int = 96
    frames: int = 8  # frames kept
    base: float = 0.15  # half-width at the source, fraction of cols
    spread: float = 0.2  # half-width growth from the source to the top, fraction of cols
    wind: float = 0.0  # centreline drift at the top, fraction of cols (signed)
    thinning: float = 0.6  # height over which density falls by 1/e, fraction of rows
    density: float = 2.5  # optical depth at the source's core: opacity 1 - exp(-depth), > 0
    rise: float = 6.0  # noise scrolled upwards per frame, cells
    grain: float = 32.0  # size of the largest noise blobs (billows), cells

    def __post_init__(self) -> None:
        if self.rows < 8 or self.cols < 8 or self.frames < 1:
            raise ValueError(
                f"a plume needs at least 8 x 8 cells and one frame, got {self.rows}x{self.cols}, {self.frames}"
            )
        if self.density <= 0 or self.thinning <= 0 or self.grain <= 1:
            raise ValueError("density, thinning must be > 0 and grain > 1")


def sample_plume(rng: np.random.Generator, frames: int = 8) -> PlumeParams:
    """A random plume: spread, drift, thinning and density drawn from ``rng`` in that order (ranges in the module
    docstring and :class:`PlumeParams`)."""
    spread = float(rng.uniform(0.18, 0.28))
    wind = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.0, 0.2))
    thinning = float(rng.uniform(0.5, 1.5))
    density = float(rng.uniform(2.0, 5.0))
    base = float(rng.uniform(0.06, 0.1))
    return PlumeParams(base=base, spread=spread, wind=wind, thinning=thinning, density=density, frames=frames)


def value_noise(
    shape: tuple[int, int], grain: float, rng: np.random.Generator, octaves: int = 3
) -> NDArray[np.float32]:
    """(rows, cols) fractal value noise in [0, 1]: ``octaves`` random grids, the first with cells ``grain`` wide,
    each next twice as fine and half as strong, bicubically upsampled and summed, then stretched to [0, 1]."""
    rows, cols = shape
    out = np.zeros(shape, np.float32)
    for k in range(octaves):
        cell = max(grain / 2**k, 1.0)
        small = rng.random((int(np.ceil(rows / cell)) + 3, int(np.ceil(cols / cell)) + 3)).astype(np.float32)
        big = cv2.resize(small, (int(small.shape[1] * cell), int(small.shape[0] * cell)), interpolation=cv2.INTER_CUBIC)
        out += big[:rows, :cols] * 0.5**k
    lo, hi = float(out.min()), float(out.max())
    return (out - lo) / max(hi - lo, 1e-6)


def plume_alpha(p: PlumeParams, turbulence: NDArray[np.float32], warp: NDArray[np.float32]) -> NDArray[np.float32]:
    """(rows, cols) opacity in [0, 1) of one frame: ``1 - exp(-depth)`` (Beer-Lambert) of the optical depth of the
    envelope of ``p`` (module docstring), its across coordinate warped by ``warp`` and its density modulated by
    ``turbulence`` (both (rows, cols) in [0, 1])."""
    z = (p.rows - 1 - np.arange(p.rows, dtype=np.float32))[:, None] / (p.rows - 1)  # height above the source, 0..1
    x = np.arange(p.cols, dtype=np.float32)[None, :] / (p.cols - 1)
    centre = 0.5 + p.wind * z**1.5
    half = p.base + p.spread * z
    across = (x - centre + 0.35 * half * (warp - 0.5)) / half
    envelope = np.exp(-3.0 * across**2)
    column = np.exp(-z / p.thinning) * smoothstep(z, 0.0, 0.06)
    body = smoothstep(turbulence, 0.3, 0.75)
    edge = smoothstep(np.minimum(x, 1 - x), 0.0, 0.08) * smoothstep(1 - z, 0.0, 0.08)  # never cut at the canvas
    depth = p.density * envelope * column * (0.15 + 0.85 * body) * edge
    return (1.0 - np.exp(-depth)).astype(np.float32)


def plume_sequence(name: str, p: PlumeParams, rng: np.random.Generator) -> SpriteSequence:
    """``p.frames`` frames of one plume (module docstring), all drawn from ``rng``: a turbulence noise field
    taller than the grid by the rise of every frame, scrolled upwards ``p.rise`` cells per frame, and a warp
    field scrolled at half that speed. Each frame's RGB is the white shading ``1 - 0.35 (1 - turbulence)``."""
    travel = int(np.ceil(p.rise * p.frames)) + 1
    turbulence = value_noise((p.rows + travel, p.cols), p.grain, rng)
    warp = value_noise((p.rows + travel, p.cols), 2.5 * p.grain, rng, octaves=2)
    sprites = []
    for f in range(p.frames):
        shift = int(round(p.rise * f))
        t = turbulence[travel - shift : travel - shift + p.rows]
        w = warp[travel - shift // 2 : travel - shift // 2 + p.rows]
        alpha = plume_alpha(p, t, w)
        shade = 1.0 - 0.35 * (1.0 - t)
        over = np.dstack([unit_to_u8(np.repeat(shade[..., None], 3, axis=-1)), unit_to_u8(alpha)])
        sprites.append(Sprite(over, np.zeros((p.rows, p.cols, 3), np.uint8), np.zeros((p.rows, p.cols), bool)))
    return SpriteSequence(name, tuple(sprites), {"generator": "plume", "kind": SMOKE_KIND, **asdict(p)})


def plume_library(n: int, seed: int, frames: int = 8) -> list[SpriteSequence]:
    """``n`` plume sequences ``plume-<seed>-<k>``, sequence k from ``default_rng([seed, 7, k])``."""
    out = []
    for k in range(n):
        rng = np.random.default_rng([seed, 7, k])
        out.append(plume_sequence(f"plume-{seed}-{k:03d}", sample_plume(rng, frames), rng))
    return out

"""Procedural flame sequences.

Two generators, chosen by name from :data:`GENERATORS` (unknown names raise):

- ``fluid``: a 2D stable-fluid fire (Stam 1999; Fedkiw, Stam & Jensen 2001): semi-Lagrangian advection,
  pressure projection (Jacobi), buoyancy from temperature minus soot weight, vorticity confinement, a wind
  and turbulence force, T^4 radiative cooling, soot made where the gas cools. Grid cells are unit sized,
  velocities in cells per step, rows grow downwards (buoyancy pulls towards row 0).
- ``noise``: a cheaper one: a tapered flame profile warped by fractal noise scrolling upwards.

Both return a :class:`synth.sprites.SpriteSequence` of frames kept every ``keep_every`` of ``frames`` steps,
each alpha-cropped, coloured by :func:`synth.colour.flame_palette`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from synth.colour import CHEMICAL_LINES, flame_palette
from synth.sprites import Sprite, SpriteSequence, crop_to_content

SHAPES: tuple[str, ...] = ("point", "line", "ring", "pool", "jet")
F32 = NDArray[np.float32]


@dataclass(frozen=True)
class FlameParams:
    """One flame sequence. Sizes in grid cells; ``scale`` output pixels per cell."""

    generator: str = "fluid"
    shape: str = "point"  # emission shape, one of SHAPES
    rows: int = 96
    cols: int = 64
    scale: int = 2
    source_width: float = 0.3  # fraction of the grid width
    buoyancy: float = 0.09  # upward acceleration per unit temperature (cells / step^2)
    smoke_weight: float = 0.02  # downward pull per unit soot
    wind: float = 0.0  # sideways acceleration at the top (cells / step^2); grows with height
    turbulence: float = 0.06  # amplitude of the random force
    vorticity: float = 0.25  # vorticity-confinement strength
    cooling: float = 0.06  # T^4 cooling rate per step
    soot: float = 0.8  # soot made per unit of heat lost
    smoke: float = 0.6  # smoke opacity scale (0: no smoke)
    smoke_grey: float = 0.25  # smoke colour (0 black .. 1 white)
    palette: str = "blackbody"
    exposure: float = 9.0  # brightness curve of the palette (higher: brighter, more saturated flames)
    peak: float = 1.0  # linear brightness at the core; > 1 clips to yellow-white like an over-exposed camera
    base_fade: float = 3.0  # the flame's base fades out over an irregular line up to this many cells high
    frames: int = 1024
    keep_every: int = 12
    warmup: int = 40  # steps before the first kept frame
    jacobi_iters: int = 25

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"unknown flame shape {self.shape!r}; choose one of {', '.join(SHAPES)}")
        if self.generator not in GENERATORS:
            raise ValueError(f"unknown flame generator {self.generator!r}; choose one of {', '.join(GENERATORS)}")
        if self.frames < 1 or self.keep_every < 1 or self.rows < 16 or self.cols < 16:
            raise ValueError("frames, keep_every must be >= 1 and the grid at least 16 x 16")


def sample_params(rng: np.random.Generator, generator: str = "fluid", rare: bool = False, **fixed) -> FlameParams:
    """Random flame parameters: shape, size, wind, turbulence, smoke; ``rare`` picks a chemical palette.
    Keyword arguments in ``fixed`` override the sampled values."""
    shape = str(rng.choice(SHAPES))
    palette = str(rng.choice(list(CHEMICAL_LINES))) if rare else "blackbody"
    width = {"point": 0.18, "line": 0.45, "ring": 0.5, "pool": 0.7, "jet": 0.1}[shape]
    p = FlameParams(
        generator=generator,
        shape=shape,
        source_width=float(width * rng.uniform(0.7, 1.3)),
        buoyancy=float(rng.uniform(0.06, 0.13)),
        wind=float(rng.normal(0.0, 0.012)),
        turbulence=float(rng.uniform(0.02, 0.1)),
        vorticity=float(rng.uniform(0.1, 0.4)),
        cooling=float(rng.uniform(0.04, 0.09)),
        soot=float(rng.uniform(0.3, 1.2)),
        smoke=float(rng.choice([0.0, rng.uniform(0.2, 1.0), rng.uniform(1.5, 5.0)], p=[0.2, 0.5, 0.3])),
        smoke_grey=float(rng.uniform(0.12, 0.45)),
        palette=palette,
        exposure=float(rng.uniform(6.0, 20.0)),
        peak=float(rng.uniform(1.0, 3.5)),
    )
    return replace(p, **fixed)


# -- the stable-fluid solver ------------------------------------------------------------------------------


def advect(field: F32, u: F32, v: F32, grid: tuple[F32, F32]) -> F32:
    """Semi-Lagrangian advection: sample ``field`` (rows, cols) back along the velocity; zero outside."""
    gx, gy = grid
    return cv2.remap(field, gx - u, gy - v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def project(u: F32, v: F32, pressure: F32, iters: int) -> tuple[F32, F32, F32]:
    """Make (u, v) divergence free by a Jacobi Poisson solve (warm-started from ``pressure``, p = 0 on the
    border: an open domain). Returns new (u, v, pressure)."""
    div = np.zeros_like(u)
    div[1:-1, 1:-1] = 0.5 * (u[1:-1, 2:] - u[1:-1, :-2] + v[2:, 1:-1] - v[:-2, 1:-1])
    p = pressure.copy()
    for _ in range(iters):
        p[1:-1, 1:-1] = 0.25 * (p[1:-1, 2:] + p[1:-1, :-2] + p[2:, 1:-1] + p[:-2, 1:-1] - div[1:-1, 1:-1])
    u, v = u.copy(), v.copy()
    u[1:-1, 1:-1] -= 0.5 * (p[1:-1, 2:] - p[1:-1, :-2])
    v[1:-1, 1:-1] -= 0.5 * (p[2:, 1:-1] - p[:-2, 1:-1])
    return u, v, p


def vorticity_force(u: F32, v: F32, eps: float) -> tuple[F32, F32]:
    """Vorticity confinement (Fedkiw et al. 2001): f = eps (N x omega), N = grad|omega| / |grad|omega||."""
    w = np.gradient(v, axis=1) - np.gradient(u, axis=0)
    mag = np.abs(w)
    ny, nx = np.gradient(mag)
    norm = np.sqrt(nx**2 + ny**2) + 1e-6
    nx, ny = nx / norm, ny / norm
    return (eps * ny * w).astype(np.float32), (-eps * nx * w).astype(np.float32)


def source_mask(p: FlameParams, rng: np.random.Generator) -> F32:
    """(rows, cols) emission strength in [0, 1] of the shape at the bottom of the grid."""
    rows, cols = p.rows, p.cols
    x = (np.arange(cols, dtype=np.float32) - cols / 2 + 0.5) / cols
    half = p.source_width / 2
    if p.shape == "ring":  # a burning ring seen from the side: two strong ends, a weaker middle
        profile = np.clip(1 - np.abs(np.abs(x) - half) / 0.06, 0, 1) + 0.35 * (np.abs(x) < half)
    else:
        profile = np.clip((half - np.abs(x)) / max(half * 0.35, 1e-3), 0, 1)
    depth = {"pool": 5, "line": 4, "jet": 4}.get(p.shape, 4)
    mask = np.zeros((rows, cols), np.float32)
    mask[rows - 3 - depth : rows - 3, :] = np.clip(profile, 0, 1)
    return mask


def _noise(rng: np.random.Generator, shape: tuple[int, int], cell: int) -> F32:
    small = rng.standard_normal((max(shape[0] // cell, 2), max(shape[1] // cell, 2))).astype(np.float32)
    return cv2.resize(small, (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)


def base_attenuation(p: FlameParams, bottom: int, rng: np.random.Generator) -> F32:
    """(rows, cols) factor in [0, 1] fading the flame out below an irregular line ``0..base_fade`` cells above
    row ``bottom`` (a soft two-cell ramp), so flames do not end in a straight cut."""
    if p.base_fade <= 0:
        return np.ones((p.rows, p.cols), np.float32)
    offset = (np.clip(_noise(rng, (1, p.cols), 6)[0] * 0.5 + 0.5, 0, 1) * p.base_fade).astype(np.float32)
    above = (bottom - np.arange(p.rows, dtype=np.float32))[:, None]
    return np.clip((above - offset[None, :]) / 2.0, 0.0, 1.0).astype(np.float32)


@dataclass
class FluidState:
    u: F32
    v: F32
    pressure: F32
    temperature: F32
    soot: F32


def fluid_step(s: FluidState, p: FlameParams, src: F32, grid: tuple[F32, F32], rng: np.random.Generator) -> None:
    """Advance the fire by one step in place."""
    shape = src.shape
    flicker = 0.75 + 0.5 * np.clip(_noise(rng, shape, 8) * 0.5 + 0.5, 0, 1)
    s.temperature = np.maximum(s.temperature, np.clip(src * flicker, 0.0, 1.0))
    if p.shape == "jet":
        s.v -= 0.6 * src
    height = np.linspace(1.0, 0.0, shape[0], dtype=np.float32)[:, None]
    s.v -= p.buoyancy * s.temperature - p.smoke_weight * s.soot
    s.u += p.wind * height + p.turbulence * _noise(rng, shape, 6)
    s.v += p.turbulence * _noise(rng, shape, 6)
    fu, fv = vorticity_force(s.u, s.v, p.vorticity)
    s.u, s.v = s.u + fu, s.v + fv
    s.u, s.v = advect(s.u, s.u, s.v, grid), advect(s.v, s.u, s.v, grid)
    s.u, s.v, s.pressure = project(s.u, s.v, s.pressure, p.jacobi_iters)
    hot = advect(s.temperature, s.u, s.v, grid)
    cooled = np.clip(hot - p.cooling * (hot**4 + 0.3 * hot), 0.0, 1.0)
    s.soot = advect(s.soot, s.u, s.v, grid) * 0.995 + p.soot * (hot - cooled)
    s.temperature = cooled.astype(np.float32)


def _border_window(shape: tuple[int, int], fraction: float = 0.12) -> F32:
    """(h, w) factor fading smoke to 0 towards the left, right and top borders (no hard edge where the plume
    leaves the simulated domain)."""
    h, w = shape
    ramp_x = np.clip(np.minimum(np.arange(w), np.arange(w)[::-1]) / max(fraction * w, 1.0), 0, 1)
    ramp_y = np.clip(np.arange(h) / max(fraction * h, 1.0), 0, 1)
    return (ramp_y[:, None] * ramp_x[None, :]).astype(np.float32)


def render_fields(temperature: F32, soot: F32, p: FlameParams, palette: F32, mask_level: float = 0.2) -> Sprite:
    """Fields (rows, cols) -> an uncropped sprite of (rows * scale, cols * scale) pixels. The flame mask is where
    the emitted colour's brightest channel exceeds ``mask_level`` (visible fire)."""
    size = (p.cols * p.scale, p.rows * p.scale)
    t = np.clip(cv2.resize(temperature, size, interpolation=cv2.INTER_CUBIC), 0.0, 1.0)
    idx = np.round(t * (len(palette) - 1)).astype(np.intp)
    emission = palette[idx]
    mask = emission.max(axis=-1) > mask_level
    dens = np.clip(cv2.resize(soot, size, interpolation=cv2.INTER_LINEAR), 0.0, None)
    alpha = (1.0 - np.exp(-p.smoke * dens)) * (1.0 - emission.max(axis=-1)) * _border_window(t.shape)
    over = np.empty(t.shape + (4,), np.uint8)
    over[..., :3] = np.uint8(round(p.smoke_grey * 255))
    over[..., 3] = np.round(np.clip(alpha, 0, 1) * 255).astype(np.uint8)
    return Sprite(over, np.round(emission * 255).astype(np.uint8), mask)


def simulate_fluid(p: FlameParams, rng: np.random.Generator) -> list[Sprite]:
    """Run the stable-fluid fire for ``p.frames`` steps; uncropped sprites of every ``keep_every`` th step."""
    shape = (p.rows, p.cols)
    zeros = np.zeros(shape, np.float32)
    state = FluidState(zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy())
    gy, gx = np.mgrid[0 : p.rows, 0 : p.cols].astype(np.float32)
    palette = flame_palette(p.palette, exposure=p.exposure, peak=p.peak)
    src = source_mask(p, rng)
    base = base_attenuation(p, p.rows - 3, rng)
    frames = []
    for step in range(p.warmup + p.frames):
        fluid_step(state, p, src, (gx, gy), rng)
        kept = step - p.warmup
        if kept >= 0 and kept % p.keep_every == 0:
            frames.append(render_fields(state.temperature * base, state.soot, p, palette))
    return frames


def simulate_noise(p: FlameParams, rng: np.random.Generator) -> list[Sprite]:
    """The cheap generator: a tapered flame profile warped by upward-scrolling fractal noise."""
    rows, cols = p.rows, p.cols
    tall = sum(_noise(rng, (rows * 4, cols), c) * (c / 16) for c in (16, 8, 4))
    y = np.linspace(1.0, 0.0, rows, dtype=np.float32)[:, None]  # 0 at the bottom row, 1 at the top
    x = (np.arange(cols, dtype=np.float32) - cols / 2 + 0.5)[None, :] / cols
    palette = flame_palette(p.palette, exposure=p.exposure, peak=p.peak)
    base = base_attenuation(p, rows, rng)
    frames = []
    for step in range(0, p.frames, p.keep_every):
        off = (step * 2) % (rows * 3)
        n = tall[rows * 3 - off : rows * 4 - off]
        sway = p.wind * 20 * y**1.5 + 0.04 * n * y
        width = p.source_width * (1.0 - y) ** 0.6 + 1e-3
        d = np.abs(x - sway) / width
        heat = np.clip(1.0 - d + 0.35 * n * (0.3 + y), 0, 1) * np.clip(1.2 - y * (1 + 0.3 * n), 0, 1)
        soot = np.clip(0.8 - d * 0.6, 0, 1) * np.clip(y - 0.5, 0, None) * (1 + 0.5 * n)
        frames.append(render_fields((heat * base).astype(np.float32), soot.astype(np.float32), p, palette))
    return frames


GENERATORS: dict[str, Callable[[FlameParams, np.random.Generator], list[Sprite]]] = {
    "fluid": simulate_fluid,
    "noise": simulate_noise,
}


def generate_sequence(name: str, p: FlameParams, rng: np.random.Generator) -> SpriteSequence:
    """Run the chosen generator and keep the frames that show a flame, alpha-cropped."""
    sprites = [c for c in (crop_to_content(s) for s in GENERATORS[p.generator](p, rng)) if c and c.mask.any()]
    return SpriteSequence(name, tuple(sprites), {"generator": p.generator, "params": asdict(p)})

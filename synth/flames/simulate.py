"""Procedural flame sequences.

Two generators, chosen by name from :data:`GENERATORS` (unknown names raise):

- ``fluid``: a 2D stable-fluid fire (Stam 1999; Fedkiw, Stam & Jensen 2001): semi-Lagrangian advection,
  pressure projection (Jacobi), buoyancy from temperature minus soot weight, vorticity confinement, a wind
  and turbulence force (sideways motion damped by :data:`DRAG`), T^4 radiative cooling plus a constant term
  (dim tails burn out), soot made where the gas cools. Grid cells are unit sized, velocities in cells per
  step, rows grow downwards (buoyancy pulls towards row 0).
- ``noise``: a cheaper one: a tapered flame profile warped by fractal noise scrolling upwards.

Both return a :class:`synth.flames.sprites.SpriteSequence` of frames kept every ``keep_every`` of ``frames`` steps,
each alpha-cropped, coloured by :func:`synth.flames.colour.flame_palette`.

What makes them read as fire (issue 23): the fuel burns in a *body* at the base (one or more tapered tongues,
``body`` of the grid high) held at full temperature, so a flame is a bright saturated mass with tongues torn off
its top, not a thin ribbon of hot gas; the palette is exposed so that the core saturates to yellow (yellow-white
at the higher peaks) over an orange gradient to a red edge (on the flame gap a wide gradient beats a body clipped
flat to pale yellow: docs/findings.md, "Does the flame look matter?"); the rendered field is warped by sub-grid noise (``detail`` cells) for
crisp, turbulent edges; frames are kept only after ``warmup`` steps (the first plume's mushroom cap has left);
a sequence is stretched sideways to a sampled box aspect ratio (``aspect``, the real boxes' distribution).
Chemical palettes tint a black-body flame (:data:`TINTS`): methane is blue at the base, metal salts colour
the lower flame and leave yellow soot tips. An *exposed* flame (``gain`` > 0, :func:`exposed_gain`) is coloured as
a camera records a fire instead: a cooler black body pushed past the sensor's range, red at the edge, orange, then
yellow and a white core (:func:`synth.flames.colour.exposed_palette`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.image.imageio import unit_to_u8
from synth.compose.ramps import smoothstep
from synth.flames.colour import exposed_palette, flame_palette
from synth.flames.sprites import Sprite, SpriteSequence, crop_to_content

SHAPES: tuple[str, ...] = ("point", "line", "ring", "pool", "jet")
#: How often :func:`sample_params` draws each shape (thin jets, gas leaks, are rare in fire footage).
SHAPE_WEIGHTS: tuple[float, ...] = (0.3, 0.2, 0.15, 0.27, 0.08)
F32 = NDArray[np.float32]

#: Chemical palettes :func:`sample_params` draws for a rare flame, with their weights: a blue methane base, green
#: copper and boron. (Every palette of :data:`synth.flames.colour.PALETTES` can still be asked for by name.)
RARE_PALETTES: dict[str, float] = {"methane": 0.5, "copper": 0.35, "boron": 0.15}
#: How a chemical palette tints a black-body flame: (weight at the base, weight at the top, height in units of
#: the burning body over which the weight goes from one to the other). Methane: blue only at the base.
TINTS: dict[str, tuple[float, float, float]] = {"methane": (1.0, 0.0, 1.0)}
DEFAULT_TINT = (0.6, 0.15, 2.5)  # metal salts: the lower flame coloured, yellow soot at the tips
#: Box aspect ratio (width / height) of real flames: fire-cctv-416's 4,844 train boxes have 5/10/50/90/95 %
#: percentiles 0.23/0.29/0.57/1.33/1.70; :func:`sample_params` draws a log-normal of this median and spread
#: (10-90 % 0.27-1.22), clipped to :data:`ASPECT_RANGE`.
ASPECT_MEDIAN, ASPECT_SIGMA = 0.57, 0.6
ASPECT_RANGE = (0.2, 2.0)
MAX_STRETCH = 1.6  # a sequence is stretched sideways by at most this factor (or 1 / it) towards ``aspect``
DRAG = 0.97  # sideways velocity kept per step: wind and swirls do not pile up into a flame blown flat
#: Camera gain range of an exposed flame (:func:`exposed_gain`): with :data:`synth.flames.colour.EXPOSED_T_MAX` the
#: composited flames come near the real train flames' near-white share, saturation and hue (``synth colour``;
#: docs/findings.md, "Does the flame look matter?").
EXPOSED_GAIN = (3.0, 10.0)


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
    gain: float = 0.0  # > 0: the camera-exposed palette at this gain (synth.flames.colour.exposed_palette)
    base_fade: float = 3.0  # the flame's base fades out over an irregular line up to this many cells high
    body: float = 0.25  # height of the burning body (fuel held at full temperature), fraction of the rows
    detail: float = 1.0  # edge turbulence: the rendered flame is warped by noise of this amplitude, grid cells
    aspect: float = 0.0  # width / height of the flame box the sequence is stretched to (0: as simulated)
    texture: float = 0.0  # inner streaks: the temperature dips by up to this fraction in rising streaks (0: none)
    frames: int = 1024
    keep_every: int = 12
    warmup: int = 100  # steps before the first kept frame (the first plume's mushroom cap leaves the grid)
    jacobi_iters: int = 25

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"unknown flame shape {self.shape!r}; choose one of {', '.join(SHAPES)}")
        if self.generator not in GENERATORS:
            raise ValueError(f"unknown flame generator {self.generator!r}; choose one of {', '.join(GENERATORS)}")
        if self.frames < 1 or self.keep_every < 1 or self.rows < 16 or self.cols < 16:
            raise ValueError("frames, keep_every must be >= 1 and the grid at least 16 x 16")
        if not 0.0 < self.body <= 0.8 or self.detail < 0 or self.aspect < 0:
            raise ValueError("body must be in (0, 0.8], detail and aspect >= 0")
        if not 0.0 <= self.texture < 1.0:
            raise ValueError(f"texture must be in [0, 1), got {self.texture}")
        if self.gain < 0:
            raise ValueError(f"gain must be >= 0 (0: the display palette), got {self.gain}")


def sample_aspect(rng: np.random.Generator) -> float:
    """A flame box aspect ratio (width / height) drawn like the real boxes' (:data:`ASPECT_MEDIAN`)."""
    return float(np.clip(ASPECT_MEDIAN * np.exp(rng.normal(0.0, ASPECT_SIGMA)), *ASPECT_RANGE))


def exposed_gain(peak: float) -> float:
    """The camera gain of an exposed flame (:data:`EXPOSED_GAIN`, log-uniform) from its sampled ``peak`` (uniform
    in 1.3..2.0): no draw of its own, so an exposed library has the same shapes, smoke and motion as the display
    one of the same seed."""
    lo, hi = EXPOSED_GAIN
    return float(lo * (hi / lo) ** np.clip((peak - 1.3) / 0.7, 0.0, 1.0))


def sample_params(
    rng: np.random.Generator, generator: str = "fluid", rare: bool = False, exposed: bool = False, **fixed
) -> FlameParams:
    """Random flame parameters: shape, box aspect ratio (:func:`sample_aspect`), size of the burning body, wind,
    turbulence, smoke, exposure; ``rare`` picks a chemical palette of :data:`RARE_PALETTES`; ``exposed``: a
    black-body flame gets the camera-exposed palette at :func:`exposed_gain` of its peak (the same draws either
    way). Keyword arguments in ``fixed`` override the sampled values."""
    shape = str(rng.choice(SHAPES, p=np.asarray(SHAPE_WEIGHTS) / sum(SHAPE_WEIGHTS)))
    names = list(RARE_PALETTES)
    weights = np.asarray([RARE_PALETTES[k] for k in names]) / sum(RARE_PALETTES.values())
    palette = str(rng.choice(names, p=weights)) if rare else "blackbody"
    aspect = sample_aspect(rng)
    reach = {"point": 0.8, "line": 1.3, "ring": 1.3, "pool": 1.5, "jet": 0.7}[shape]  # base width / box width
    p = FlameParams(
        generator=generator,
        shape=shape,
        source_width=float(np.clip(0.45 * aspect * reach * rng.uniform(0.85, 1.15), 0.08, 0.85)),
        buoyancy=float(rng.uniform(0.06, 0.12)),
        wind=float(rng.normal(0.0, 0.006)),
        turbulence=float(rng.uniform(0.03, 0.09)),
        vorticity=float(rng.uniform(0.05, 0.2)),
        cooling=float(rng.uniform(0.07, 0.13)),
        soot=float(rng.uniform(0.3, 1.2)),
        smoke=float(rng.choice([0.0, rng.uniform(0.2, 1.0), rng.uniform(1.5, 4.0)], p=[0.3, 0.5, 0.2])),
        smoke_grey=float(rng.uniform(0.12, 0.45)),
        palette=palette,
        exposure=float(rng.uniform(8.0, 13.0)),  # measured on the flame gap: a wide orange-yellow gradient
        peak=float(rng.uniform(1.3, 2.0)),  # beats a body clipped flat to pale yellow (docs/findings.md)
        body=float(rng.uniform(0.15, 0.35)),
        detail=float(rng.uniform(1.5, 2.5)),
        aspect=aspect,
    )
    if exposed and palette == "blackbody":
        p = replace(p, gain=exposed_gain(p.peak))
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


def _tongues(p: FlameParams, rng: np.random.Generator) -> list[tuple[float, float, float]]:
    """The burning body as tongues (centre x as a fraction of the width from the middle, half width as a
    fraction of the width, height as a fraction of ``p.body``): one for a point or jet, two strong ends and a
    lower middle for a ring, several side by side over the source for a line or pool."""
    half = p.source_width / 2
    if p.shape in ("point", "jet"):
        return [(0.0, half, 1.0 if p.shape == "point" else 1.4)]
    if p.shape == "ring":
        return [(-half, 0.3 * half, 1.0), (half, 0.3 * half, 1.0), (0.0, 0.8 * half, 0.5)]
    n = int(rng.integers(2, 5)) if p.shape == "line" else int(rng.integers(3, 7))
    n = max(1, min(n, int(p.source_width / 0.1)))  # tongues at least ~1/10 of the grid wide
    centres = np.linspace(-half, half, n + 2)[1:-1] + rng.normal(0.0, 0.25 * half / n, n)
    return [(float(c), float(1.4 * half / n), float(rng.uniform(0.45, 1.0))) for c in centres]


def source_mask(p: FlameParams, rng: np.random.Generator) -> F32:
    """(rows, cols) emission strength in [0, 1]: the burning body standing on row ``rows - 3`` (see
    :func:`_tongues`), each tongue a teardrop ``p.body`` x its height high."""
    rows, cols = p.rows, p.cols
    x = ((np.arange(cols, dtype=np.float32) - cols / 2 + 0.5) / cols)[None, :]
    up = ((rows - 3 - np.arange(rows, dtype=np.float32)) / max(p.body * rows, 2.0))[:, None]  # 0 at the base
    mask = np.zeros((rows, cols), np.float32)
    for centre, half, height in _tongues(p, rng):
        u = np.clip(up / height, 0.0, 1.0)
        width = half * np.sqrt(1.0 - u) * (0.7 + 0.6 * u)  # a teardrop: widest a third of the way up
        soft = max(0.35 * half, 1.5 / cols)
        tongue = np.clip((width - np.abs(x - centre)) / soft, 0.0, 1.0) * (up >= 0)
        mask = np.maximum(mask, tongue)
    return mask.astype(np.float32)


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
    s.u = DRAG * s.u + p.wind * height + p.turbulence * _noise(rng, shape, 6)
    s.v += p.turbulence * _noise(rng, shape, 6)
    fu, fv = vorticity_force(s.u, s.v, p.vorticity)
    s.u, s.v = s.u + fu, s.v + fv
    s.u, s.v = advect(s.u, s.u, s.v, grid), advect(s.v, s.u, s.v, grid)
    s.u, s.v, s.pressure = project(s.u, s.v, s.pressure, p.jacobi_iters)
    hot = advect(s.temperature, s.u, s.v, grid)
    cooled = np.clip(hot - p.cooling * (hot**4 + 0.3 * hot + 0.15), 0.0, 1.0)  # + 0.15: dim tails burn out
    s.soot = advect(s.soot, s.u, s.v, grid) * 0.995 + p.soot * (hot - cooled)
    s.temperature = cooled.astype(np.float32)


def _border_window(shape: tuple[int, int], fraction: float = 0.25) -> F32:
    """(h, w) factor fading smoke to 0 towards the left, right and top borders over ``fraction`` of the side (the
    bottom over 0.4 of that), in a smoothstep: no hard or straight edge where the plume leaves the domain or
    where the sprite ends under a plume blown down beside the flame."""
    h, w = shape
    ramp_x = np.clip(np.minimum(np.arange(w), np.arange(w)[::-1]) / max(fraction * w, 1.0), 0, 1)
    ramp_y = np.clip(np.arange(h) / max(fraction * h, 1.0), 0, 1)
    ramp_y = np.minimum(ramp_y, np.clip(np.arange(h)[::-1] / max(0.4 * fraction * h, 1.0), 0, 1))
    return (smoothstep(ramp_y)[:, None] * smoothstep(ramp_x)[None, :]).astype(np.float32)


def tint_weight(p: FlameParams, bottom: int) -> F32 | None:
    """(rows, cols) weight in [0, 1] of the chemical palette against the black-body one (:data:`TINTS`), by
    height above row ``bottom``; None for a black-body flame."""
    if p.palette == "blackbody":
        return None
    base, top, reach = TINTS.get(p.palette, DEFAULT_TINT)
    up = np.clip((bottom - np.arange(p.rows, dtype=np.float32)) / max(reach * p.body * p.rows, 1.0), 0.0, 1.0)
    return np.repeat((base + (top - base) * up)[:, None], p.cols, axis=1).astype(np.float32)


def palettes(p: FlameParams) -> tuple[F32, F32 | None]:
    """(black-body palette, chemical palette or None) of ``p``: the black body the display palette, or with
    ``p.gain`` > 0 the camera-exposed one (:func:`synth.flames.colour.exposed_palette`); the chemical one is exposed at most
    1.2 x so its hue survives (a blue base is blue, not clipped white)."""
    if p.gain > 0:
        body = exposed_palette(p.gain, exposure=p.exposure)
    else:
        body = flame_palette("blackbody", exposure=p.exposure, peak=p.peak)
    if p.palette == "blackbody":
        return body, None
    return body, flame_palette(p.palette, exposure=p.exposure, peak=min(p.peak, 1.2))


def edge_warp(p: FlameParams, rng: np.random.Generator, tall: int = 4) -> tuple[F32, F32]:
    """Two (tall x rows x scale, cols x scale) noise fields in output pixels (amplitude ``p.detail`` cells) that
    :func:`render_fields` scrolls upwards frame by frame to warp the flame: crisp, turbulent edges below the
    grid's resolution."""
    shape = (p.rows * p.scale * tall, p.cols * p.scale)
    amp = p.detail * p.scale
    fields = []
    for _ in range(2):
        n = sum(_noise(rng, shape, c * p.scale) * w for c, w in ((4, 0.6), (2, 0.3), (1, 0.2)))
        fields.append((n * amp).astype(np.float32))
    return fields[0], fields[1]


def streaks(p: FlameParams, rng: np.random.Generator, tall: int = 4) -> F32:
    """A (tall x rows x scale, cols x scale) field in [0, 1] of thin vertical streaks (noise cells 1.5 x 8 and
    0.75 x 3 grid cells) that :func:`render_fields` scrolls upwards with the warp: where it is high the flame's
    temperature dips by up to ``p.texture``, so its body shows orange tongues and licks inside the yellow, as
    real flames do, instead of one flat clipped colour."""
    shape = (p.rows * p.scale * tall, p.cols * p.scale)
    field = np.zeros(shape, np.float32)
    for (across, up), weight in (((1.5, 8.0), 0.65), ((0.75, 3.0), 0.35)):
        small = rng.standard_normal(
            (max(int(shape[0] / (up * p.scale)), 2), max(int(shape[1] / (across * p.scale)), 2))
        )
        field += weight * cv2.resize(small.astype(np.float32), (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)
    return np.clip(0.5 + 0.5 * field / max(float(field.std()), 1e-6), 0.0, 1.0).astype(np.float32)


def render_fields(
    temperature: F32,
    soot: F32,
    p: FlameParams,
    palette: F32,
    mask_level: float = 0.2,
    warp: tuple[F32, F32] | None = None,
    tint: tuple[F32, F32] | None = None,
    texture: F32 | None = None,
) -> Sprite:
    """Fields (rows, cols) -> an uncropped sprite of (rows * scale, cols * scale) pixels. ``warp``: (dx, dy)
    displacements in output pixels of that size, applied to the temperature; ``tint``: (chemical palette,
    (rows, cols) weight) mixed into ``palette``; ``texture``: a :func:`streaks` window of that size (the
    temperature times ``1 - p.texture * texture``, and its edge softened by a blur of ``p.texture * scale``
    pixels: a gradient through orange and red, not a crisp orange rim). The flame mask is where the emitted
    colour's brightest channel exceeds ``mask_level`` (visible fire)."""
    size = (p.cols * p.scale, p.rows * p.scale)
    t = np.clip(cv2.resize(temperature, size, interpolation=cv2.INTER_CUBIC), 0.0, 1.0)
    if warp is not None:
        gy, gx = np.mgrid[0 : size[1], 0 : size[0]].astype(np.float32)
        t = cv2.remap(t, gx + warp[0], gy + warp[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    if texture is not None and p.texture > 0:
        t = cv2.GaussianBlur(t * (1.0 - p.texture * texture), (0, 0), sigmaX=p.texture * p.scale)
    idx = np.round(t * (len(palette) - 1)).astype(np.intp)
    emission = palette[idx]
    if tint is not None:
        w = cv2.resize(tint[1], size, interpolation=cv2.INTER_LINEAR)[..., None]
        emission = (1.0 - w) * emission + w * tint[0][idx]
    mask = emission.max(axis=-1) > mask_level
    dens = np.clip(cv2.resize(soot, size, interpolation=cv2.INTER_LINEAR), 0.0, None)
    window = _border_window(t.shape)
    alpha = (1.0 - np.exp(-p.smoke * dens)) * (1.0 - emission.max(axis=-1)) * window
    over = np.empty(t.shape + (4,), np.uint8)
    over[..., :3] = np.uint8(round(p.smoke_grey * 255))
    over[..., 3] = unit_to_u8(alpha)
    return Sprite(over, np.round(emission * 255).astype(np.uint8), mask)


def _frame_warp(warp: tuple[F32, ...], rows: int, step: int) -> tuple[F32, ...]:
    """The ``rows``-high window of the tall ``warp`` fields at ``step`` (scrolling upwards, wrapping)."""
    span = len(warp[0]) - rows
    off = span - (3 * step) % span
    return tuple(f[off : off + rows] for f in warp)


def simulate_fluid(p: FlameParams, rng: np.random.Generator) -> list[Sprite]:
    """Run the stable-fluid fire for ``p.frames`` steps; uncropped sprites of every ``keep_every`` th step."""
    shape = (p.rows, p.cols)
    zeros = np.zeros(shape, np.float32)
    state = FluidState(zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy())
    gy, gx = np.mgrid[0 : p.rows, 0 : p.cols].astype(np.float32)
    body, chemical = palettes(p)
    weight = tint_weight(p, p.rows - 3)
    tint = None if chemical is None or weight is None else (chemical, weight)
    src = source_mask(p, rng)
    base = base_attenuation(p, p.rows - 3, rng)
    warp = edge_warp(p, rng)
    texture_at = streaks_at(p, rng)
    frames = []
    for step in range(p.warmup + p.frames):
        fluid_step(state, p, src, (gx, gy), rng)
        kept = step - p.warmup
        if kept >= 0 and kept % p.keep_every == 0:
            dx, dy = _frame_warp(warp, p.rows * p.scale, kept)
            fields = (state.temperature * base, state.soot, p, body)
            frames.append(render_fields(*fields, warp=(dx, dy), tint=tint, texture=texture_at(kept)))
    return frames


def streaks_at(p: FlameParams, rng: np.random.Generator) -> Callable[[int], F32 | None]:
    """The flame's :func:`streaks` as a function of the kept step: the (rows, cols) field scrolled up with the
    flame at that step, or None without ``p.texture`` (then nothing is drawn from ``rng``; else one seed)."""
    if p.texture <= 0:
        return lambda step: None
    inner = streaks(p, np.random.default_rng(rng.integers(2**63)))
    return lambda step: _frame_warp((inner,), p.rows * p.scale, step)[0]


def simulate_noise(p: FlameParams, rng: np.random.Generator) -> list[Sprite]:
    """The cheap generator: a tapered flame profile warped by upward-scrolling fractal noise."""
    rows, cols = p.rows, p.cols
    tall = sum(_noise(rng, (rows * 4, cols), c) * (c / 16) for c in (16, 8, 4))
    y = np.linspace(1.0, 0.0, rows, dtype=np.float32)[:, None]  # 0 at the bottom row, 1 at the top
    x = (np.arange(cols, dtype=np.float32) - cols / 2 + 0.5)[None, :] / cols
    if p.gain > 0:
        palette = exposed_palette(p.gain, exposure=p.exposure)
    else:
        palette = flame_palette(p.palette, exposure=p.exposure, peak=p.peak)
    base = base_attenuation(p, rows, rng)
    warp = edge_warp(p, rng) if p.detail > 0 else None
    texture_at = streaks_at(p, rng)
    frames = []
    for step in range(0, p.frames, p.keep_every):
        off = (step * 2) % (rows * 3)
        n = tall[rows * 3 - off : rows * 4 - off]
        sway = p.wind * 20 * y**1.5 + 0.04 * n * y
        width = p.source_width * (1.0 - y) ** 0.6 + 1e-3
        d = np.abs(x - sway) / width
        heat = np.clip(1.0 - d + 0.35 * n * (0.3 + y), 0, 1) * np.clip(1.2 - y * (1 + 0.3 * n), 0, 1)
        soot = np.clip(0.8 - d * 0.6, 0, 1) * np.clip(y - 0.5, 0, None) * (1 + 0.5 * n)
        w = None if warp is None else _frame_warp(warp, rows * p.scale, step)
        fields = ((heat * base).astype(np.float32), soot.astype(np.float32), p, palette)
        frames.append(render_fields(*fields, warp=w, tint=None, texture=texture_at(step)))
    return frames


GENERATORS: dict[str, Callable[[FlameParams, np.random.Generator], list[Sprite]]] = {
    "fluid": simulate_fluid,
    "noise": simulate_noise,
}


def mask_aspect(sprite: Sprite) -> float:
    """Width / height of the box of the sprite's flame mask (which must not be empty)."""
    rows, cols = np.nonzero(sprite.mask.any(axis=1))[0], np.nonzero(sprite.mask.any(axis=0))[0]
    return float(cols[-1] - cols[0] + 1) / float(rows[-1] - rows[0] + 1)


def stretch(sprite: Sprite, factor: float) -> Sprite:
    """The sprite resized sideways by ``factor`` (height kept); the mask resampled at 0.5."""
    h, w = sprite.mask.shape
    width = max(int(round(w * factor)), 1)
    interp = cv2.INTER_AREA if width < w else cv2.INTER_LINEAR
    over = cv2.resize(sprite.over, (width, h), interpolation=interp)
    emission = cv2.resize(sprite.emission, (width, h), interpolation=interp)
    mask = cv2.resize(sprite.mask.astype(np.float32), (width, h), interpolation=cv2.INTER_LINEAR) >= 0.5
    return Sprite(over.reshape(h, width, 4), emission.reshape(h, width, 3), mask.reshape(h, width))


def generate_sequence(name: str, p: FlameParams, rng: np.random.Generator) -> SpriteSequence:
    """Run the chosen generator and keep the frames that show a flame, alpha-cropped; with ``p.aspect`` > 0
    every frame is stretched sideways by one factor (at most :data:`MAX_STRETCH`) that brings the frames'
    median flame-box aspect ratio to ``p.aspect`` (recorded as ``stretch`` in the metadata)."""
    sprites = [c for c in (crop_to_content(s) for s in GENERATORS[p.generator](p, rng)) if c and c.mask.any()]
    factor = 1.0
    if p.aspect > 0 and sprites:
        median = float(np.median([mask_aspect(s) for s in sprites]))
        factor = float(np.clip(p.aspect / median, 1 / MAX_STRETCH, MAX_STRETCH))
        sprites = [stretch(s, factor) for s in sprites]
        sprites = [s for s in sprites if s.mask.any()]
    meta = {"generator": p.generator, "params": asdict(p), "stretch": round(factor, 4)}
    return SpriteSequence(name, tuple(sprites), meta)

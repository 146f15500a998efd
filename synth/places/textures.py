"""Procedural surface textures: (size, size, 3) uint8 RGB images that tile, each drawn from an explicit rng.

Chosen by name from :data:`TEXTURES` (unknown names raise). Colours are sRGB.
"""

from __future__ import annotations

from collections.abc import Callable

import cv2
import numpy as np
from numpy.typing import NDArray

U8 = NDArray[np.uint8]


def _tileable_noise(rng: np.random.Generator, size: int, cell: int) -> NDArray[np.float32]:
    """(size, size) smooth noise in ~[-1, 1] that tiles (wrap-around interpolation)."""
    n = max(size // cell, 2)
    small = rng.standard_normal((n, n)).astype(np.float32)
    big = cv2.resize(np.tile(small, (3, 3)), (size * 3, size * 3), interpolation=cv2.INTER_CUBIC)
    return big[size : 2 * size, size : 2 * size] / 1.5


def _fractal(rng: np.random.Generator, size: int) -> NDArray[np.float32]:
    return sum(_tileable_noise(rng, size, c) * (c / 32) for c in (32, 16, 8, 4))


def _colourise(base: NDArray[np.float64], shade: NDArray[np.float32], amount: float) -> U8:
    img = np.asarray(base, np.float32)[None, None, :] * (1.0 + amount * shade[..., None])
    return np.clip(img, 0, 255).astype(np.uint8)


def _jitter(rng: np.random.Generator, rgb: tuple[int, int, int], spread: float = 25.0) -> NDArray[np.float64]:
    return np.clip(np.asarray(rgb, float) + rng.normal(0, spread, 3), 10, 245)


#: Paints and finishes seen in real buildings (sRGB); each texture picks one and jitters it slightly.
PLASTER_PAINTS = (
    (236, 234, 228),  # white
    (226, 221, 208),  # off-white
    (214, 205, 186),  # beige
    (200, 200, 197),  # light grey
    (224, 214, 178),  # cream
    (192, 204, 210),  # pale blue
    (201, 211, 190),  # pale green
    (222, 204, 184),  # peach
)
CARPETS = ((112, 112, 116), (78, 88, 108), (108, 86, 66), (116, 54, 52), (80, 94, 72), (60, 60, 64))
BRICKS = ((150, 70, 50), (166, 96, 66), (128, 62, 46), (176, 122, 92))
TILES = ((222, 222, 218), (200, 200, 196), (214, 206, 190), (170, 172, 175))


def _pick(rng: np.random.Generator, palette: tuple[tuple[int, int, int], ...], spread: float) -> NDArray[np.float64]:
    return _jitter(rng, palette[int(rng.integers(len(palette)))], spread)


def plaster(rng: np.random.Generator, size: int = 128) -> U8:
    return _colourise(_pick(rng, PLASTER_PAINTS, 5), _fractal(rng, size), 0.05)


def concrete(rng: np.random.Generator, size: int = 128) -> U8:
    shade = _fractal(rng, size) * 0.6 + 0.4 * _tileable_noise(rng, size, 2)
    return _colourise(_jitter(rng, (140, 138, 132), 12), shade, 0.12)


def planks(rng: np.random.Generator, size: int = 128) -> U8:
    base = _jitter(rng, (150, 100, 60), 20)
    y = np.arange(size)[:, None]
    grain = np.sin((y + 6 * _fractal(rng, size)) * 0.9).astype(np.float32) * 0.5 + _fractal(rng, size) * 0.5
    img = _colourise(base, grain, 0.15)
    board = max(size // 6, 4)
    img[::board] = (img[::board] * 0.55).astype(np.uint8)
    return img


def tiles(rng: np.random.Generator, size: int = 128) -> U8:
    img = _colourise(_pick(rng, TILES, 6), _fractal(rng, size), 0.05)
    step = size // int(rng.choice([4, 8]))
    grout = np.clip(img[0, 0].astype(int) - 70, 40, 255).astype(np.uint8)
    img[::step], img[:, ::step] = grout, grout
    return img


def bricks(rng: np.random.Generator, size: int = 128) -> U8:
    img = _colourise(_pick(rng, BRICKS, 10), _fractal(rng, size) + 0.4 * _tileable_noise(rng, size, 2), 0.15)
    rows, h = 8, size // 8
    mortar = int(rng.integers(150, 200))
    for r in range(rows):
        img[r * h : r * h + 2] = mortar
        off = h if r % 2 else 0
        img[r * h : (r + 1) * h, off :: 2 * h][:, :2] = mortar
    return img


def grass(rng: np.random.Generator, size: int = 128) -> U8:
    return _colourise(_jitter(rng, (70, 110, 45), 15), _fractal(rng, size) + 0.5 * _tileable_noise(rng, size, 2), 0.3)


def asphalt(rng: np.random.Generator, size: int = 128) -> U8:
    return _colourise(_jitter(rng, (75, 75, 78), 8), _fractal(rng, size) + 0.6 * _tileable_noise(rng, size, 2), 0.2)


def metal(rng: np.random.Generator, size: int = 128) -> U8:
    img = _colourise(_jitter(rng, (150, 155, 160), 15), _fractal(rng, size), 0.1)
    img[:, :: max(size // 8, 2)] = (img[:, :: max(size // 8, 2)] * 0.7).astype(np.uint8)
    return img


def carpet(rng: np.random.Generator, size: int = 128) -> U8:
    return _colourise(_pick(rng, CARPETS, 8), _tileable_noise(rng, size, 2), 0.12)


TEXTURES: dict[str, Callable[[np.random.Generator, int], U8]] = {
    "plaster": plaster,
    "concrete": concrete,
    "planks": planks,
    "tiles": tiles,
    "bricks": bricks,
    "grass": grass,
    "asphalt": asphalt,
    "metal": metal,
    "carpet": carpet,
}


def make_texture(name: str, rng: np.random.Generator, size: int = 128) -> U8:
    """(size, size, 3) uint8 texture called ``name``."""
    if name not in TEXTURES:
        raise ValueError(f"unknown texture {name!r}; choose one of {', '.join(TEXTURES)}")
    return TEXTURES[name](rng, size)

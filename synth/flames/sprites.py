"""Flame sprites: the layers a compositor needs, and sequences of them on disk.

A :class:`Sprite` of size (h, w) holds
- ``over``: (h, w, 4) uint8 straight-alpha RGBA laid *over* the background (smoke, or a user's RGBA render),
- ``emission``: (h, w, 3) uint8 sRGB light *added* on top (the flame's glow),
- ``mask``: (h, w) bool, the flame itself (the box comes from here, never from the smoke),
- ``smoke``: whether the part of ``over`` that is not flame is smoke (False for a flame cut out of a photo, whose
  ``over`` is the flame and the dim edge around it: :func:`load_rgba_folder`).

Composite of one sprite: ``out = bg * (1 - a) + rgb * a``, then ``out = blend(out, emission)``.

On disk a sequence is a folder: ``sequence.json`` (generator, parameters, frame indices, what each file
holds) and per kept frame ``NNNN_emission.png`` (the flame's light on black: what the flame looks like),
``NNNN_mask.png`` and, when the frame has any smoke, ``NNNN_smoke.png`` (the ``over`` layer: for a procedural
flame it holds only the smoke, the flame being light; a frame without smoke has no file and loads as a fully
transparent layer). Lossless, deterministic bytes. Folders written before the smoke layer had its name keep
it as ``NNNN_over.png`` and load the same. ``fuzzyfire synth flames`` also draws ``preview.png``
(:mod:`synth.flames.preview`).
A user's own RGBA sequence (e.g. EmberGen renders) is a folder of RGBA PNGs: see :func:`sprite_from_rgba`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.image.imageio import ImageError

#: A sprite pixel is *smoke* where its ``over`` alpha is at least this (and it is not flame): smoke a viewer sees
#: (a quarter of the background hidden), not the faint haze at the plume's edges. Smoke boxes come from here.
SMOKE_ALPHA = 0.25

#: ``meta["kind"]`` of a smoke sequence (a plume, a smoke matte; flames have none): Method 2 lays these as plumes.
SMOKE_KIND = "smoke"

#: What each file of a sequence folder holds (written into ``sequence.json`` for whoever opens the folder).
LAYER_FILES: dict[str, str] = {
    "NNNN_emission.png": "the flame's light on black, added on top of the background (what the flame looks like)",
    "NNNN_mask.png": "the flame (white): its box comes from here",
    "NNNN_smoke.png": "smoke as straight-alpha RGBA laid over the background; no file when a frame has no smoke",
    "preview.png (library folder)": "every sequence's frames composited over a dark and a light background",
}


@dataclass(frozen=True)
class Sprite:
    over: NDArray[np.uint8]
    emission: NDArray[np.uint8]
    mask: NDArray[np.bool_]
    smoke: bool = True

    def __post_init__(self) -> None:
        h, w = self.mask.shape
        assert self.over.shape == (h, w, 4) and self.emission.shape == (h, w, 3), "sprite layers differ in size"

    def smoke_mask(self) -> NDArray[np.bool_]:
        """(h, w) bool: smoke pixels (``over`` alpha >= :data:`SMOKE_ALPHA`, not flame; none unless ``smoke``)."""
        return (self.over[..., 3] >= round(SMOKE_ALPHA * 255)) & ~self.mask & self.smoke

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.mask.shape[1], self.mask.shape[0]


@dataclass(frozen=True)
class SpriteSequence:
    name: str
    sprites: tuple[Sprite, ...]
    meta: Mapping[str, Any]


def is_smoke(seq: SpriteSequence) -> bool:
    """Whether ``seq`` is a smoke sequence (a plume or a smoke matte) rather than a flame."""
    return seq.meta.get("kind") == SMOKE_KIND


def mask_span(sprite: Sprite) -> tuple[int, int, int, int] | None:
    """(first column, first row, last column, last row), inclusive sprite pixels, of the sprite's flame mask; None
    when the mask is empty."""
    rows, cols = np.flatnonzero(sprite.mask.any(axis=1)), np.flatnonzero(sprite.mask.any(axis=0))
    if not rows.size:
        return None
    return int(cols[0]), int(rows[0]), int(cols[-1]), int(rows[-1])


def flame_rect(sprite: Sprite) -> tuple[int, int, int, int]:
    """:func:`mask_span` of ``sprite``, its whole canvas when the mask is empty."""
    return mask_span(sprite) or (0, 0, sprite.size[0] - 1, sprite.size[1] - 1)


def flame_extent(sprite: Sprite) -> tuple[int, int]:
    """(width, height) in sprite pixels of the box of the sprite's flame mask (the sprite's size when the mask is
    empty): what a flame's size in the scene refers to (smoke above it is not the flame)."""
    c0, r0, c1, r1 = flame_rect(sprite)
    return c1 - c0 + 1, r1 - r0 + 1


def content_rect(sprite: Sprite, threshold: int = 2, pad: int = 1) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1), sprite pixels, end exclusive: the pixels that show anything (alpha, emission or mask above
    ``threshold``) with ``pad`` pixels margin, inside the sprite; None when it shows nothing."""
    visible = (sprite.over[..., 3] > threshold) | (sprite.emission.max(axis=-1) > threshold) | sprite.mask
    rows, cols = np.nonzero(visible.any(axis=1))[0], np.nonzero(visible.any(axis=0))[0]
    if rows.size == 0:
        return None
    h, w = sprite.mask.shape
    return max(cols[0] - pad, 0), max(rows[0] - pad, 0), min(cols[-1] + 1 + pad, w), min(rows[-1] + 1 + pad, h)


def crop_to_content(sprite: Sprite, threshold: int = 2, pad: int = 1) -> Sprite | None:
    """The sprite cropped to :func:`content_rect`; None when it shows nothing."""
    rect = content_rect(sprite, threshold, pad)
    return None if rect is None else crop_sprite(sprite, rect)


def shown_part(sprite: Sprite) -> Sprite | None:
    """``sprite`` cropped to :func:`content_rect`, or None when that part holds no flame pixel."""
    rect = content_rect(sprite)
    if rect is None:
        return None
    part = crop_sprite(sprite, rect)
    return part if part.mask.any() else None


def crop_sprite(sprite: Sprite, rect: tuple[int, int, int, int]) -> Sprite:
    """The part (x0, y0, x1, y1) of ``sprite`` (sprite pixels, end exclusive), copied."""
    x0, y0, x1, y1 = (int(v) for v in rect)
    cut = (slice(y0, y1), slice(x0, x1))
    return Sprite(sprite.over[cut].copy(), sprite.emission[cut].copy(), sprite.mask[cut].copy(), sprite.smoke)


def flatten_rgba(sprite: Sprite) -> NDArray[np.uint8]:
    """One (h, w, 4) uint8 straight-alpha RGBA image approximating the sprite under plain alpha blending (what
    a textured plane in a 3D scene can show): the emission counts as coverage ``e`` (its brightest channel),
    ``a = 1 - (1 - a_smoke)(1 - e)`` and ``rgb = (smoke * a_smoke (1 - e) + emission) / a``. Flame cores
    become opaque, their edges and the smoke semi-transparent."""
    over = sprite.over.astype(np.float32) / 255.0
    emission = sprite.emission.astype(np.float32) / 255.0
    e = emission.max(axis=-1, keepdims=True)
    a_smoke = over[..., 3:4]
    alpha = 1.0 - (1.0 - a_smoke) * (1.0 - e)
    rgb = (over[..., :3] * a_smoke * (1.0 - e) + emission) / np.maximum(alpha, 1e-6)
    out = np.concatenate([np.clip(rgb, 0.0, 1.0), alpha], axis=-1)
    return np.round(out * 255.0).astype(np.uint8)


def sprite_from_rgba(rgba: NDArray[np.uint8], flame_threshold: float = 0.55, smoke: bool = True) -> Sprite:
    """A sprite from a user's (h, w, 4) straight-alpha RGBA render: laid over as is, no added emission; the flame
    mask is where alpha >= 0.5 and the brightest channel >= ``flame_threshold`` (bright, not grey smoke); ``smoke``:
    whether the rest of it is smoke (a render's grey plume) or not (a cut-out's dim flame edge)."""
    if rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(f"expected an RGBA image, got shape {rgba.shape}")
    rgb = rgba[..., :3].astype(np.float32) / 255.0
    bright = rgb.max(axis=-1)
    saturated = bright - rgb.min(axis=-1) > 0.15
    mask = (rgba[..., 3] >= 128) & (bright >= flame_threshold) & (saturated | (bright > 0.9))
    return Sprite(np.ascontiguousarray(rgba), np.zeros(rgba.shape[:2] + (3,), np.uint8), mask, smoke)


def write_png(path: Path, array: NDArray[np.uint8]) -> None:
    """Write an (h, w) grey, (h, w, 3) RGB or (h, w, 4) RGBA uint8 array as a PNG; OSError when it cannot."""
    if array.ndim == 3:
        array = cv2.cvtColor(array, cv2.COLOR_RGBA2BGRA if array.shape[2] == 4 else cv2.COLOR_RGB2BGR)
    if not cv2.imwrite(str(path), array, [cv2.IMWRITE_PNG_COMPRESSION, 3]):
        raise OSError(f"{path}: could not write PNG")


def _read_png(path: Path, flags: int = cv2.IMREAD_UNCHANGED) -> NDArray[np.uint8]:
    data = cv2.imread(str(path), flags)
    if data is None:
        raise ImageError(path, "cannot be decoded as PNG")
    if data.ndim == 3:
        data = cv2.cvtColor(data, cv2.COLOR_BGRA2RGBA if data.shape[2] == 4 else cv2.COLOR_BGR2RGB)
    return data


def save_sequence(folder: Path, seq: SpriteSequence) -> Path:
    """Write ``seq`` into ``folder`` (created); returns the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    for i, sp in enumerate(seq.sprites):
        if sp.over[..., 3].any():
            write_png(folder / f"{i:04d}_smoke.png", sp.over)
        write_png(folder / f"{i:04d}_emission.png", sp.emission)
        write_png(folder / f"{i:04d}_mask.png", sp.mask.astype(np.uint8) * 255)
    meta = {"name": seq.name, "frames": len(seq.sprites), **dict(seq.meta), "layers": LAYER_FILES}
    (folder / "sequence.json").write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return folder


def load_sequence(folder: Path) -> SpriteSequence:
    """Read a folder written by :func:`save_sequence`, or a user's folder of RGBA PNGs (sorted by name)."""
    meta_path = folder / "sequence.json"
    if not meta_path.is_file():
        return load_rgba_folder(folder)
    meta = json.loads(meta_path.read_text(encoding="utf-8"))
    sprites = []
    for i in range(int(meta["frames"])):
        emission = _read_png(folder / f"{i:04d}_emission.png")
        mask = _read_png(folder / f"{i:04d}_mask.png", cv2.IMREAD_GRAYSCALE) > 127
        sprites.append(Sprite(_read_over(folder, i, mask.shape), emission, mask))
    return SpriteSequence(str(meta.get("name", folder.name)), tuple(sprites), meta)


def _read_over(folder: Path, i: int, shape: tuple[int, int]) -> NDArray[np.uint8]:
    """Frame ``i``'s (h, w, 4) ``over`` layer: ``NNNN_smoke.png``, else an older folder's ``NNNN_over.png``, else
    (a frame without smoke) fully transparent zeros."""
    for name in (f"{i:04d}_smoke.png", f"{i:04d}_over.png"):
        if (folder / name).is_file():
            return _read_png(folder / name)
    return np.zeros((*shape, 4), np.uint8)


def load_rgba_folder(folder: Path) -> SpriteSequence:
    """A user's RGBA sequence (or a ``synth cutouts`` sequence): every ``*.png`` in ``folder`` with an alpha channel,
    cropped to its content; frames with no flame pixel are skipped. ``meta["files"]``: the PNG of each kept
    sprite. A cut-out sequence (its parent holds ``cutouts.json``) is flame alone: its sprites carry no smoke."""
    cut = (folder.parent / "cutouts.json").is_file()
    paths = sorted(p for p in folder.glob("*.png") if p.is_file())
    if not paths:
        raise FileNotFoundError(f"{folder}: no sequence.json and no PNG frames")
    sprites, files = [], []
    for path in paths:
        rgba = _read_png(path)
        if rgba.ndim != 3 or rgba.shape[2] != 4:
            raise ImageError(path, "has no alpha channel (RGBA PNG needed)")
        kept = shown_part(sprite_from_rgba(rgba, smoke=not cut))
        if kept is not None:
            sprites.append(kept)
            files.append(path.name)
    if not sprites:
        raise ImageError(folder, "no frame shows a flame (bright, opaque pixels)")
    return SpriteSequence(folder.name, tuple(sprites), {"generator": "user-rgba", "files": files})


def load_library(folders: Sequence[Path]) -> list[SpriteSequence]:
    """Every sequence folder in ``folders`` (each either a sequence or a folder of sequence folders)."""
    seqs: list[SpriteSequence] = []
    for folder in folders:
        subs = sorted(p for p in folder.iterdir() if p.is_dir()) if not (folder / "sequence.json").exists() else []
        for sub in subs or [folder]:
            seqs.append(load_sequence(sub))
    return seqs

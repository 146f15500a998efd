"""Helpers for the curation tests (not a test module): a per-session model cache and generated photos.

Generated "scenes" are random shapes on gradients: distinct seeds give images a CNN tells apart, and
:func:`transformed` makes the near-duplicate copies the dedup tests must find.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray
from PIL import Image

from curate.calibrate import centre_crop, hflip

MPL_SAMPLE = Path(__import__("matplotlib").get_data_path()) / "sample_data"
GRACE_HOPPER = MPL_SAMPLE / "grace_hopper.jpg"  # ImageNet class 652 "military uniform"


def use_session_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Point FUZZYFIRE_CACHE at one folder per test session (the ONNX export then happens once)."""
    folder = tmp_path_factory.getbasetemp() / "fuzzyfire-cache"
    folder.mkdir(exist_ok=True)
    os.environ["FUZZYFIRE_CACHE"] = str(folder)
    return folder


def scene(seed: int, size: tuple[int, int] = (160, 120)) -> NDArray[np.uint8]:
    """A (H, W, 3) uint8 RGB picture of random rectangles, circles and lines on a colour gradient."""
    rng = np.random.default_rng(seed)
    w, h = size
    c0, c1 = rng.integers(0, 256, 3), rng.integers(0, 256, 3)
    t = np.linspace(0, 1, w)[None, :, None]
    img = np.ascontiguousarray(np.broadcast_to(c0 * (1 - t) + c1 * t, (h, w, 3)).astype(np.uint8))
    for _ in range(int(rng.integers(4, 9))):
        color = tuple(int(v) for v in rng.integers(0, 256, 3))
        x0, y0 = int(rng.integers(0, w)), int(rng.integers(0, h))
        kind = rng.integers(0, 3)
        if kind == 0:
            cv2.rectangle(
                img, (x0, y0), (x0 + int(rng.integers(10, w // 2)), y0 + int(rng.integers(10, h // 2))), color, -1
            )
        elif kind == 1:
            cv2.circle(img, (x0, y0), int(rng.integers(5, h // 3)), color, -1)
        else:
            cv2.line(img, (x0, y0), (int(rng.integers(0, w)), int(rng.integers(0, h))), color, int(rng.integers(2, 8)))
    return img


def transformed(img: NDArray[np.uint8], kind: str) -> NDArray[np.uint8]:
    """A near-duplicate copy: ``hflip``, ``crop`` (90 %), ``resize`` (75 %), ``bright`` (+15 %)."""
    h, w = img.shape[:2]
    if kind == "hflip":
        return hflip(img)
    if kind == "crop":
        return centre_crop(img, 20)
    if kind == "resize":
        return cv2.resize(img, (w * 3 // 4, h * 3 // 4), interpolation=cv2.INTER_AREA)
    if kind == "bright":
        return np.clip(img.astype(np.int32) * 115 // 100, 0, 255).astype(np.uint8)
    raise ValueError(kind)


def save(img: NDArray[np.uint8], path: Path, quality: int = 92) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    kwargs = {"quality": quality} if path.suffix.lower() in (".jpg", ".jpeg") else {}
    Image.fromarray(img).save(path, **kwargs)
    return path


def write_scene_dataset(
    root: Path, items: dict[str, tuple[int, str | None]], names: tuple[str, ...] = ("fire", "smoke")
) -> Path:
    """A YOLO folder ``root/train/{images,labels}`` + data.yaml: ``stem -> (scene seed, transform or None)``;
    each image gets one box of class ``seed % len(names)`` whose size depends on the seed."""
    for stem, (seed, kind) in items.items():
        img = scene(seed) if kind is None else transformed(scene(seed), kind)
        save(img, root / "train" / "images" / f"{stem}.jpg")
        label = root / "train" / "labels" / f"{stem}.txt"
        label.parent.mkdir(parents=True, exist_ok=True)
        label.write_text(f"{seed % len(names)} 0.5 0.5 {0.1 + 0.01 * (seed % 50):.2f} 0.25\n")
    (root / "data.yaml").write_text(f"train: train/images\nnc: {len(names)}\nnames: [{', '.join(names)}]\n")
    return root

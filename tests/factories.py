"""Tiny on-disk images and datasets for tests (written with explicit seeds, never shipped data)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from PIL import Image


def write_image(path: Path, width: int, height: int, seed: int = 0, fmt: str | None = None) -> Path:
    """A random RGB image of ``width`` x ``height`` at ``path`` (format from the suffix)."""
    rng = np.random.default_rng(seed)
    pixels = rng.integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(pixels).save(path, format=fmt)
    return path


def jpeg_bytes(width: int, height: int, seed: int = 0, orientation: int | None = None) -> bytes:
    rng = np.random.default_rng(seed)
    pixels = rng.integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    buf = io.BytesIO()
    kwargs = {}
    if orientation is not None:
        exif = Image.Exif()
        exif[274] = orientation
        kwargs["exif"] = exif.tobytes()
    Image.fromarray(pixels).save(buf, "JPEG", quality=90, **kwargs)
    return buf.getvalue()


def write_yolo_dataset(root: Path, names: tuple[str, ...] = ("fire", "smoke")) -> dict[str, list[list[float]]]:
    """A Roboflow-style YOLO folder (train/valid, data.yaml) with known rows; returns label rows per stem."""
    rows = {
        "a": [[0, 0.5, 0.5, 0.25, 0.5], [1, 0.2, 0.3, 0.1, 0.2]],
        "b": [[0, 0.125, 0.75, 0.25, 0.1]],
        "c": [],  # negative with an empty label file
    }
    layout = {"a": ("train", 64, 48), "b": ("train", 80, 40), "c": ("valid", 32, 32)}
    for stem, (split, w, h) in layout.items():
        write_image(root / split / "images" / f"{stem}.jpg", w, h, seed=len(stem) + w)
        label = root / split / "labels" / f"{stem}.txt"
        label.parent.mkdir(parents=True, exist_ok=True)
        label.write_text("".join(" ".join(f"{v:g}" for v in r) + "\n" for r in rows[stem]))
    write_image(root / "valid" / "images" / "d.png", 40, 30, seed=7)  # negative without a label file
    (root / "data.yaml").write_text(
        f"train: ../train/images\nval: ../valid/images\nnc: {len(names)}\nnames: [{', '.join(names)}]\n"
    )
    return rows

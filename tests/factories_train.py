"""Tiny learnable detection datasets for the train tests: coloured rectangles on noisy backgrounds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from ground.data.dataset import Dataset, DatasetBuilder

COLOURS = {"fire": (250, 120, 20), "smoke": (40, 90, 250)}


def painted_dataset(root: Path, count: int, seed: int, size: tuple[int, int] = (80, 64)) -> Dataset:
    """``count`` PNG images of ``size`` (w, h) under ``root`` with 1-2 painted boxes each (negatives every 5th)."""
    rng = np.random.default_rng(seed)
    builder = DatasetBuilder(root, list(COLOURS))
    w, h = size
    for i in range(count):
        image = rng.integers(0, 90, size=(h, w, 3), dtype=np.uint8)
        boxes = []
        for _ in range(0 if i % 5 == 4 else int(rng.integers(1, 3))):
            bw, bh = int(rng.integers(10, w // 2)), int(rng.integers(10, h // 2))
            x, y = int(rng.integers(0, w - bw)), int(rng.integers(0, h - bh))
            name = list(COLOURS)[int(rng.integers(0, 2))]
            image[y : y + bh, x : x + bw] = COLOURS[name]
            boxes.append((name, (x, y, bw, bh)))
        path = root / f"img{i:03d}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(image).save(path)
        image_id = builder.add_image(path.name, w, h, source="real:painted")
        for name, box in boxes:
            builder.add_box(image_id, name, box)
    return builder.build()

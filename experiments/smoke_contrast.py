"""How faint is the smoke people label? The calibration of the smoke visibility rule (synth.compose.visibility).

For every smoke box of a labelled dataset (default: ../shared/data/fire-smoke-608, class ``smoke``), at least 16 px a
side, the CIE76 ΔE*ab of each pixel inside the box against the median colour of a ring around it (15 % of the box's
longer side, at least 8 px); per box the median and the 75th percentile of those differences; printed: the 5th,
10th, 25th and 50th percentiles of both over the boxes. The ring stands in for what is behind the smoke (a synthetic
plume has its exact plate), so the figures are a rough scale, not a measurement of each plume.

    python experiments/smoke_contrast.py [DATASET]
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

from ground.data.load import load_split
from ground.image.imageio import read_image
from synth.flames.cutouts import pixel_box


def box_contrast(lab: np.ndarray, box: tuple[int, int, int, int]) -> tuple[float, float] | None:
    """(median, 75th percentile) ΔE of the box's pixels against its ring's median colour; None without a ring."""
    x, y, w, h = box
    height, width = lab.shape[:2]
    pad = max(8, int(0.15 * max(w, h)))
    x0, y0, x1, y1 = max(x - pad, 0), max(y - pad, 0), min(x + w + pad, width), min(y + h + pad, height)
    ring = np.ones((y1 - y0, x1 - x0), bool)
    ring[y - y0 : y - y0 + h, x - x0 : x - x0 + w] = False
    if ring.sum() < 50:
        return None
    median = np.median(lab[y0:y1, x0:x1][ring], axis=0)
    d = np.sqrt(((lab[y : y + h, x : x + w].reshape(-1, 3) - median) ** 2).sum(-1))
    return float(np.median(d)), float(np.quantile(d, 0.75))


def main(path: Path) -> None:
    ds = load_split(path, classes=["smoke"], negatives=[n for n in load_split(path).category_names if n != "smoke"])
    boxes = ds.annotations_by_image()
    found = []
    for img in ds.images:
        if not boxes[img.id]:
            continue
        rgb = read_image(ds.image_path(img))
        lab = cv2.cvtColor(rgb.astype(np.float32) / 255.0, cv2.COLOR_RGB2Lab)
        for a in boxes[img.id]:
            box = pixel_box(a.bbox, rgb.shape[1], rgb.shape[0])
            if min(box[2], box[3]) >= 16 and (c := box_contrast(lab, box)) is not None:
                found.append(c)
    values = np.array(found)
    print(f"smoke boxes: {len(values)}")
    for q in (0.05, 0.1, 0.25, 0.5):
        median, upper = np.quantile(values, q, axis=0)
        print(f"percentile {q:.0%}: median pixel ΔE {median:.1f}, 75th-percentile pixel ΔE {upper:.1f}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "../shared/data/fire-smoke-608")

"""Cut-out mask quality against true flame masks: the ``colour`` rule against the ``grabcut`` rule
(:mod:`synth.flames.cutouts`). Prints ``name: value unit`` lines.

The images are Method 2 composites, whose flames' true visible masks are kept beside them (``masks/<name>.png``:
value k = the k-th fire box of the image, annotations in id order; :mod:`synth.audit`). Each fire box at least
16 px on both sides and at least 8 % fire-coloured (the command's defaults) is cut with each rule; the cut-out's
mask (alpha >= 128) is compared with the true mask inside the box: IoU mean and standard deviation, and the share
of near-filled rectangles (mask >= 90 % of the box: a fire-lit patch taken whole). Twice: with the boxes as
written (tight), and with each side widened by ``--loose`` of the box (hand-drawn labels are looser). Also the
time per cut-out of each rule.

Usage: ``python experiments/cutout_masks.py --environments ../shared/data/panoramas [--n 100] [--seed 0]``
(generates a Method 2 pool of ``--n`` 416x416 images in a temporary folder) or ``--pool DIR`` (a Method 2 pool
already made, e.g. by ``fuzzyfire synth method2``).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.image.imageio import read_image
from synth.flames.cutouts import MASK_RULES, CutoutConfig, cut, pixel_box

NEAR_FILLED = 0.9  # mask share of the box from which a cut-out counts as a filled rectangle


def make_pool(environments: list[Path], n: int, seed: int, out: Path) -> Path:
    """A Method 2 pool of ``n`` 416x416 composites on ``environments`` (panoramas or meshes) in ``out``."""
    from synth.flames.library import build_library
    from synth.generate import generate
    from synth.method2 import Method2Config

    cfg = Method2Config(n=n, seed=seed, width=416, height=416, scenes=0, environments=tuple(environments))
    generate(cfg, build_library(cfg.flames), out)
    return out


def fire_boxes(pool: Path) -> list[tuple[Path, Path, list[list[float]]]]:
    """(image path, instance mask path, fire boxes [x, y, w, h] in id order) of every image of ``pool``."""
    coco = json.loads((pool / "annotations.json").read_text(encoding="utf-8"))
    fire = next(c["id"] for c in coco["categories"] if c["name"] == "fire")
    boxes: dict[int, list[list[float]]] = {img["id"]: [] for img in coco["images"]}
    for a in sorted(coco["annotations"], key=lambda a: a["id"]):
        if a["category_id"] == fire:
            boxes[a["image_id"]].append(a["bbox"])
    out = []
    for img in coco["images"]:
        name = Path(img["file_name"])
        out.append((pool / name, pool / "masks" / name.relative_to("images").with_suffix(".png"), boxes[img["id"]]))
    return out


def widened(bbox: list[float], loose: float) -> tuple[float, float, float, float]:
    x, y, w, h = bbox
    return x - loose * w, y - loose * h, w * (1 + 2 * loose), h * (1 + 2 * loose)


def iou(a: NDArray[np.bool_], b: NDArray[np.bool_]) -> float:
    union = int((a | b).sum())
    return float((a & b).sum()) / union if union else 1.0


def measure(pool: Path, loose: float) -> dict[str, dict[str, list[float]]]:
    """Per rule: ``iou`` and ``filled`` (1/0) per cut box, and ``seconds`` per cut."""
    got: dict[str, dict[str, list[float]]] = {r: {"iou": [], "filled": [], "seconds": []} for r in MASK_RULES}
    for image, masks, boxes in fire_boxes(pool):
        rgb = read_image(image)
        labels = cv2.imread(str(masks), cv2.IMREAD_UNCHANGED)
        for k, bbox in enumerate(boxes, start=1):
            box = pixel_box(widened(bbox, loose), rgb.shape[1], rgb.shape[0])
            x, y, w, h = box
            if min(w, h) < CutoutConfig().min_side:
                continue
            truth = labels[y : y + h, x : x + w] == k
            for rule in MASK_RULES:
                start = time.perf_counter()
                result = cut(rgb, box, CutoutConfig(mask=rule))
                if result is None:
                    break  # under min_cover: skipped by every rule alike
                got[rule]["seconds"].append(time.perf_counter() - start)
                mask = result[0][..., 3] >= 128
                got[rule]["iou"].append(iou(mask, truth))
                got[rule]["filled"].append(float(mask.mean() >= NEAR_FILLED))
    return got


def report(got: dict[str, dict[str, list[float]]], prefix: str) -> None:
    print(f"{prefix}cutouts: {len(got[MASK_RULES[0]]['iou'])} boxes")
    for rule, m in got.items():
        print(f"{prefix}{rule}_iou_mean: {np.mean(m['iou']):.3f} IoU")
        print(f"{prefix}{rule}_iou_std: {np.std(m['iou']):.3f} IoU")
        print(f"{prefix}{rule}_near_filled: {100 * np.mean(m['filled']):.1f} % of cut-outs")
        print(f"{prefix}{rule}_time: {1000 * np.mean(m['seconds']):.2f} ms per cut-out")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pool", type=Path, help="a Method 2 pool with masks/ (instead of generating one)")
    ap.add_argument("--environments", type=Path, nargs="+", help="places to generate a pool on (panoramas, meshes)")
    ap.add_argument("--n", type=int, default=100, help="images of the generated pool")
    ap.add_argument("--seed", type=int, default=0, help="seed of the generated pool")
    ap.add_argument("--loose", type=float, default=0.1, help="widening of each box side for the loose run, 0..1")
    args = ap.parse_args()
    if (args.pool is None) == (args.environments is None):
        ap.error("give --pool or --environments")
    with tempfile.TemporaryDirectory() as tmp:
        pool = args.pool or make_pool(args.environments, args.n, args.seed, Path(tmp) / "pool")
        report(measure(pool, 0.0), "tight_")
        report(measure(pool, args.loose), "loose_")


if __name__ == "__main__":
    main()

"""What "on which fires" costs beside scoring: the test images' attributes, the image hits, and the per-slice
paired bootstrap.

- ``slices_attributes_share``: computing every attribute of every test image (:func:`eval.attributes.
  dataset_attributes`, decode at 256 px, 2 threads) as a share of scoring the same images end to end at 320 px
  (``fuzzyfire score`` as a study scores: conf 0.001, decode, letterbox, onnxruntime, NMS, pycocotools), on
  ../shared/data/fire-smoke-608 (979 images) or 100 generated 640x480 JPEGs (target <= 0.10).
- ``slices_image_hits``: :func:`eval.imagelevel.image_hits` of one scored set, and the matches at IoU 0.25.
- ``slices_bootstrap``: :func:`eval.slices.compare_slices` of 3 runs against 3 at 1,000 resamples over every slice.

.venv/bin/python bench/bench_slices.py
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
from bench_score import SIZE, _dataset

from eval.attributes import dataset_attributes
from eval.config import InferenceConfig
from eval.imagelevel import image_hits
from eval.onnx_model import OnnxDetector
from eval.score import score, scored_images
from eval.slices import Side, compare_slices, make_slices
from eval.stats import MatchTable
from ground.detect.cocoeval import LOOSE_IOU, run_cocoeval


def main() -> None:
    import torch

    from train.export import export_onnx
    from train.model import Detector

    with tempfile.TemporaryDirectory() as tmp:
        torch.manual_seed(0)
        det = OnnxDetector(export_onnx(Detector(1).eval(), Path(tmp) / "det.onnx", SIZE, ["fire"]))
        ds, what = _dataset(Path(tmp))
        start = time.perf_counter()
        result = score(det, ds, InferenceConfig(batch=16))
        scoring = time.perf_counter() - start
        start = time.perf_counter()
        attrs = dataset_attributes(ds, workers=2)
        attributes = time.perf_counter() - start
        print(f"slices_attributes: {len(ds.images) / attributes:.0f} img/s ({what})")
        print(f"slices_scoring: {len(ds.images) / scoring:.0f} img/s (same images, {SIZE} px, conf 0.001)")
        print(f"slices_attributes_share: {attributes / scoring:.3f} of the scoring time (target <= 0.10)")
        scored, cat_ids = scored_images(result)
        start = time.perf_counter()
        hits = image_hits(scored, result.records, cat_ids)
        loose = MatchTable(run_cocoeval(scored, result.records, cat_ids, [LOOSE_IOU]))
        derive = time.perf_counter() - start
        print(f"slices_image_hits: {derive:.2f} s (image hits + matches at IoU 0.25, {len(result.records)} detections)")
        slices = make_slices(attrs, hits.image_ids, hits.fire)
        tables = MatchTable(result.evaluation)
        side = Side([tables] * 3, [loose] * 3, [(hits, 0.25)] * 3)
        start = time.perf_counter()
        rows = compare_slices(side, side, slices, np.random.default_rng(0), 1000)
        boot = time.perf_counter() - start
        compared = len({r["slice"] for r in rows})
        print(f"slices_bootstrap: {boot:.1f} s ({compared} slices x 3 metrics, 3 runs a side, 1,000 resamples)")


if __name__ == "__main__":
    main()

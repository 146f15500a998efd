"""Scoring speed at 320 px on CPU, and bootstrap speed.

- ``score_*``: ``fuzzyfire score`` end to end (decode + letterbox in threads, onnxruntime, NMS, COCO metrics)
  on ../shared/data/fire-smoke-608 (all 979 images, 608x608 JPEGs) or on generated 640x480 JPEGs, with our detector
  (random weights: its many low-confidence boxes make NMS the worst case) exported by ``train/export.py``.
- ``score_end_to_end`` / ``score_onnx_forward_alone`` / ``score_ratio_to_forward``: the same scoring against
  onnxruntime's forward pass alone over the same letterboxed batches with the same session (target ratio >= 0.8).
- ``onnx_vs_torch``: the same model's forward pass, onnxruntime vs torch eager, batch 16 (target >= 4x).
- ``bootstrap_*``: image-level bootstrap resamples of AP on 1,000 images (target: 1,000 in seconds), with about
  6,000 detections, and with about 100,000 (``bootstrap_100k_*``: up to 200 low-confidence boxes per image,
  as a detector scored at conf 0.001 leaves on a test set like fire-smoke-608, where a study bootstraps every
  comparison).

.venv/bin/python bench/bench_score.py
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from eval.config import InferenceConfig
from eval.onnx_model import OnnxDetector
from eval.score import score
from eval.stats import MatchTable, bootstrap_ap
from ground.data.dataset import DatasetBuilder
from ground.data.formats.registry import read_dataset
from ground.detect.cocoeval import run_cocoeval
from ground.detect.detections import PostprocessConfig
from ground.detect.letterbox import letterbox_image, to_nchw_float
from ground.image.imageio import read_image

SIZE = 320
SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "fire-smoke-608"


def _dataset(tmp: Path):
    if SHARED.is_dir():
        return read_dataset(SHARED).dataset, "fire-smoke-608, all 979 images"
    import cv2

    rng = np.random.default_rng(0)
    builder = DatasetBuilder(tmp, ["fire"])
    for i in range(100):
        pixels = cv2.GaussianBlur(rng.integers(0, 256, (480, 640, 3), dtype=np.uint8), (0, 0), 3)
        cv2.imwrite(str(tmp / f"{i}.jpg"), pixels)
        builder.add_box(builder.add_image(f"{i}.jpg", 640, 480), "fire", (100, 100, 200, 150))
    return builder.build(), "100 generated 640x480 JPEGs"


def bench_scoring(tmp: Path) -> None:
    import torch

    from train.export import export_onnx
    from train.model import Detector

    torch.manual_seed(0)
    model = Detector(1).eval()
    path = export_onnx(model, tmp / "det.onnx", SIZE, ["fire"])
    det = OnnxDetector(path)
    ds, what = _dataset(tmp)
    score(det, ds.filter_images(lambda img: img.id <= ds.images[8].id))  # warm-up
    batches = _input_batches(det, ds, 16)
    # Interleaved, best of two each: the forward pass alone over the same images (same batches, same session and
    # threads), then `score` end to end; the ratio of the two is one run's.
    forward_s, end_to_end_s = [], []
    for _ in range(2):
        forward_s.append(_forward_alone(det, batches))
        start = time.perf_counter()
        result = score(det, ds, InferenceConfig(batch=16))
        end_to_end_s.append(time.perf_counter() - start)
    images = result.metrics.images
    end_to_end, forward = images / min(end_to_end_s), images / min(forward_s)
    per_image = result.metrics.detections / images
    print(f"score_throughput: {end_to_end:.0f} img/s ({what}, {SIZE} px, target >= 100)")
    print(f"score_detections: {per_image:.0f} per image after NMS (an untrained model: NMS's worst case)")
    print(f"score_end_to_end: {end_to_end:.1f} img/s (decode, onnxruntime, NMS, COCO metrics; batch 16)")
    print(f"score_onnx_forward_alone: {forward:.1f} img/s (same model, images, batches and threads)")
    print(f"score_ratio_to_forward: {end_to_end / forward:.2f} (target >= 0.8)")
    start = time.perf_counter()
    sparse = score(det, ds, InferenceConfig(PostprocessConfig(conf=0.25), batch=16))
    elapsed = time.perf_counter() - start
    print(f"score_throughput_conf0.25: {sparse.metrics.images / elapsed:.0f} img/s (same, few boxes: decode+onnx+COCO)")
    x = np.random.default_rng(0).random((16, 3, SIZE, SIZE), dtype=np.float32)
    onnx_s = _best_of(lambda: det.raw(x))
    with torch.inference_mode():
        xt = torch.from_numpy(x)
        torch_s = _best_of(lambda: model.predict(xt))
    print(f"onnx_forward: {16 / onnx_s:.0f} img/s (batch 16, {SIZE} px)")
    print(f"torch_forward: {16 / torch_s:.0f} img/s (eager, same model)")
    print(f"onnx_vs_torch: {torch_s / onnx_s:.1f} x (target >= 4)")


def _input_batches(det: OnnxDetector, ds, size: int) -> list[list[np.ndarray]]:
    """The letterboxed uint8 images ``score`` feeds the model, in its batches (converted to float when run)."""
    spec = det.spec
    boxed = [
        letterbox_image(read_image(ds.image_path(img)), spec.input_width, spec.input_height, spec.pad_value)
        for img in ds.images
    ]
    return [boxed[i : i + size] for i in range(0, len(boxed), size)]


def _forward_alone(det: OnnxDetector, batches: list[list[np.ndarray]]) -> float:
    """Seconds onnxruntime takes over every batch (the float conversion outside the clock)."""
    total = 0.0
    for images in batches:
        x = to_nchw_float(images)
        start = time.perf_counter()
        det.raw(x)
        total += time.perf_counter() - start
    return total


def _best_of(fn, repeats: int = 5) -> float:
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def bench_bootstrap(tmp: Path, clutter: int = 0, name: str = "bootstrap") -> None:
    """Bootstrap speed on 1,000 random images; ``clutter``: up to that many extra low-score boxes per image."""
    rng = np.random.default_rng(0)
    builder = DatasetBuilder(tmp, ["fire", "smoke"])
    records = []
    for _ in range(1000):
        image_id = builder.add_image("x.jpg", 640, 480)
        for _ in range(rng.integers(0, 4)):
            xy, wh, cls = rng.uniform(0, 400, 2), rng.uniform(10, 200, 2), ("fire", "smoke")[rng.integers(0, 2)]
            builder.add_box(image_id, cls, (*xy, *wh))
            for _ in range(3):
                box = [*(xy + rng.normal(0, 10, 2)), *(wh * rng.uniform(0.7, 1.3, 2))]
                records.append(
                    {"image_id": image_id, "category_id": 1 + (cls == "smoke"), "bbox": box, "score": rng.random()}
                )
        for _ in range(rng.integers(0, clutter + 1)):
            box = [*rng.uniform(0, 560, 2), *rng.uniform(8, 80, 2)]
            records.append(
                {"image_id": image_id, "category_id": int(rng.integers(1, 3)), "bbox": box, "score": 0.1 * rng.random()}
            )
    start = time.perf_counter()
    table = MatchTable(run_cocoeval(builder.build(), records, [1, 2]))
    setup = time.perf_counter() - start
    start = time.perf_counter()
    bootstrap_ap(table, np.random.default_rng(0), num_samples=1000)
    elapsed = time.perf_counter() - start
    print(f"{name}_setup: {setup:.2f} s (one COCOeval.evaluate, 1000 images, {len(records)} detections)")
    print(f"{name}_resamples: {1000 / elapsed:.0f} resamples/s ({elapsed:.2f} s for 1000)")


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        try:
            bench_scoring(Path(tmp))
        except ImportError as exc:  # the train package builds the benchmark model
            print(f"score_skipped: {exc}", file=sys.stderr)
        bench_bootstrap(Path(tmp))
        bench_bootstrap(Path(tmp), clutter=200, name="bootstrap_100k")
    return 0


if __name__ == "__main__":
    sys.exit(main())

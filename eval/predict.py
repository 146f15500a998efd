"""Batched inference over a dataset: decode + letterbox in a thread pool, onnxruntime, NMS, boxes mapped
back to original image pixels."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from functools import partial

import numpy as np
from numpy.typing import NDArray

from eval.config import InferenceConfig
from eval.onnx_model import OnnxDetector
from ground.data.dataset import Dataset, ImageRecord
from ground.data.problems import Problem
from ground.detect.detections import ImageDetections, Predictions, postprocess, to_original
from ground.detect.letterbox import letterbox_image, to_chw_float, to_nchw_float
from ground.image.imageio import ImageError, read_image
from ground.run.progress import progress

Loaded = tuple[int, int] | ImageError  # an image's decoded (width, height), or why it could not be read


def _loader(width: int, height: int, pad: int, resize: str) -> Callable[[str, NDArray[np.float32], int], Loaded]:
    """``load(path, batch, slot)``: decode, letterbox and write the image into ``batch[slot]`` (3, H, W)
    (:func:`ground.detect.letterbox.to_chw_float`), in the decoding thread."""

    def load(path: str, batch: NDArray[np.float32], slot: int) -> Loaded:
        try:
            image = read_image(path)
        except ImageError as exc:
            return exc
        to_chw_float(letterbox_image(image, width, height, pad, resize), batch[slot])
        return image.shape[1], image.shape[0]

    return load


def _prefetched(
    paths: Sequence[str], size: int, shape: tuple[int, int], pool: ThreadPoolExecutor, load: Callable
) -> Iterator[tuple[NDArray[np.float32], list[Loaded]]]:
    """Batches in order: a (B, 3, H, W) float32 input (``shape`` = (H, W)) the decoding threads filled and each
    image's :data:`Loaded`; the next two batches decode while the caller runs the current one."""
    chunks = [paths[i : i + size] for i in range(0, len(paths), size)]

    def submit(chunk: Sequence[str]) -> tuple[NDArray[np.float32], list[Future]]:
        batch = np.empty((len(chunk), 3, *shape), dtype=np.float32)
        return batch, [pool.submit(load, p, batch, j) for j, p in enumerate(chunk)]

    pending = deque(submit(chunk) for chunk in chunks[:2])
    for nxt in range(2, len(chunks) + 2):
        batch, futures = pending.popleft()
        if nxt < len(chunks):
            pending.append(submit(chunks[nxt]))
        yield batch, [f.result() for f in futures]


def _postprocess_one(
    boxes: NDArray, scores: NDArray, size: tuple[int, int], opt: InferenceConfig, input_size: tuple[int, int]
) -> ImageDetections:
    return to_original(postprocess(boxes, scores, opt.postprocess), size, input_size)


def predict_dataset(detector: OnnxDetector, dataset: Dataset, options: InferenceConfig | None = None) -> Predictions:
    """Run ``detector`` on every image of ``dataset`` with the letterbox, batching and post-processing of
    ``options`` (default: :class:`eval.config.InferenceConfig`'s). Unreadable images are skipped and reported;
    an image whose decoded size differs from its record is scored and reported as a warning."""
    opt = options or InferenceConfig()
    spec = detector.spec
    input_size = (spec.input_width, spec.input_height)
    images: list[ImageRecord] = list(dataset.images)
    paths = [str(dataset.image_path(img)) for img in images]
    out = Predictions(spec.class_names, {}, [])
    load = _loader(spec.input_width, spec.input_height, spec.pad_value, opt.resize)
    done = 0
    pending: list[tuple[int, Future]] = []
    post = partial(_postprocess_one, opt=opt, input_size=input_size)
    with ThreadPoolExecutor(max_workers=max(1, opt.workers)) as pool:
        batches = _prefetched(paths, max(1, opt.batch), (spec.input_height, spec.input_width), pool, load)
        for batch, loaded in progress(batches, total=-(-len(paths) // max(1, opt.batch)), desc="scoring", unit="batch"):
            records = images[done : done + len(loaded)]
            done += len(loaded)
            good = [j for j, item in enumerate(loaded) if not isinstance(item, ImageError)]
            for rec, item in zip(records, loaded):
                if isinstance(item, ImageError):
                    out.problems.append(Problem(item.path, f"skipped: {item.reason}"))
                elif item != (rec.width, rec.height):
                    msg = f"decoded size {item[0]}x{item[1]} differs from the dataset's {rec.width}x{rec.height}"
                    out.problems.append(Problem(str(dataset.image_path(rec)), msg, "warning"))
            if not good:
                continue
            boxes, scores = detector(batch if len(good) == len(loaded) else batch[good])
            # NMS in the pool too (OpenCV releases the GIL), collected at the end: the next batch runs meanwhile.
            pending += [(records[j].id, pool.submit(post, b, s, loaded[j])) for j, b, s in zip(good, boxes, scores)]
        for image_id, future in pending:
            out.by_image[image_id] = future.result()
    return out


def detect_images(
    detector: OnnxDetector, images: Sequence[NDArray[np.uint8]], options: InferenceConfig | None = None
) -> list[ImageDetections]:
    """Detections of decoded (H, W, 3) uint8 RGB ``images`` (e.g. video frames), one :class:`ImageDetections`
    per image with xyxy boxes in that image's pixels: the letterbox and post-processing of
    :func:`predict_dataset`, run in one onnxruntime call per ``options.batch`` images."""
    opt = options or InferenceConfig()
    spec = detector.spec
    input_size = (spec.input_width, spec.input_height)
    found: list[ImageDetections] = []
    for start in range(0, len(images), max(1, opt.batch)):
        chunk = images[start : start + max(1, opt.batch)]
        boxed = [letterbox_image(img, spec.input_width, spec.input_height, spec.pad_value, opt.resize) for img in chunk]
        boxes, scores = detector(to_nchw_float(boxed))
        sizes = [(img.shape[1], img.shape[0]) for img in chunk]
        found += [_postprocess_one(b, s, size, opt, input_size) for b, s, size in zip(boxes, scores, sizes)]
    return found

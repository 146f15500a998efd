"""A detector on a user's pictures, ``fuzzyfire predict``'s work: a folder of images (read recursively), one
image, or a video, each drawn with its detections into an output folder, plus the detections as JSON.

Images go through :func:`eval.predict.predict_dataset` (so the same letterbox, onnxruntime batching, NMS and
mapping back to original pixels as ``fuzzyfire score``) as a dataset without boxes; their sizes are read from the
headers first, and a file :mod:`ground.image.imageio` cannot read is named with its reason and skipped. Video
frames go through :func:`eval.predict.detect_images`, the same post-processing on decoded frames.

``detections.json`` is a list of COCO-style results, one per detection, best first within an image:
``{"file_name": path relative to the source folder (a video's name), "frame": index from 0 (videos only),
"category": class name, "bbox": [x, y, w, h] pixels of the original image, "score": 0..1}``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from eval.config import InferenceConfig
from eval.draw import draw_detections
from eval.onnx_model import OnnxDetector
from eval.predict import detect_images, predict_dataset
from eval.video import VideoWriter, is_video_file, read_batches, video_info
from ground.data.dataset import Dataset, DatasetBuilder
from ground.data.problems import Problem
from ground.data.walk import walk_files
from ground.detect.cocoeval import ClassMatch, detection_records
from ground.detect.detections import ImageDetections, Predictions
from ground.image.imageio import ImageError, image_size, is_image_file, read_image
from ground.run.progress import progress

DETECTIONS_FILE = "detections.json"
#: Suffixes a drawn image keeps; any other image is written as ``<name>.png`` (e.g. ``a.gif.png``).
KEPT_SUFFIXES = frozenset({".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp"})
JPEG_QUALITY = 95


class SourceError(ValueError):
    """A source that is neither an image, a folder nor a video."""


@dataclass
class MediaPredictions:
    """What a run produced: the ``records`` of ``detections.json`` (module docstring), the unreadable inputs,
    how many images or frames were run, and the drawn files written (images, or the one video)."""

    records: list[dict[str, Any]]
    problems: list[Problem] = field(default_factory=list)
    inputs: int = 0
    written: list[Path] = field(default_factory=list)


def source_kind(source: Path) -> str:
    """``"video"`` for a video file (:data:`eval.video.VIDEO_SUFFIXES`), ``"images"`` for an image file or a
    folder; raises :class:`SourceError` for anything else."""
    if source.is_dir():
        return "images"
    if not source.is_file():
        raise SourceError(f"{source}: no such file or folder")
    if is_video_file(source):
        return "video"
    if is_image_file(source):
        return "images"
    raise SourceError(f"{source}: neither an image, a folder of images nor a video (by its suffix)")


def image_files(source: Path, exclude: Path | None = None) -> list[Path]:
    """``source`` itself when it is a file, else the image files below it (:func:`ground.data.walk.walk_files`:
    links followed, hidden entries skipped, sorted), leaving out those inside ``exclude``."""
    if source.is_file():
        return [source]
    skip = exclude.resolve() if exclude is not None else None
    found = walk_files(source, is_image_file)
    return [p for p in found if skip is None or not p.resolve().is_relative_to(skip)]


def images_dataset(source: Path, paths: Sequence[Path], class_names: Sequence[str], problems: list[Problem]) -> Dataset:
    """A dataset without boxes of the readable ``paths`` (names relative to ``source``'s folder), sizes from
    the image headers; each unreadable file is appended to ``problems`` as ``skipped: <reason>``."""
    root = source if source.is_dir() else source.parent
    builder = DatasetBuilder(root, class_names)
    for path in progress(paths, desc="reading headers"):
        try:
            width, height = image_size(path)
        except ImageError as exc:
            problems.append(Problem(str(path), f"skipped: {exc.reason}"))
            continue
        builder.add_image(path.relative_to(root).as_posix(), width, height)
    return builder.build()


def keep_classes(det: ImageDetections, labels: frozenset[int] | None) -> ImageDetections:
    """``det`` restricted to the class indices ``labels`` (all of them when None)."""
    if labels is None:
        return det
    keep = np.isin(det.labels, sorted(labels))
    return ImageDetections(det.boxes[keep], det.scores[keep], det.labels[keep])


def to_records(preds: Predictions, names: dict[int, tuple[str, int | None]]) -> list[dict[str, Any]]:
    """``detections.json`` records of ``preds``, rounded as ``score``'s ``predictions.json``
    (:func:`ground.detect.cocoeval.detection_records`); ``names``: image id -> (file name, frame or None)."""
    classes = preds.class_names
    match = ClassMatch({i: i + 1 for i in range(len(classes))}, tuple(classes), (), ())
    out = []
    for rec in detection_records(preds, match):
        file_name, frame = names[rec["image_id"]]
        where = {"file_name": file_name} if frame is None else {"file_name": file_name, "frame": frame}
        out.append({**where, "category": classes[rec["category_id"] - 1], "bbox": rec["bbox"], "score": rec["score"]})
    return out


def drawn_path(out: Path, file_name: str) -> Path:
    """Where the drawn copy of image ``file_name`` (relative) goes in ``out``: same relative path, same suffix
    when :data:`KEPT_SUFFIXES` has it, else ``.png`` appended."""
    dst = out / file_name
    return dst if dst.suffix.lower() in KEPT_SUFFIXES else dst.with_name(dst.name + ".png")


def write_image(path: Path, rgb: NDArray[np.uint8]) -> None:
    """Encode (H, W, 3) uint8 RGB by ``path``'s suffix (JPEG at :data:`JPEG_QUALITY`) and write it, folders
    created; OSError when OpenCV cannot encode it."""
    params = [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY] if path.suffix.lower() in (".jpg", ".jpeg") else []
    ok, buf = cv2.imencode(path.suffix.lower(), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), params)
    if not ok:
        raise OSError(f"{path}: OpenCV cannot encode this image format")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(buf.tobytes())


def _draw_images(ds: Dataset, preds: Predictions, out: Path, workers: int) -> tuple[list[Path], list[Problem]]:
    """Each predicted image of ``ds`` drawn with its detections into ``out``; (files written, problems)."""

    def one(image_id: int) -> Path | Problem:
        img = ds_images[image_id]
        try:
            pixels = read_image(ds.image_path(img))
        except ImageError as exc:
            return Problem(exc.path, f"not drawn: {exc.reason}")
        det = preds.by_image[image_id]
        dst = drawn_path(out, img.file_name)
        write_image(dst, draw_detections(pixels, det.boxes, det.scores, det.labels, preds.class_names))
        return dst

    ds_images = {img.id: img for img in ds.images}
    ids = sorted(preds.by_image)
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        done = list(progress(pool.map(one, ids), total=len(ids), desc="drawing"))
    return [d for d in done if isinstance(d, Path)], [d for d in done if isinstance(d, Problem)]


def predict_images(
    detector: OnnxDetector, source: Path, out: Path, options: InferenceConfig, labels: frozenset[int] | None = None
) -> MediaPredictions:
    """Run ``detector`` on the image ``source`` or every image below the folder ``source`` (``out`` excluded)
    and draw each into ``out`` at its relative path; detections of class indices ``labels`` only (None: all)."""
    problems: list[Problem] = []
    paths = image_files(source, out)
    if not paths:
        raise SourceError(f"{source}: no image files in it (by their suffixes)")
    ds = images_dataset(source, paths, detector.spec.class_names, problems)
    preds = predict_dataset(detector, ds, options) if ds.images else Predictions(detector.spec.class_names, {})
    problems += preds.problems
    preds.by_image = {k: keep_classes(v, labels) for k, v in preds.by_image.items()}
    written, failed = _draw_images(ds, preds, out, options.workers)
    names: dict[int, tuple[str, int | None]] = {img.id: (img.file_name, None) for img in ds.images}
    return MediaPredictions(to_records(preds, names), problems + failed, len(preds.by_image), written)


def predict_video(
    detector: OnnxDetector, source: Path, out: Path, options: InferenceConfig, labels: frozenset[int] | None = None
) -> MediaPredictions:
    """Run ``detector`` on every frame of the video ``source`` and write them drawn as ``out/<stem>.mp4`` (mp4v,
    the source's frame rate, its first frame's size); detections of class indices ``labels`` only (None: all).
    Raises :class:`eval.video.VideoError` when the video cannot be read (nothing is written then)."""
    info = video_info(source)
    names = detector.spec.class_names
    dst = out / f"{source.stem}.mp4"
    result = MediaPredictions([], written=[dst])
    writer: VideoWriter | None = None
    batches = read_batches(source, max(1, options.batch))
    total = -(-info.frames // max(1, options.batch)) if info.frames else None
    try:
        for frames in progress(batches, total=total, desc="frames", unit="batch", min_items=1):
            writer = writer or VideoWriter(dst, info.fps, frames[0].shape[1], frames[0].shape[0])
            found = [keep_classes(d, labels) for d in detect_images(detector, frames, options)]
            ids = range(result.inputs + 1, result.inputs + 1 + len(frames))
            result.records += to_records(
                Predictions(names, dict(zip(ids, found))), {i: (source.name, i - 1) for i in ids}
            )
            for pixels, det in zip(frames, found):
                writer.write(draw_detections(pixels, det.boxes, det.scores, det.labels, names))
            result.inputs += len(frames)
    finally:
        if writer is not None:
            writer.close()
    return result


def write_records(records: Sequence[dict[str, Any]], out: Path) -> Path:
    """Write ``records`` as ``out/detections.json`` (:data:`DETECTIONS_FILE`); returns its path."""
    path = out / DETECTIONS_FILE
    path.write_text(json.dumps(list(records)) + "\n", encoding="utf-8")
    return path

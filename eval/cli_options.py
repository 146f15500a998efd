"""Options of the commands that run a detector ONNX (``score``, ``compare``, ``predict``): the model's layout,
classes and input size, the letterbox and post-processing, batching and device, and the detector they build."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the parser is built without importing OpenCV or onnxruntime
    from eval.onnx_model import OnnxDetector
    from eval.predict import PredictOptions


def parse_names(text: str) -> list[str]:
    """``"fire, smoke"`` -> ``["fire", "smoke"]``."""
    return [n.strip() for n in text.split(",") if n.strip()]


def parse_size(text: str) -> tuple[int, int]:
    """``"320"`` -> (320, 320), ``"640x480"`` -> (640, 480): (width, height)."""
    w, _, h = text.lower().partition("x")
    try:
        return int(w), int(h or w)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected N or WxH, e.g. 320 or 640x480") from None


def parse_device(text: str) -> str:
    """``auto | cpu | cuda | cuda:N``, checked by :func:`curate.core.device.parse_device`."""
    from curate.core.device import DeviceError, parse_device

    try:
        parse_device(text)
    except DeviceError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def add_model_args(p: argparse.ArgumentParser, conf: float = 0.001) -> None:
    """The model and post-processing options; ``conf`` is the default confidence threshold (0.001 for COCO
    scoring, which keeps low scores for recall; higher where boxes are drawn)."""
    p.add_argument(
        "--format", default="auto", choices=("auto", "fuzzyfire", "yolov5", "yolov8"), help="model output layout"
    )
    p.add_argument(
        "--names", type=parse_names, help="model class names in output order, e.g. fire,smoke (default: metadata)"
    )
    p.add_argument("--imgsz", type=parse_size, help="input size N or WxH for models with a dynamic input size")
    p.add_argument(
        "--resize",
        default="area",
        choices=("area", "linear"),
        help="letterbox resize: area when shrinking (default; ours and YOLOv5's) or always bilinear "
        "(ultralytics 8.x's: use it to reproduce ultralytics' own numbers)",
    )
    p.add_argument("--conf", type=float, default=conf, help=f"confidence threshold (default {conf:g})")
    p.add_argument("--iou", type=float, default=0.6, help="NMS IoU threshold (default 0.6)")
    p.add_argument("--max-det", type=int, default=300, help="detections kept per image (default 300)")
    p.add_argument("--batch", type=int, default=16, help="images per onnxruntime call (default 16)")
    p.add_argument("--workers", type=int, default=2, help="image decoding threads (default 2)")
    p.add_argument("--threads", type=int, default=0, help="onnxruntime threads (default 0 = all cores)")
    p.add_argument(
        "--device",
        default="auto",
        type=parse_device,
        help="auto | cpu | cuda | cuda:N (default auto: onnxruntime's CUDA provider when installed, else the CPU)",
    )


def build_detector(model: Path, args: argparse.Namespace) -> tuple[OnnxDetector, PredictOptions]:
    """The detector and post-processing the options of :func:`add_model_args` describe (the device notice, if
    any, on stderr); raises :class:`eval.onnx_model.ModelError` for a model that cannot be run."""
    from dataclasses import fields

    from eval.score import ScoreConfig

    cfg = ScoreConfig(**{f.name: getattr(args, f.name) for f in fields(ScoreConfig)})
    detector = cfg.detector(model, args.format, args.names, args.imgsz)
    if detector.device_notice:
        print(detector.device_notice, file=sys.stderr)
    return detector, cfg.predict_options(args.resize)

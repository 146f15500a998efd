"""``fuzzyfire predict``: a detector's boxes drawn on images or on a video's frames, and its detections as JSON
(:mod:`eval.predict_media`). ``cmd_predict`` returns an exit code."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from eval.cli.options import MODEL_ALIASES, open_detector, parse_names
from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings, command_config

#: Flags of ``fuzzyfire predict``: aliases of :class:`eval.config.PredictConfig` keys (their defaults are the keys').
ALIASES: tuple[Alias, ...] = (
    *MODEL_ALIASES,
    Alias("--classes", ("classes",), "only these model classes, e.g. fire (null: every class)", {"type": parse_names}),
)


def _predict_config() -> type:
    from eval.config import PredictConfig

    return PredictConfig


_DESCRIPTION = """Run a detector ONNX (ours, YOLOv5, YOLOv8/11 exports) on images or a video, with the letterbox
and post-processing of `fuzzyfire score`, and draw its boxes with class and score. IMAGES|VIDEO is a folder of
images (read recursively; unreadable files are named and skipped), one image, or a video (OpenCV reads it; the
drawn frames are written as OUT/<name>.mp4, mp4v). OUT also gets detections.json: one COCO-style result per
detection, {"file_name", "frame" (videos), "category", "bbox": [x, y, w, h] pixels of the original image,
"score"}. OUT must be new or empty (--overwrite to write into it anyway). Settings: --config CONFIG.yaml
(docs/config.md#predict), the options below, then --set KEY=VALUE. The confidence threshold (--conf) is higher
than score's: the boxes drawn are those that would raise an alarm.

example:
  fuzzyfire predict runs/R400_S0/best.onnx ../shared/data/fire-cctv-416/valid/images --out out/pred
  fuzzyfire predict best.onnx cctv.mp4 --out out/pred-video --conf 0.4 --classes fire
  fuzzyfire predict yolov8n_fire.onnx photos/ --out out/pred-v8 --format yolov8 --names fire,smoke"""


def check_output(out: Path, source: Path, overwrite: bool) -> str | None:
    """Why ``out`` cannot take the drawn pictures (None when it can): an existing non-empty folder without
    ``overwrite``, a file, or a folder holding ``source`` (its pictures would be overwritten)."""
    if out.exists() and not out.is_dir():
        return f"{out}: exists and is not a folder"
    if source.exists() and source.resolve().is_relative_to(out.resolve()):
        return f"{out}: holds the input {source}; choose an --out outside it"
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        return f"{out}: folder is not empty; choose a new --out or pass --overwrite"
    return None


def class_labels(wanted: Sequence[str] | None, names: Sequence[str]) -> frozenset[int] | None:
    """Model class indices of the ``--classes`` names (case-insensitive; None when not given); ValueError
    naming the model's classes for a name it does not have."""
    if not wanted:
        return None
    lower = [n.lower() for n in names]
    unknown = [w for w in wanted if w.lower() not in lower]
    if unknown:
        raise ValueError(f"--classes {','.join(unknown)}: the model's classes are {', '.join(names)}")
    return frozenset(lower.index(w.lower()) for w in wanted)


def cmd_predict(args: argparse.Namespace) -> int:
    from eval.onnx_model import ModelError
    from eval.predict_media import SourceError, predict_images, predict_video, source_kind, write_records
    from eval.video import VideoError
    from ground.cli.commands import print_problems

    cfg = command_config(args, _predict_config(), ALIASES, {"--out": args.out})
    if cfg is None:
        return 0
    refused = check_output(args.out, args.source, args.overwrite)
    try:
        if refused:
            raise ValueError(refused)
        kind = source_kind(args.source)
        detector = open_detector(args.model, cfg.model, cfg.inference)
        labels = class_labels(cfg.classes, detector.spec.class_names)
        args.out.mkdir(parents=True, exist_ok=True)
        run = predict_video if kind == "video" else predict_images
        result = run(detector, args.source, args.out, cfg.inference, labels)
    except (SourceError, ModelError, VideoError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if result.problems:
        print_problems(result.problems, sys.stderr, limit=20)
    path = write_records(result.records, args.out)
    unit = "frames" if kind == "video" else "images"
    drawn = result.written[0] if kind == "video" else f"{len(result.written)} drawn images"
    conf = cfg.inference.postprocess.conf
    print(f"{result.inputs} {unit}, {len(result.records)} detections >= {conf:g}: {drawn}, {path}")
    return 0 if result.inputs else 1


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``predict`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "predict",
        help="draw a detector ONNX's boxes on images or a video, and write its detections as JSON",
        description=_DESCRIPTION,
    )
    p.add_argument("model", type=Path, metavar="MODEL.onnx", help="detector .onnx file")
    p.add_argument("source", type=Path, metavar="IMAGES|VIDEO", help="image folder (recursive), image, or video")
    p.add_argument("--out", type=Path, help="folder for the drawn pictures and detections.json (required)")
    p.add_argument("--overwrite", action="store_true", help="write into a non-empty --out")
    add_settings(p, _predict_config, ALIASES, cmd_predict, flag="--config")

"""``fuzzyfire score``: COCO metrics of a detector ONNX on a test set. ``cmd_*`` return an exit code."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def _names(text: str) -> list[str]:
    return [n.strip() for n in text.split(",") if n.strip()]


def _size(text: str) -> tuple[int, int]:
    w, _, h = text.lower().partition("x")
    try:
        return int(w), int(h or w)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected N or WxH, e.g. 320 or 640x480") from None


def _fmt(value: float | None) -> str:
    return "  -  " if value is None else f"{value:.3f}"


def _print_text(result, intervals: dict) -> None:  # result: eval.score.ScoreResult
    m, spec = result.metrics, result.spec
    print(
        f"model  {spec.path} ({spec.format}, {spec.input_width}x{spec.input_height}, classes {list(spec.class_names)})"
    )
    print(f"test   {m.images} images ({m.negatives} negatives), {m.boxes} boxes, {m.detections} detections")
    print("       " + "  ".join(f"{k} {_fmt(v)}" for k, v in m.summary.items()))
    for key, iv in intervals.items():
        print(f"       {key[:-3]} 95% CI [{iv['low']:.3f}, {iv['high']:.3f}] ({iv['samples']} image resamples)")
    print(f"       {'class':<12} {'boxes':>6} {'AP':>6} {'AP50':>6}")
    for name, row in m.per_class.items():
        print(f"       {name:<12} {row['boxes']:>6} {_fmt(row['AP']):>6} {_fmt(row['AP50']):>6}")
    skipped = m.extra["classes"]
    if skipped["not_in_model"]:
        print(f"       not scored (the model has no such class): {', '.join(skipped['not_in_model'])}")


def cmd_score(args: argparse.Namespace) -> int:
    from curate.cli import print_problems
    from eval.coco import ClassMatchError
    from eval.onnx_model import ModelError, OnnxDetector
    from eval.predict import PredictOptions
    from eval.score import ScoreError, load_test_set, score, write_outputs

    try:
        detector = OnnxDetector(args.model, args.format, args.names, args.imgsz, threads=args.threads)
        dataset, problems = load_test_set(
            args.data, args.data_format, args.split, _aliases(args.alias), args.drop_class
        )
        options = PredictOptions(args.conf, args.iou, args.max_det, args.batch, args.workers)
        result = score(detector, dataset, options, problems)
    except (ModelError, ScoreError, ClassMatchError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    shown = [p for p in result.problems if p.level != "info"]
    if shown:
        print_problems(shown, sys.stderr, limit=20)
    intervals = _intervals(result, args.ci, args.seed) if args.ci else {}
    if args.out:
        files = write_outputs(result, args.out, intervals)
        print(f"wrote {', '.join(str(p) for p in files.values())}", file=sys.stderr)
    if args.json:
        print(json.dumps({**result.metrics.to_dict(), **intervals}, indent=1))
    else:
        _print_text(result, intervals)
    return 0


def _intervals(result, samples: int, seed: int) -> dict[str, dict[str, float]]:
    """``{"AP_ci": {...}, "AP50_ci": {...}}``: 95% image-level bootstrap intervals."""
    import numpy as np

    from eval.stats import MatchTable, bootstrap_ap

    found = bootstrap_ap(MatchTable(result.evaluation), np.random.default_rng(seed), samples)
    return {f"{key}_ci": {**iv.to_dict(), "samples": samples, "seed": seed} for key, iv in found.items()}


def _aliases(items: list[str]) -> dict[str, str]:
    out = {}
    for item in items:
        name, sep, target = item.partition("=")
        if not sep or not name.strip() or not target.strip():
            raise SystemExit(f"--alias {item!r}: expected NAME=CLASS, e.g. Flame=fire")
        out[name.strip()] = target.strip()
    return out


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``score`` to the ``fuzzyfire`` parser."""
    p = sub.add_parser(
        "score",
        help="COCO AP of a detector ONNX (ours, YOLOv5, YOLOv8/11 exports) on a test set",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Run a detector ONNX with onnxruntime on every image of a test set (letterbox, NMS, boxes in\n"
        "original pixels) and report COCO AP, AP50, AP75, small/medium/large and per class (pycocotools;\n"
        "negative images count). Classes are matched by name between the model's metadata and the test set.\n\n"
        "example:\n  fuzzyfire score runs/R500_S500/seed0/best.onnx --data ../shared/data/fire-smoke-608 --split test\n"
        "  fuzzyfire score yolov8n.onnx --data out/test --format yolov8 --names fire --json --out out/score",
    )
    p.add_argument("model", type=Path, help="detector .onnx file")
    p.add_argument("--data", required=True, help="test set: folder or COCO .json in any format fuzzyfire reads")
    p.add_argument("--split", help="score only this split of the test set (e.g. test); default: every image")
    p.add_argument("--from", dest="data_format", default="auto", help="test-set format (default: detect)")
    p.add_argument(
        "--format", default="auto", choices=("auto", "fuzzyfire", "yolov5", "yolov8"), help="model output layout"
    )
    p.add_argument(
        "--names", type=_names, help="model class names in output order, e.g. fire,smoke (default: metadata)"
    )
    p.add_argument("--imgsz", type=_size, help="input size N or WxH for models with a dynamic input size")
    p.add_argument("--conf", type=float, default=0.001, help="confidence threshold (default 0.001)")
    p.add_argument("--iou", type=float, default=0.6, help="NMS IoU threshold (default 0.6)")
    p.add_argument("--max-det", type=int, default=300, help="detections kept per image (default 300)")
    p.add_argument("--batch", type=int, default=16, help="images per onnxruntime call (default 16)")
    p.add_argument("--workers", type=int, default=2, help="image decoding threads (default 2)")
    p.add_argument("--threads", type=int, default=0, help="onnxruntime threads (default 0 = all cores)")
    p.add_argument(
        "--alias", action="append", default=[], metavar="NAME=CLASS", help="map a test-set class, e.g. Flame=fire"
    )
    p.add_argument("--drop-class", action="append", default=[], metavar="NAME", help="ignore a test-set class")
    p.add_argument(
        "--ci", type=int, default=0, metavar="N", help="95%% bootstrap interval of AP from N image resamples"
    )
    p.add_argument("--seed", type=int, default=0, help="bootstrap seed (default 0)")
    p.add_argument("--json", action="store_true", help='print {"AP", "AP50", "images", "boxes", "per_class", ...}')
    p.add_argument("--out", type=Path, help="also write predictions.json, metrics.json and pr_curve.png here")
    p.set_defaults(func=cmd_score)

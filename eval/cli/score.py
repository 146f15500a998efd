"""``fuzzyfire score``: COCO metrics of a detector ONNX on a test set, with its error breakdown, the boxes it
finds, a bootstrap interval, and an image-labelled set's image recall. ``cmd_score`` returns an exit code."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from eval.cli.options import SCORING_ALIASES, fmt, load_test_set, report_problems, score_model
from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings, command_config

#: Flags of ``fuzzyfire score``: aliases of :class:`eval.config.ScoreConfig` keys (their defaults are the keys').
ALIASES: tuple[Alias, ...] = (
    *SCORING_ALIASES,
    Alias("--ci", ("ci",), "95%% bootstrap interval of AP from N image resamples; 0 = none",
          {"type": int, "metavar": "N"}),
    Alias("--alarm-conf", ("alarm_conf",), "confidence of a false alarm and of a found box for --errors, and of "
          "an image-labelled set's image recall", {"type": float}),
)  # fmt: skip


def _score_config() -> type:
    from eval.config import ScoreConfig

    return ScoreConfig


def _split_label(test, holdout: float = 0.0) -> str:  # test: eval.score.TestSet
    """How the scored split is named in the output: as the dataset names it, and the held-out share if any."""
    from eval.score import ALL_SPLITS

    if test.split != ALL_SPLITS:
        label = f"split {test.split}"
    else:
        label = "all splits" if any(test.splits) else "every image (no splits)"
    return f"{label}, held out at {holdout:g}" if holdout else label


def _print_text(result, intervals: dict, split: str) -> None:  # result: eval.score.ScoreResult
    m, spec = result.metrics, result.spec
    print(
        f"model  {spec.path} ({spec.format}, {spec.input_width}x{spec.input_height}, classes {list(spec.class_names)})"
    )
    if result.dataset.image_labelled:  # no boxes: no AP table, the image recall follows
        print(f"data   {split}: {m.images} images ({m.images - m.negatives} holding a class, {m.negatives} without), "
              f"labelled per image (no boxes), {m.detections} detections")  # fmt: skip
        return
    print(f"data   {split}: {m.images} images ({m.negatives} negatives), {m.boxes} boxes, {m.detections} detections")
    print("       " + "  ".join(f"{k} {fmt(v)}" for k, v in m.summary.items()))
    for key, iv in intervals.items():
        print(f"       {key[:-3]} 95% CI [{iv['low']:.3f}, {iv['high']:.3f}] ({iv['samples']} image resamples)")
    print(f"       {'class':<12} {'boxes':>6} {'AP':>6} {'AP50':>6} {'AP25':>6}")
    for name, row in m.per_class.items():
        print(
            f"       {name:<12} {row['boxes']:>6} {fmt(row['AP']):>6} {fmt(row['AP50']):>6} {fmt(row.get('AP25')):>6}"
        )
    skipped = m.extra["classes"]
    if skipped["not_in_model"]:
        print(f"       not scored (the model has no such class): {', '.join(skipped['not_in_model'])}")


def cmd_score(args: argparse.Namespace) -> int:
    from eval.onnx_model import ModelError
    from eval.score import ScoreError, error_pictures, score_errors, score_found, score_image_level, write_outputs
    from ground.cli.commands import print_problems
    from ground.detect.cocoeval import ClassMatchError

    cfg = command_config(args, _score_config(), ALIASES, {"--data": args.data})
    if cfg is None:
        return 0
    try:
        test = load_test_set(args.data, cfg.data)
        result = score_model(args.model, cfg, test.dataset, test.problems)
    except (ModelError, ScoreError, ClassMatchError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    report_problems(result)
    intervals = _intervals(result, cfg.ci, cfg.seed) if cfg.ci else {}
    held = {"holdout": cfg.data.holdout} if cfg.data.holdout else {}
    errors = score_errors(result, cfg.alarm_conf) if args.errors else None
    found = score_found(result, cfg.alarm_conf) if args.errors else None
    if args.out:
        files = write_outputs(result, args.out, {**intervals, **held})
        if errors is not None and found is not None:
            files["errors"] = errors.write(args.out, {"boxes_found": found.to_dict()})
            files["error_pictures"], not_drawn = error_pictures(result, args.out)
            if not_drawn:
                print_problems(not_drawn, sys.stderr, limit=20)
        print(f"wrote {', '.join(str(p) for p in files.values())}", file=sys.stderr)
    level = score_image_level(result, cfg.alarm_conf) if test.dataset.image_labelled else None
    if args.json:
        extra = {"errors": errors.to_dict(), "boxes_found": found.to_dict()} if errors and found else {}
        extra |= {"image_level": level.to_dict()} if level else {}
        print(json.dumps({**result.metrics.to_dict(), **held, **intervals, **extra}, indent=1))
    else:
        _print_text(result, intervals, _split_label(test, cfg.data.holdout))
        if level is not None:
            _print_image_level(level)
        if errors is not None and found is not None:
            _print_errors(errors)
            _print_found(found)
    return 0


def _print_image_level(level) -> None:  # level: eval.imagelevel.ImageLevel
    """An image-labelled set's result: image recall at the confidence, and at the alarm budget of its own images
    without fire when it has any."""
    found = round(level.recall_at_conf * level.fire_images)
    print(f"image  {found} of {level.fire_images} images holding fire detected at confidence >= {level.conf:g}: "
          f"image recall {level.recall_at_conf:.3f} (no boxes: AP is -)")  # fmt: skip
    if level.free_images:
        print(f"       {round(level.alarm_share_at_conf * level.free_images)} of its {level.free_images} images without "
              f"fire raise an alarm at {level.conf:g}; at most {level.budget:g} false-alarm images per 100 of them "
              f"(threshold {level.budget_threshold:.3f}): image recall {level.budget_recall:.3f}")  # fmt: skip


def _print_errors(errors) -> None:  # errors: eval.errors.ErrorBreakdown
    if errors.ap50 is None:
        print("errors (TIDE): no box to find on these images (AP50 undefined); false alarms only")
    else:
        print("errors (TIDE): AP50 gained when each kind is fixed alone, in points")
        for kind, delta in errors.delta_ap50.items():
            print(f"       {kind:<15} {100 * delta:>5.1f}  ({errors.counts[kind]})")
    if errors.false_alarms_per_100 is not None:
        print(
            f"alarms {errors.false_alarms_per_100:.1f} detections >= {errors.alarm_conf:g} per 100 images without "
            f"fire ({100 * errors.alarm_image_share:.0f}% of the {errors.negatives} such images raise one)"
        )


def _print_found(found) -> None:  # found: eval.found.BoxesFound
    if not found.boxes:
        return
    o = found.outcomes
    poor = o["merged"] + o["split"] + o["too_large"] + o["too_small"]
    print(
        f"boxes  at confidence >= {found.conf:g}: {o['found']} of {found.boxes} found at IoU >= 0.5 "
        f"({100 * o['found'] / found.boxes:.0f}%), {poor} boxed poorly (merged with neighbours {o['merged']}, split "
        f"{o['split']}, too large {o['too_large']}, too small {o['too_small']}), {o['missed']} missed"
    )
    for label, table in (("by size (px)", found.by_size), ("by boxes in image", found.by_crowding)):
        cells = "  ".join(f"{k} {100 * f / n:.0f}% of {n}" for k, (f, n) in table.items() if n)
        print(f"       found {label:<17} {cells}")


def _intervals(result, samples: int, seed: int) -> dict[str, dict[str, float]]:
    """``{"AP_ci": {...}, "AP50_ci": {...}}``: 95% image-level bootstrap intervals."""
    import numpy as np

    from eval.stats import MatchTable, bootstrap_ap

    found = bootstrap_ap(MatchTable(result.evaluation), np.random.default_rng(seed), samples)
    return {f"{key}_ci": {**iv.to_dict(), "samples": samples, "seed": seed} for key, iv in found.items()}


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``score`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "score",
        help="COCO AP of a detector ONNX (ours, YOLOv5, YOLOv8/11 exports) on a test set",
        description="Run a detector ONNX with onnxruntime on every image of a test set (letterbox, NMS, boxes in\n"
        "original pixels) and report COCO AP, AP50, AP75, small/medium/large and per class (pycocotools;\n"
        "negative images count). Classes are matched by name between the model's metadata and the test set.\n"
        "Settings: --config CONFIG.yaml (docs/config.md#score), the options below, then --set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire score runs/R500_S500/seed0/best.onnx --data ../shared/data/fire-smoke-608 --split test\n"
        "  fuzzyfire score yolov8n.onnx --data out/test --format yolov8 --names fire --json --out out/score\n"
        "  fuzzyfire score best.onnx --data ds/data.yaml --split val --resize linear --errors\n"
        "  fuzzyfire score best.onnx --data ds --errors --out out/score   # + out/score/errors/*.png\n"
        "  fuzzyfire score best.onnx --data ../shared/data/fire-free --holdout 0.25 --errors   # false alarms on\n"
        "      the fire-free photos that pools with background_holdout 0.25 never composited on\n"
        "  fuzzyfire score best.onnx --data ds --config score.yaml --set inference.postprocess.iou=0.5",
    )
    p.add_argument("model", type=Path, metavar="MODEL.onnx", help="detector .onnx file")
    p.add_argument("--data", help="test set: folder, COCO .json or data.yaml, in any format fuzzyfire reads (required)")
    p.add_argument(
        "--errors",
        action="store_true",
        help="TIDE-style breakdown: AP50 lost to classification, localisation, both, duplicate, background and "
        "missed errors, false alarms on images without fire, and which boxes are found at --alarm-conf (merged "
        "with neighbours, split, too large or small, missed; by size and by boxes per image: eval/found.py); "
        "with --out, pictures of the worst false alarms and misses in OUT/errors/",
    )
    p.add_argument("--json", action="store_true", help='print {"AP", "AP50", "images", "boxes", "per_class", ...}')
    p.add_argument(
        "--out",
        type=Path,
        help="also write predictions.json, metrics.json, pr_curve.png, matches.npz (with --errors: errors.json "
        "and errors/, pictures of the worst false alarms and misses)",
    )
    add_settings(p, _score_config, ALIASES, cmd_score, flag="--config")

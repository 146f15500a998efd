"""What the commands that run a detector ONNX (``score``, ``compare``, ``predict``) share: their flags, each an
alias of a key of :mod:`eval.config` (the model, how it runs, the test set), the parsers of the flags' values,
and the detector, test set and scores the settings build. Their ``--config CONFIG.yaml`` is an option
(``flag`` of :func:`ground.cli.options.add_settings`), not the positional of other commands: these commands'
positionals are their models and inputs."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from eval.onnx_model import FORMATS
from ground.cli.options import Alias
from ground.data.formats.images import IMAGE_LABELLED, NEGATIVES_ONLY
from ground.data.formats.registry import FORMATS as DATA_FORMATS
from ground.detect.letterbox import RESIZE_MODES

if TYPE_CHECKING:  # the parser is built without importing onnxruntime
    from eval.config import InferenceConfig, OnnxModelConfig, ScoringConfig, TestSetConfig
    from eval.onnx_model import OnnxDetector
    from eval.score import ScoreResult, TestSet
    from ground.data.dataset import Dataset
    from ground.data.problems import Problem


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


def parse_alias(text: str) -> tuple[str, str]:
    """``"Flame=fire"`` -> ``("Flame", "fire")``: a test-set class and the class it is read as."""
    name, sep, target = text.partition("=")
    if not sep or not name.strip() or not target.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: expected NAME=CLASS, e.g. Flame=fire")
    return name.strip(), target.strip()


def _drop_keys(names: list[str]) -> dict[str, Any]:
    from ground.data.names import split_names

    return {"data.drop_class": split_names(names)}


#: The model and how it runs: flags of score, compare and predict.
MODEL_ALIASES: tuple[Alias, ...] = (
    Alias("--format", ("model.format",), "model output layout", {"choices": FORMATS, "metavar": "|".join(FORMATS)}),
    Alias("--names", ("model.names",), "model class names in output order, e.g. fire,smoke (null: the metadata's)",
          {"type": parse_names}),
    Alias("--imgsz", ("model.imgsz",), "input size N or WxH for models with a dynamic input size",
          {"type": parse_size, "metavar": "N|WxH"}),
    Alias("--resize", ("inference.resize",), "letterbox resize: area when shrinking (ours and YOLOv5's) or always "
          "bilinear (ultralytics 8.x's: use it to reproduce ultralytics' own numbers)",
          {"choices": RESIZE_MODES, "metavar": "|".join(RESIZE_MODES)}),
    Alias("--conf", ("inference.postprocess.conf",), "confidence threshold", {"type": float}),
    Alias("--iou", ("inference.postprocess.iou",), "NMS IoU threshold", {"type": float}),
    Alias("--max-det", ("inference.postprocess.max_det",), "detections kept per image", {"type": int}),
    Alias("--batch", ("inference.batch",), "images per onnxruntime call", {"type": int}),
    Alias("--workers", ("inference.workers",), "image decoding threads", {"type": int}),
    Alias("--threads", ("inference.threads",), "onnxruntime threads; 0 = all cores", {"type": int}),
    Alias("--device", ("inference.device",), "auto | cpu | cuda | cuda:N; auto = onnxruntime's CUDA provider when "
          "installed, else the CPU", {}),
)  # fmt: skip

#: How --data is read: flags of score and compare.
DATA_ALIASES: tuple[Alias, ...] = (
    Alias("--split", ("data.split",), "split to score (val and valid are one name); null: test, else val/valid, "
          "else the whole set when it has no splits; all = every image", {"metavar": "NAME"}),
    Alias("--from", ("data.format",), f"test-set format: auto (detect) | {' | '.join(DATA_FORMATS)}",
          {"choices": ("auto", *DATA_FORMATS), "metavar": "FORMAT"}),
    Alias("--alias", ("data.aliases",), "map a test-set class, e.g. Flame=fire (repeatable)",
          {"action": "append", "type": parse_alias, "metavar": "NAME=CLASS"},
          lambda pairs: {"data.aliases": dict(pairs)}),
    Alias("--drop-class", ("data.drop_class",), "ignore a test-set class (repeatable or a,b)",
          {"action": "append", "metavar": "NAME"}, _drop_keys),
    Alias("--label", ("data.label",), "every image of --data (a folder of images without label files) holds CLASS, "
          "e.g. fire: an image-labelled set, judged by image recall (no AP); a classification layout (fire/ and "
          "normal/ sub-folders) is read so without it (null: such a folder is negatives only)", {"metavar": "CLASS"}),
    Alias("--holdout", ("data.holdout",), "score only the images held out by content at this share (0..1), the "
          "photos a Method 2 pool with background_holdout SHARE never composites on (0: every image)",
          {"type": float, "metavar": "SHARE"}),
)  # fmt: skip

#: Flags of score and compare: the keys of :class:`eval.config.ScoringConfig`.
SCORING_ALIASES: tuple[Alias, ...] = (
    *MODEL_ALIASES,
    *DATA_ALIASES,
    Alias("--seed", ("seed",), "seed of the bootstrap's image resamples", {"type": int}),
)


def open_detector(path: Path, model: OnnxModelConfig, inference: InferenceConfig) -> OnnxDetector:
    """The detector ONNX at ``path`` as ``model`` describes it, on ``inference``'s device (the device notice, if
    any, on stderr); raises :class:`eval.onnx_model.ModelError` for a model that cannot be run."""
    detector = inference.detector(path, model)
    if detector.device_notice:
        print(detector.device_notice, file=sys.stderr)
    return detector


def load_test_set(path: Path | str, data: TestSetConfig) -> TestSet:
    """The test set at ``path`` as ``data`` reads it (:func:`eval.score.load_test_set`); says on stderr which
    split is scored when none was named, and what a set without boxes is judged by."""
    from eval.score import ALL_SPLITS
    from eval.score import load_test_set as load

    test = load(path, data)
    for note in (p for p in test.problems if p.code == NEGATIVES_ONLY):
        print(f"{note.path}: {note.reason} (AP has no boxes to find: --errors counts its false alarms; if its "
              "images hold fire: --label fire, or fire/ and normal/ sub-folders)", file=sys.stderr)  # fmt: skip
    for note in (p for p in test.problems if p.code == IMAGE_LABELLED):
        print(f"{note.path}: {note.reason}", file=sys.stderr)
    if data.split is None and test.split != ALL_SPLITS:
        others = [s for s in test.splits if s != test.split]
        print(
            f"scoring split {test.split!r} of {path} ({len(test.dataset.images)} images; other splits: "
            f"{', '.join(others) or 'none'}; --split NAME or --split all to choose)",
            file=sys.stderr,
        )
    return test


def score_model(path: Path, cfg: ScoringConfig, dataset: Dataset, problems: list[Problem]) -> ScoreResult:
    """The model at ``path`` scored on ``dataset`` as ``cfg`` says; a set without classes (negatives only) is
    scored on the model's classes, none of them present (every detection false)."""
    from eval.score import score

    detector = open_detector(path, cfg.model, cfg.inference)
    if not dataset.categories:
        from ground.data.classes import canonical_class

        dataset = dataset.with_categories(list(dict.fromkeys(canonical_class(n) for n in detector.spec.class_names)))
    return score(detector, dataset, cfg.inference, problems)


def report_problems(result: ScoreResult) -> None:
    """The reading and scoring problems of ``result`` worth a word (not info lines), on stderr."""
    from ground.cli.commands import print_problems

    shown = [p for p in result.problems if p.level != "info"]
    if shown:
        print_problems(shown, sys.stderr, limit=20)


def fmt(value: float | None) -> str:
    """A metric as printed: three decimals, or ``-`` where it is undefined."""
    return "  -  " if value is None else f"{value:.3f}"

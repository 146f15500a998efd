"""Score one detector ONNX on one test set: the function behind ``fuzzyfire score``."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, NamedTuple

from pycocotools.cocoeval import COCOeval

from eval.config import InferenceConfig, TestSetConfig
from eval.error_pictures import WORST, write_error_pictures
from eval.errors import ALARM_CONF, ErrorBreakdown, error_breakdown
from eval.found import BoxesFound, boxes_found
from eval.imagelevel import ImageLevel, image_level
from eval.onnx_model import ModelSpec, OnnxDetector
from eval.operating import ALARM_BUDGET, Alarms, FoundScores, alarms_of, found_scores
from eval.plots import plot_pr_curves, pr_curves_from_eval
from eval.predict import predict_dataset
from eval.stats import MatchTable
from ground.data.dataset import Dataset
from ground.data.formats.registry import read_dataset
from ground.data.holdout import held_out_images
from ground.data.load import SplitError, pick_split
from ground.data.problems import Problem
from ground.detect.cocoeval import CocoMetrics, evaluate_detections
from ground.detect.detections import Predictions
from ground.detect.fast_cocoeval import CocoBoxes, boxes_to_records


class ScoreError(ValueError):
    """Nothing could be scored (no readable image, empty split)."""


@dataclass
class ScoreResult:
    """Metrics of one (model, test set) pair, with what produced them: ``detections``, the evaluated detections
    of the matched classes, and ``records``, the same as COCO result records (built on first use)."""

    metrics: CocoMetrics
    evaluation: COCOeval
    detections: CocoBoxes
    predictions: Predictions
    spec: ModelSpec
    dataset: Dataset
    problems: list[Problem]

    @cached_property
    def records(self) -> list[dict[str, Any]]:
        return boxes_to_records(self.detections)


ALL_SPLITS = "all"  # --split all: every image of every split


class TestSet(NamedTuple):
    """A test set as scored: its dataset, the reader's problems, the split scored (:data:`ALL_SPLITS` for
    every image) and every split the source has."""

    dataset: Dataset
    problems: list[Problem]
    split: str
    splits: list[str]


def load_test_set(path: Path | str, settings: TestSetConfig | None = None) -> TestSet:
    """Read any dataset :func:`ground.data.formats.registry.read_dataset` reads (a folder, a COCO .json, a
    ``data.yaml``) as ``settings`` say (default: :class:`eval.config.TestSetConfig`'s): one split of it (``val``
    and ``valid`` are one name; None = :func:`default_split`; :data:`ALL_SPLITS` = every image), with its class
    ``aliases`` (source name -> class) and the boxes of the classes ``drop_class`` removed; with ``holdout`` > 0
    only the images held out by content at that share (:func:`ground.data.holdout.held_out`: the photos a Method 2
    pool with ``background_holdout`` never shows). ``label``: the class every image of a folder without label
    files holds (an image-labelled set)."""
    cfg = settings or TestSetConfig()
    try:
        result = read_dataset(path, cfg.format, aliases=cfg.aliases, label=cfg.label).drop_classes(cfg.drop_class)
    except ValueError as exc:
        if cfg.label is None:
            raise
        raise ScoreError(str(exc)) from None
    ds = result.dataset
    splits = ds.splits
    split = default_split(ds, path) if cfg.split is None else cfg.split
    if split != ALL_SPLITS:
        try:
            ds, split = pick_split(ds, split, path), ds.resolve_split(split) or split
        except SplitError as exc:
            raise ScoreError(f"{exc}; --split all for every image") from None
    if cfg.holdout and ds.images:
        try:
            ds = held_out_images(ds, cfg.holdout, path)
        except ValueError as exc:
            raise ScoreError(str(exc)) from None
    if not ds.images:
        raise ScoreError(f"{path}: no images to score")
    return TestSet(ds, list(result.problems), split, splits)


def default_split(ds: Dataset, where: Path | str = "") -> str:
    """The split scored when none is named: ``test``, else the validation split (``val`` / ``valid``); a
    dataset without splits is scored whole (:data:`ALL_SPLITS`). Training images are never scored silently:
    a dataset with splits but neither of these raises :class:`ScoreError`."""
    if ds.splits == [""]:
        return ALL_SPLITS
    for name in ("test", "val"):
        found = ds.resolve_split(name)
        if found is not None:
            return found
    raise ScoreError(
        f"{where}: no test or validation split (splits: {_shown(ds)}): name one with --split, or --split all"
    )


def _shown(ds: Dataset) -> str:
    return ", ".join(s or "(none)" for s in ds.splits)


def score(
    detector: OnnxDetector, dataset: Dataset, options: InferenceConfig | None = None, problems: Sequence[Problem] = ()
) -> ScoreResult:
    """Run ``detector`` over ``dataset`` (as ``options`` say: :func:`eval.predict.predict_dataset`) and compute
    COCO metrics over every readable image."""
    preds = predict_dataset(detector, dataset, options)
    if not preds.by_image:
        raise ScoreError(f"{dataset.root}: none of the {len(dataset.images)} images could be read")
    metrics, ev, detections = evaluate_detections(dataset, preds)
    return ScoreResult(metrics, ev, detections, preds, detector.spec, dataset, [*problems, *preds.problems])


def scored_images(result: ScoreResult) -> tuple[Dataset, list[int]]:
    """The images (those that could be read) and the category ids ``result`` was scored on."""
    scored = result.dataset.filter_images(lambda img: img.id in result.predictions.by_image)
    return scored, list(result.evaluation.params.catIds)


def score_errors(result: ScoreResult, alarm_conf: float = ALARM_CONF) -> ErrorBreakdown:
    """The error breakdown (:mod:`eval.errors`) of a scored result, over the images and classes it was scored on."""
    scored, cat_ids = scored_images(result)
    return error_breakdown(scored, result.records, cat_ids, alarm_conf)


def score_found(result: ScoreResult, conf: float = ALARM_CONF) -> BoxesFound:
    """Which ground-truth boxes a scored result finds at ``conf`` (:mod:`eval.found`), over the images and
    classes it was scored on."""
    scored, cat_ids = scored_images(result)
    return boxes_found(scored, result.records, cat_ids, conf)


def score_image_level(result: ScoreResult, conf: float = ALARM_CONF, budget: float = ALARM_BUDGET) -> ImageLevel:
    """A scored result read per image (:func:`eval.imagelevel.image_level`): its images holding a scored class
    detected at ``conf``, and at ``budget`` false-alarm images per 100 of its own images without one."""
    scored, cat_ids = scored_images(result)
    return image_level(scored, result.records, cat_ids, conf, budget)


def score_operating(fire: ScoreResult, negatives: ScoreResult) -> tuple[FoundScores, Alarms]:
    """A model's operating data (:mod:`eval.operating`) from its scoring of a set with fire and of a set without:
    the boxes it found and the alarms it raised, over the images (those that could be read) and classes each
    was scored on."""
    scored, cat_ids = scored_images(fire)
    free, _ = scored_images(negatives)
    return found_scores(scored, fire.records, cat_ids), alarms_of(negatives.records, [img.id for img in free.images])


def error_pictures(result: ScoreResult, out: Path, count: int = WORST) -> tuple[Path, list[Problem]]:
    """Pictures of the ``count`` worst false alarms and missed boxes of a scored result in ``out/errors/``
    (:func:`eval.error_pictures.write_error_pictures`); returns the folder and the images not drawn."""
    scored, cat_ids = scored_images(result)
    return write_error_pictures(scored, result.records, cat_ids, out, count)


def write_outputs(result: ScoreResult, out: Path, extra: Mapping[str, Any] | None = None) -> dict[str, Path]:
    """Write ``predictions.json`` (COCO results), ``metrics.json`` (plus ``extra`` keys), ``pr_curve.png``
    and ``matches.npz`` (the per-image matches :class:`eval.stats.MatchTable` bootstraps) into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    files = {
        "predictions": out / "predictions.json",
        "metrics": out / "metrics.json",
        "pr_curve": out / "pr_curve.png",
        "matches": out / "matches.npz",
    }
    files["predictions"].write_text(json.dumps(result.records))
    MatchTable(result.evaluation).save(files["matches"])
    doc = {**result.metrics.to_dict(), **(extra or {}), "model": str(result.spec.path), "format": result.spec.format}
    files["metrics"].write_text(json.dumps(doc, indent=1) + "\n")
    names = [c.name for c in result.dataset.categories if c.id in result.evaluation.params.catIds]
    curves = pr_curves_from_eval(result.evaluation.eval["precision"], names)
    title = f"{result.spec.path.name}: AP50 {result.metrics.summary['AP50'] or 0:.3f}"
    plot_pr_curves(result.evaluation.params.recThrs, curves, files["pr_curve"], title=title + " (IoU 0.5)")
    return files

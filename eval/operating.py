"""A fire alarm's operating curve: the share of fire boxes a detector finds against the false alarms it raises on
images without fire, as its confidence threshold moves - what a user who must pick a threshold asks, and the
comparison of two detectors at the same alarm rate instead of at one fixed confidence (cf. the miss rate against
false positives per image of pedestrian detection: Dollár et al., "Pedestrian Detection: An Evaluation of the
State of the Art", TPAMI 2012).

A fire box is *found* at threshold ``t`` when a detection of its class with score >= ``t`` matches it at IoU >=
0.5 by COCO's matching (pycocotools: detections best first, each box once, at most 100 per image, crowd boxes
ignored), so the recall at the lowest threshold is COCO's recall at IoU 0.5. An *alarm* is any detection with
score >= ``t`` on an image of a set without boxes (:mod:`eval.errors` counts them at ``t`` = 0.25); the alarm
rate is alarms per 100 such images. :func:`operating_point` reads the curve at an alarm budget: the lowest
threshold at which the rate is at most the budget, and the recall there. Scores are those the detector wrote
(the scoring keeps detections from ``score.conf``, 0.001 by default), so a budget above every alarm the
detector raised is met at threshold 0 with every kept detection.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from eval.stats import PairedDelta, class_matches, paired_delta, resample_weights, resampled, seed_picks
from ground.data.dataset import Dataset
from ground.detect.cocoeval import run_cocoeval

ALARM_BUDGET = 10.0  # false alarms per 100 images without fire at which Table 2 reads the recall (issue 23)
RECALL_AT_ALARMS = "recall_at_10_alarms"  # result key of the recall of fire boxes at ALARM_BUDGET (0..1)
FOUND_IOU = 0.5
OPERATING = "operating"  # a study row's (FoundScores, Alarms): its curve and paired comparisons; not written out


@dataclass(frozen=True)
class FoundScores:
    """The fire boxes of a scored set: ``scores`` (F,) float64, best first, of the detections that found a box at
    IoU >= 0.5 (module docstring; one per found box), ``image`` (F,) int64 the index of each one's image and
    ``image_boxes`` (I,) int64 the boxes a detection could find in each image (crowd boxes left out), images in
    the order of their ids."""

    scores: NDArray[np.float64]
    image: NDArray[np.int64]
    image_boxes: NDArray[np.int64]

    @property
    def boxes(self) -> int:
        return int(self.image_boxes.sum())

    def recall(self, threshold: float, weights: NDArray | None = None) -> float:
        """Share (0..1) of the boxes found by detections with score >= ``threshold`` (0 when there is no box);
        ``weights`` (I,): how often each image counts (a bootstrap resample; default once)."""
        if weights is None:
            return float(np.count_nonzero(self.scores >= threshold)) / self.boxes if self.boxes else 0.0
        boxes = float(weights @ self.image_boxes)
        return float(weights[self.image] @ (self.scores >= threshold)) / boxes if boxes else 0.0


@dataclass(frozen=True)
class Alarms:
    """The detections on a set of ``images`` images without fire: ``scores`` (A,) float64 best first and
    ``image`` (A,) int64 the index of each one's image."""

    scores: NDArray[np.float64]
    image: NDArray[np.int64]
    images: int

    def threshold(self, budget: float, weights: NDArray | None = None) -> float:
        """The lowest threshold at which at most ``budget`` alarms per 100 images are raised (``weights`` (N,):
        how often each image counts; default once): ``floor(budget * images / 100)`` are allowed, and when there
        are more the threshold lies just above the first score over the allowance (ties there all left out);
        0 when every alarm is allowed."""
        if self.images < 1:
            raise ValueError("the alarm rate needs at least one image without fire")
        if budget < 0:
            raise ValueError(f"the alarm budget must be >= 0, got {budget}")
        w = np.ones(self.images) if weights is None else np.asarray(weights, dtype=np.float64)
        allowed = np.floor(budget * w.sum() / 100.0 + 1e-9)
        over = np.searchsorted(np.cumsum(w[self.image]), allowed, side="right")
        return 0.0 if over >= len(self.scores) else float(np.nextafter(self.scores[over], np.inf))

    def per_100(self, threshold: float) -> float:
        """Alarms per 100 images at ``threshold`` (scores >= it)."""
        return 100.0 * float(np.count_nonzero(self.scores >= threshold)) / self.images


@dataclass(frozen=True)
class OperatingPoint:
    """A detector read at ``threshold`` (detections with score >= it count): ``alarms_per_100`` images without
    fire, and ``recall`` (0..1) of the fire boxes."""

    threshold: float
    alarms_per_100: float
    recall: float


def found_scores(dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int]) -> FoundScores:
    """The :class:`FoundScores` of COCO result ``records`` ({image_id, category_id, bbox xywh px, score}) on
    ``dataset`` over the categories ``cat_ids``, by pycocotools' matching at IoU 0.5 (module docstring)."""
    ev = run_cocoeval(dataset, records, cat_ids, iou_thresholds=[FOUND_IOU])
    classes = [class_matches(ev, k, ev.params.maxDets[-1]) for k in range(len(ev.params.catIds))]
    scores = np.concatenate([np.zeros(0), *(cm.score[cm.tp[0]] for cm in classes)])  # type: ignore[index]
    image = np.concatenate([np.zeros(0, dtype=np.int64), *(cm.image[cm.tp[0]] for cm in classes)])
    image_boxes = np.sum([cm.npig for cm in classes], axis=0, dtype=np.int64) if classes else np.zeros(0, np.int64)
    return FoundScores(*_best_first(scores, image), image_boxes)


def _best_first(scores: NDArray[np.float64], image: NDArray[np.int64]) -> tuple[NDArray, NDArray]:
    """``scores`` (N,) and their ``image`` indices (N,) sorted by score, best first (ties in their order)."""
    order = np.argsort(-scores, kind="stable")
    return scores[order], image[order]


def alarms_of(records: Sequence[dict[str, Any]], image_ids: Sequence[int]) -> Alarms:
    """The :class:`Alarms` of the detections ``records`` (COCO results) on the images ``image_ids`` without fire
    (their order is the images' index; a record on another image is an error)."""
    index = {int(i): k for k, i in enumerate(image_ids)}
    try:
        image = np.asarray([index[int(r["image_id"])] for r in records], dtype=np.int64)
    except KeyError as exc:
        raise ValueError(f"a detection on image {exc.args[0]}, which is not among the images without fire") from None
    scores = np.asarray([r["score"] for r in records], dtype=np.float64)
    return Alarms(*_best_first(scores, image), len(index))


def pooled(sets: Sequence[Alarms]) -> Alarms:
    """Several sets of images without fire as one (their images one after the other)."""
    if not sets:
        raise ValueError("no set of images without fire to pool")
    offsets = np.cumsum([0, *(a.images for a in sets)])[:-1]
    scores = np.concatenate([a.scores for a in sets])
    image = np.concatenate([a.image + o for a, o in zip(sets, offsets)])
    return Alarms(*_best_first(scores, image), int(sum(a.images for a in sets)))


def operating_point(found: FoundScores, alarms: Alarms, budget: float = ALARM_BUDGET) -> OperatingPoint:
    """The detector at the lowest threshold that raises at most ``budget`` alarms per 100 images without fire
    (:meth:`Alarms.threshold`), with its alarm rate and ``found``'s recall there."""
    threshold = alarms.threshold(budget)
    return OperatingPoint(threshold, alarms.per_100(threshold), found.recall(threshold))


def operating_curve(found: FoundScores, alarms: Alarms) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(alarms per 100 images (P,), recall (P,)) at every threshold where either changes (the scores of both
    sides), from the highest threshold down: both rise monotonically."""
    thresholds = np.unique(np.concatenate([found.scores, alarms.scores]))[::-1]
    rate = 100.0 * np.searchsorted(-alarms.scores, -thresholds, side="right") / alarms.images
    recall = np.searchsorted(-found.scores, -thresholds, side="right") / max(found.boxes, 1)
    return rate.astype(np.float64), recall.astype(np.float64)


def paired_recall_bootstrap(
    a: Sequence[tuple[FoundScores, Alarms]],
    b: Sequence[tuple[FoundScores, Alarms]],
    rng: np.random.Generator,
    num_samples: int = 1000,
    budget: float = ALARM_BUDGET,
    level: float = 0.95,
    seeds: bool = False,
) -> PairedDelta:
    """Paired bootstrap of the recall difference ``b - a`` at ``budget`` alarms per 100 images: each resample
    draws the images with fire and, independently, the images without fire, and reads every model at its own
    threshold on the drawn images (the threshold is part of what is resampled). Each side may be several runs
    (e.g. one per seed), averaged per resample; all must be scored on the same images. ``seeds``: each resample
    also draws the seeds (:func:`eval.stats.seed_picks`: run i of each side is seed i); the image draws are the
    same as without."""
    if not a or not b:
        raise ValueError("paired bootstrap needs at least one run on each side")
    runs = [*a, *b]
    if any(len(f.image_boxes) != len(runs[0][0].image_boxes) or al.images != runs[0][1].images for f, al in runs):
        raise ValueError("paired bootstrap needs every run scored on the same images")

    def mean_recall(side, wf=None, wn=None, pick=None) -> float:
        chosen = side if pick is None else [side[i] for i in pick]
        return float(np.mean([f.recall(al.threshold(budget, wn), wf) for f, al in chosen]))

    fire = resample_weights(len(runs[0][0].image_boxes), num_samples, rng)
    free = resample_weights(runs[0][1].images, num_samples, rng)
    picks = seed_picks(len(a), len(b), num_samples, rng, seeds)
    samples = np.empty(num_samples)
    for s, (wf, wn) in enumerate(zip(fire, free)):
        pick = None if picks is None else picks[s]
        samples[s] = mean_recall(b, wf, wn, pick) - mean_recall(a, wf, wn, pick)
    return paired_delta(mean_recall(b) - mean_recall(a), samples, level, resampled(picks))


def recall_at_rates(found: FoundScores, alarms: Alarms, rates: NDArray[np.float64]) -> NDArray[np.float64]:
    """The recall (R,) at each alarm budget of ``rates`` (R,) (alarms per 100 images): :func:`operating_point`
    read along the curve."""
    return curve_at_rates(*operating_curve(found, alarms), rates, found.recall(np.inf))


def curve_at_rates(
    rate: NDArray[np.float64], recall: NDArray[np.float64], rates: NDArray[np.float64], floor: float = 0.0
) -> NDArray[np.float64]:
    """An operating curve (``rate`` (P,) rising, ``recall`` (P,): :func:`operating_curve`) read at each budget of
    ``rates`` (R,): the recall of its last point within the budget, ``floor`` below its first point."""
    at = np.searchsorted(rate, rates, side="right") - 1  # the last curve point within each budget
    return np.where(at >= 0, recall[np.maximum(at, 0)], floor).astype(np.float64)

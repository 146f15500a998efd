"""Statistics over runs and test images: mean ± sample std over seeds, image-level bootstrap intervals of
COCO AP, and paired bootstrap of the AP difference between two models scored on the same test images.

The bootstrap re-uses one ``COCOeval.evaluate()``: the per-image matches are gathered once into a
:class:`MatchTable`, and each resample only re-accumulates them with integer image weights (an image drawn
k times counts k times), following pycocotools' accumulate (sort by score, cumulative TP/FP, precision made
monotone, read at 101 recall thresholds). With all weights 1 this reproduces pycocotools exactly.

The re-accumulation touches every detection once per resample and each IoU threshold's true positives, not
every (threshold, detection) pair: the first position where recall reaches a threshold is a true positive, and
the monotone precision there is the largest precision at a true positive from there on (a false positive, an
ignored or a weight-0 detection never raises precision over the position before it), so precision is only
needed at the true positives — counted detections up to each from one cumulative sum of the weights, shared
by the thresholds without ignored detections. The weights are integers, so every sum is exact and the result
identical to accumulating all pairs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from pycocotools.cocoeval import COCOeval


@dataclass(frozen=True)
class MeanStd:
    """Mean and sample standard deviation (ddof = 1; None for fewer than two values) of ``n`` values."""

    mean: float
    std: float | None
    n: int

    def format(self, scale: float = 100.0, digits: int = 1) -> str:
        """``"41.2 ± 1.3"`` (values times ``scale``); ``"41.2"`` when there is no std."""
        text = f"{self.mean * scale:.{digits}f}"
        return text if self.std is None else f"{text} ± {self.std * scale:.{digits}f}"


def mean_std(values: Sequence[float]) -> MeanStd:
    """Mean ± sample std of ``values`` (e.g. one metric over seeds); raises ValueError when empty."""
    arr = np.asarray([v for v in values if v is not None], dtype=np.float64)
    if arr.size == 0:
        raise ValueError("mean_std of no values")
    std = float(arr.std(ddof=1)) if arr.size > 1 else None
    return MeanStd(float(arr.mean()), std, int(arr.size))


@dataclass(frozen=True)
class ClassMatches:
    """One class, detections sorted best first: image index (D,), TP and FP flags (T, D); ignored
    detections are neither. ``npig``: (I,) non-ignored ground-truth boxes per image. ``score`` (D,): the
    detections' scores (None when loaded from a saved :class:`MatchTable`, which does not keep them)."""

    image: NDArray[np.int64]
    tp: NDArray[np.bool_]
    fp: NDArray[np.bool_]
    npig: NDArray[np.int64]
    score: NDArray[np.float64] | None = None


def class_matches(ev: COCOeval, k: int, max_det: int) -> ClassMatches:
    """Class ``k``'s matches of an evaluated ``COCOeval`` (area "all", at most ``max_det`` detections per image),
    in pycocotools' order."""
    num_images, num_areas = len(ev.params.imgIds), len(ev.params.areaRng)
    npig = np.zeros(num_images, dtype=np.int64)
    scores, images, matched, ignored = [], [], [], []
    for i in range(num_images):
        e = ev.evalImgs[k * num_areas * num_images + i]  # area index 0 = "all"
        if e is None:
            continue
        npig[i] = int(np.count_nonzero(np.asarray(e["gtIgnore"]) == 0))
        d = len(e["dtScores"][:max_det])
        scores.append(np.asarray(e["dtScores"][:max_det], dtype=np.float64))
        images.append(np.full(d, i, dtype=np.int64))
        matched.append(np.asarray(e["dtMatches"])[:, :max_det])  # (T, d)
        ignored.append(np.asarray(e["dtIgnore"])[:, :max_det])
    num_t = len(ev.params.iouThrs)
    if not scores:
        empty = np.zeros((num_t, 0), dtype=bool)
        return ClassMatches(np.zeros(0, dtype=np.int64), empty, empty, npig, np.zeros(0))
    all_scores = np.concatenate(scores)
    order = np.argsort(-all_scores, kind="mergesort")  # pycocotools' order
    dtm = np.concatenate(matched, axis=1)[:, order] != 0
    dtig = np.concatenate(ignored, axis=1)[:, order].astype(bool)
    return ClassMatches(np.concatenate(images)[order], dtm & ~dtig, ~dtm & ~dtig, npig, all_scores[order])


@dataclass(frozen=True)
class Hits:
    """One class's matches arranged for weighted re-accumulation (module docstring): ``image`` (D,) as in
    :class:`ClassMatches`; per IoU threshold t, ``tp_at[t]`` the positions of its true positives (best first) and
    ``counted[t]`` (D,) bool, the detections that are TP or FP, or None when every detection is one."""

    image: NDArray[np.int64]
    tp_at: tuple[NDArray[np.int64], ...]
    counted: tuple[NDArray[np.bool_] | None, ...]

    @classmethod
    def of(cls, cm: ClassMatches) -> Hits:
        counted = cm.tp | cm.fp
        return cls(
            cm.image,
            tuple(np.flatnonzero(row) for row in cm.tp),
            tuple(None if row.all() else row for row in counted),
        )

    def precision(self, w: NDArray[np.float64], npig: float, rec_thrs: NDArray[np.float64]) -> NDArray[np.float64]:
        """(T, R) interpolated precision at ``rec_thrs`` (R,) for image weights ``w`` (I,), ``npig`` > 0 the
        weighted ground-truth count; equal to pycocotools' accumulate on the resampled images."""
        wd = w[self.image]
        all_counted = np.cumsum(wd)
        out = np.zeros((len(self.tp_at), len(rec_thrs)))
        for t, (at, counted) in enumerate(zip(self.tp_at, self.counted)):
            if at.size == 0:
                continue
            tp = np.cumsum(wd[at])
            n = all_counted[at] if counted is None else np.cumsum(wd * counted)[at]
            pr = np.maximum.accumulate((tp / (n + np.spacing(1)))[::-1])[::-1]
            idx = np.searchsorted(tp / npig, rec_thrs, side="left")
            out[t] = np.where(idx < at.size, pr[np.minimum(idx, at.size - 1)], 0.0)
        return out


class MatchTable:
    """Per-image matches of one evaluated ``COCOeval`` (area "all", the last ``maxDets``), re-accumulated
    for any image weighting. ``image_ids`` (I,) is the image order weights refer to."""

    def __init__(self, ev: COCOeval) -> None:
        if not ev.evalImgs:
            raise ValueError("run COCOeval.evaluate() first")
        max_det = ev.params.maxDets[-1]
        self.image_ids = np.asarray(ev.params.imgIds, dtype=np.int64)
        self.cat_ids = list(ev.params.catIds)
        self.rec_thrs = np.asarray(ev.params.recThrs, dtype=np.float64)
        self.classes = [class_matches(ev, k, max_det) for k in range(len(self.cat_ids))]

    def precision(self, weights: NDArray | None = None) -> NDArray[np.float64]:
        """(T, R, K) interpolated precision for image ``weights`` (I,) (default: each image once); -1 for a
        class without ground truth under these weights, as in ``COCOeval.eval["precision"]``."""
        w = np.ones(len(self.image_ids)) if weights is None else np.asarray(weights, dtype=np.float64)
        num_t = self.classes[0].tp.shape[0] if self.classes else 0
        out = -np.ones((num_t, len(self.rec_thrs), len(self.classes)))
        for k, (cm, hits) in enumerate(zip(self.classes, self._hits)):
            npig = float(w @ cm.npig)
            if npig > 0:
                out[:, :, k] = hits.precision(w, npig, self.rec_thrs)
        return out

    @cached_property
    def _hits(self) -> list[Hits]:
        return [Hits.of(cm) for cm in self.classes]

    def ap(self, weights: NDArray | None = None) -> dict[str, float]:
        """``{"AP", "AP50"}`` over classes with ground truth (NaN when none has any)."""
        prec = self.precision(weights)
        return {"AP": _mean_valid(prec), "AP50": _mean_valid(prec[:1])}

    def of_class(self, k: int) -> MatchTable:
        """The table of the ``k``-th class of :attr:`cat_ids` alone (same images, same weights): its AP and AP50
        are that class's (``CocoMetrics.per_class``), and a paired bootstrap of two such tables compares one class."""
        table = MatchTable.__new__(MatchTable)
        table.image_ids, table.cat_ids, table.rec_thrs = self.image_ids, [self.cat_ids[k]], self.rec_thrs
        table.classes = [self.classes[k]]
        return table

    def restricted(self, thresholds: Sequence[int], keep: NDArray[np.bool_]) -> MatchTable:
        """The table at the IoU thresholds of index ``thresholds`` only, and with only the detections and boxes
        of the images ``keep`` (I,) (the others weigh 0: an AP on those images, computed faster). Image order is
        kept, so the same weights apply."""
        table = MatchTable.__new__(MatchTable)
        table.image_ids, table.cat_ids, table.rec_thrs = self.image_ids, self.cat_ids, self.rec_thrs
        rows = list(thresholds)
        table.classes = []
        for cm in self.classes:
            on = keep[cm.image]
            score = None if cm.score is None else cm.score[on]
            table.classes.append(
                ClassMatches(cm.image[on], cm.tp[rows][:, on], cm.fp[rows][:, on], cm.npig * keep, score)
            )
        return table

    def save(self, path: Path) -> Path:
        """Store the table (a few arrays per class) so a report can bootstrap without re-running a model."""
        arrays: dict[str, NDArray] = {"image_ids": self.image_ids, "cat_ids": np.asarray(self.cat_ids)}
        arrays["rec_thrs"] = self.rec_thrs
        for k, cm in enumerate(self.classes):
            arrays.update({f"image{k}": cm.image, f"tp{k}": cm.tp, f"fp{k}": cm.fp, f"npig{k}": cm.npig})
        np.savez_compressed(path, **arrays)
        return path

    @classmethod
    def load(cls, path: Path) -> MatchTable:
        with np.load(path) as z:
            table = cls.__new__(cls)
            table.image_ids, table.cat_ids, table.rec_thrs = z["image_ids"], z["cat_ids"].tolist(), z["rec_thrs"]
            table.classes = [
                ClassMatches(z[f"image{k}"], z[f"tp{k}"], z[f"fp{k}"], z[f"npig{k}"]) for k in range(len(table.cat_ids))
            ]
        return table


def _mean_valid(prec: NDArray[np.float64]) -> float:
    valid = prec[prec > -1]
    return float(valid.mean()) if valid.size else math.nan


def resample_weights(num_images: int, num_samples: int, rng: np.random.Generator) -> NDArray[np.int64]:
    """(num_samples, num_images) counts: how often each image is drawn in each bootstrap resample."""
    draws = rng.integers(0, num_images, size=(num_samples, num_images))
    return np.stack([np.bincount(row, minlength=num_images) for row in draws])


@dataclass(frozen=True)
class Interval:
    """A point estimate with a percentile bootstrap interval at ``level``; ``samples`` (S,) the resamples."""

    point: float
    low: float
    high: float
    level: float
    samples: NDArray[np.float64]

    def to_dict(self) -> dict[str, float]:
        return {"value": self.point, "low": self.low, "high": self.high, "level": self.level}


def interval(point: float, samples: NDArray[np.float64], level: float) -> Interval:
    """``point`` with the percentile interval at ``level`` of the finite ``samples`` (S,) (NaN bounds when none)."""
    finite = samples[np.isfinite(samples)]
    if finite.size == 0:
        return Interval(point, math.nan, math.nan, level, samples)
    low, high = np.quantile(finite, [(1 - level) / 2, 1 - (1 - level) / 2])
    return Interval(point, float(low), float(high), level, samples)


def bootstrap_ap(
    table: MatchTable, rng: np.random.Generator, num_samples: int = 1000, level: float = 0.95
) -> dict[str, Interval]:
    """95% image-level bootstrap intervals of AP and AP50: test images drawn with replacement."""
    weights = resample_weights(len(table.image_ids), num_samples, rng)
    point = table.ap()
    samples = [table.ap(w) for w in weights]
    return {key: interval(point[key], np.array([s[key] for s in samples]), level) for key in point}


@dataclass(frozen=True)
class PairedDelta:
    """``AP(b) - AP(a)`` on the same images: point, bootstrap interval and a two-sided bootstrap p-value
    (twice the smaller share of resamples on either side of zero, capped at 1)."""

    interval: Interval
    p_value: float
    resampled: str = "images"  # what each resample draws: images | images and seeds (:func:`seed_picks`)

    def to_dict(self) -> dict[str, float]:
        return {**self.interval.to_dict(), "p_value": self.p_value, "resampled": self.resampled}  # type: ignore[dict-item]


#: With at least this many seeds on each side, paired by seed, a paired bootstrap resamples the seeds as well as
#: the test images (two levels: :func:`seed_picks`), so its interval covers how another training would land.
MIN_SEEDS_RESAMPLED = 3


def seed_picks(
    na: int, nb: int, num_samples: int, rng: np.random.Generator, seeds: bool = True
) -> NDArray[np.int64] | None:
    """The seeds each resample of a two-level bootstrap averages, (S, k) indices into both sides' runs (the same
    for ``a`` and ``b``: run i of each is seed i), drawn with replacement; None when the bootstrap resamples the
    images only: ``seeds`` false, sides of different lengths or fewer than :data:`MIN_SEEDS_RESAMPLED` runs."""
    if not seeds or na != nb or na < MIN_SEEDS_RESAMPLED:
        return None
    return rng.integers(0, na, size=(num_samples, na))


def resampled(picks: NDArray[np.int64] | None) -> str:
    """What a bootstrap with these :func:`seed_picks` resamples, as :class:`PairedDelta` says it."""
    return "images" if picks is None else "images and seeds"


def _mean_ap(tables: Sequence[MatchTable], weights: NDArray | None, pick: NDArray | None = None) -> dict[str, float]:
    scores = [t.ap(weights) for t in tables]
    chosen = scores if pick is None else [scores[i] for i in pick]
    return {key: float(np.mean([sc[key] for sc in chosen])) for key in scores[0]}


def paired_bootstrap(
    a: MatchTable | Sequence[MatchTable],
    b: MatchTable | Sequence[MatchTable],
    rng: np.random.Generator,
    num_samples: int = 1000,
    level: float = 0.95,
    keep: NDArray[np.bool_] | None = None,
    seeds: bool = False,
) -> dict[str, PairedDelta]:
    """Paired image-level bootstrap of the AP and AP50 differences ``b - a``: each resample draws one set of
    test images and scores both on it. ``a`` and ``b`` may each be several runs (e.g. one per seed) whose
    AP is averaged per resample. Every table must cover the same image ids. ``keep`` (I,): only those images
    are drawn, the others weigh 0 (a slice; give tables :meth:`MatchTable.restricted` to it, whose AP50 is then
    the AP at their one IoU threshold). ``seeds``: with as many runs on each side, run i of each being seed i,
    and at least :data:`MIN_SEEDS_RESAMPLED` of them, each resample also draws the seeds (two levels: seeds, then
    images; :func:`seed_picks`); the image draws are the same as without."""
    ta = [a] if isinstance(a, MatchTable) else list(a)
    tb = [b] if isinstance(b, MatchTable) else list(b)
    if not ta or not tb:
        raise ValueError("paired bootstrap needs at least one table on each side")
    if any(not np.array_equal(ta[0].image_ids, t.image_ids) for t in ta + tb):
        raise ValueError("paired bootstrap needs both models scored on the same test images")
    if keep is None:
        weights = resample_weights(len(ta[0].image_ids), num_samples, rng)
    else:
        where = np.flatnonzero(keep)
        weights = np.zeros((num_samples, len(keep)), dtype=np.int64)
        weights[:, where] = resample_weights(len(where), num_samples, rng)
    picks = seed_picks(len(ta), len(tb), num_samples, rng, seeds)
    pa, pb = _mean_ap(ta, None), _mean_ap(tb, None)
    deltas: dict[str, list[float]] = {key: [] for key in pa}
    for s, w in enumerate(weights):
        pick = None if picks is None else picks[s]
        sa, sb = _mean_ap(ta, w, pick), _mean_ap(tb, w, pick)
        for key in deltas:
            deltas[key].append(sb[key] - sa[key])
    how = resampled(picks)
    return {key: paired_delta(pb[key] - pa[key], np.asarray(values), level, how) for key, values in deltas.items()}


def paired_delta(point: float, samples: NDArray[np.float64], level: float = 0.95, how: str = "images") -> PairedDelta:
    """A paired difference ``point`` with its resampled differences ``samples`` (S,): the percentile interval and
    the two-sided bootstrap p-value of :class:`PairedDelta` over the finite samples (NaN when none); ``how``: what
    was resampled (:func:`resampled`)."""
    finite = samples[np.isfinite(samples)]
    p = min(1.0, 2 * min(np.mean(finite <= 0), np.mean(finite >= 0))) if finite.size else math.nan
    return PairedDelta(interval(point, samples, level), float(p), how)

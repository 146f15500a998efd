"""Image-level detection: did the detector raise an alarm on this frame, and was it on the fire? What a fire user
judges a detector by, per image and per camera, and a measure that does not hang on how a test set's annotators
drew their boxes (whole burning regions or single flames).

A fire image is **detected** at threshold ``t`` when a detection of a scored class with score >= ``t`` *hits* one
of its fire boxes: IoU >= :data:`HIT_IOU` (0.1), or the detection's centre inside the box. An image labelled with
a scored class at the image level (an image-labelled set: no boxes) is detected by any detection of that class. The centre rule keeps a
detection of one flame inside a box drawn round a whole burning building (IoU far below 0.1) a hit; the IoU
rule keeps a detection drawn round a whole region holding a small box a hit. A **false-alarm image** is an image
without fire with any detection >= ``t``; the alarm rate is false-alarm images per 100 images without fire.

:class:`ImageHits` keeps, per image, the best score of a detection that hits it, so the image recall at any
threshold, of any subset of images (a slice) or any bootstrap weighting, is one comparison. Image recall is read
against the alarm rate (:func:`image_operating_curve`) or at an alarm budget (:func:`image_recall_at_budget`, the
threshold found by :meth:`eval.operating.Alarms.threshold` on per-image alarms), or at a fixed confidence when
there is no set without fire.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from eval.operating import Alarms, alarms_of
from eval.stats import PairedDelta, paired_delta, resample_weights, resampled, seed_picks
from ground.data.boxes import box_iou_xyxy, xywh_to_xyxy, xyxy_to_cxcywh
from ground.data.dataset import Dataset

HIT_IOU = 0.1  # IoU with a fire box at which a detection hits it (or its centre inside the box)
IMAGE_RECALL = "image_recall"  # result key: share of fire images detected at the operating threshold (0..1)
IMAGE_RECALL_AT_CONF = "image_recall_at_conf"  # result key: image recall at confidence ALARM_CONF (0..1)
IMAGE_LABELLED = "image_labelled"  # result key: True for a set judged at the image level only (no boxes, no AP)
IMAGELEVEL = "imagelevel"  # a study row's (ImageHits, per-image Alarms or a confidence): its image recall; not written


@dataclass(frozen=True)
class ImageHits:
    """The images of a scored set in the order of their ids: ``fire`` (I,) bool, the images with a fire box (not
    crowd) or an image-level label of a scored class, and ``best`` (I,) float64 the best score of a detection that hits one of its boxes
    (-inf when none does, and for images without fire)."""

    image_ids: NDArray[np.int64]
    fire: NDArray[np.bool_]
    best: NDArray[np.float64]

    def recall(self, threshold: float, weights: NDArray | None = None) -> float:
        """Share (0..1) of the fire images detected at ``threshold`` (NaN without fire images); ``weights`` (I,):
        how often each image counts (a slice's mask times a bootstrap resample; default once)."""
        w = self.fire.astype(np.float64) if weights is None else np.asarray(weights, np.float64) * self.fire
        total = float(w.sum())
        return float(w @ (self.best >= threshold)) / total if total else float("nan")


def image_hits(dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int]) -> ImageHits:
    """:class:`ImageHits` of COCO result ``records`` ({image_id, category_id, bbox xywh px, score}) on ``dataset``
    over the categories ``cat_ids`` (a detection hits a box of its own class)."""
    cats = set(cat_ids)
    ids = np.asarray(sorted(img.id for img in dataset.images), dtype=np.int64)
    index = {int(i): k for k, i in enumerate(ids)}
    gt: dict[int, list[tuple[int, list[float]]]] = {}
    for a in dataset.annotations:
        if not a.iscrowd and a.category_id in cats:
            gt.setdefault(a.image_id, []).append((a.category_id, list(a.bbox)))
    labelled = _image_labels(dataset, cats)
    fire = np.zeros(len(ids), dtype=bool)
    fire[[index[i] for i in (*gt, *labelled)]] = True
    best = np.full(len(ids), -np.inf)
    dets: dict[int, list[dict[str, Any]]] = {}
    for r in records:
        if (r["image_id"] in gt or r["image_id"] in labelled) and r["category_id"] in cats:
            dets.setdefault(r["image_id"], []).append(r)
    for image_id, found in dets.items():
        held = labelled.get(image_id, set())
        best[index[image_id]] = max(_best_hit(gt.get(image_id, []), found),
                                    max((float(d["score"]) for d in found if d["category_id"] in held), default=-np.inf))  # fmt: skip
    return ImageHits(ids, fire, best)


def _image_labels(dataset: Dataset, cats: set[int]) -> dict[int, set[int]]:
    """image id -> the category ids among ``cats`` it is labelled with at the image level (labelled images only)."""
    ids = {c.name: c.id for c in dataset.categories}
    held = {img.id: {ids[n] for n in img.labels if ids.get(n) in cats} for img in dataset.images if img.labels}
    return {i: c for i, c in held.items() if c}


def _best_hit(boxes: Sequence[tuple[int, list[float]]], dets: Sequence[dict[str, Any]]) -> float:
    """The best score among ``dets`` (COCO records of one image) that hit a box of ``boxes`` ((category, xywh))."""
    best = -np.inf
    for cat in {c for c, _ in boxes}:
        g = xywh_to_xyxy(np.asarray([b for c, b in boxes if c == cat], dtype=np.float64))
        mine = [d for d in dets if d["category_id"] == cat]
        if not mine:
            continue
        d = xywh_to_xyxy(np.asarray([m["bbox"] for m in mine], dtype=np.float64))
        scores = np.asarray([m["score"] for m in mine], dtype=np.float64)
        cx, cy = xyxy_to_cxcywh(d)[:, :2].T
        inside = (cx[:, None] >= g[None, :, 0]) & (cx[:, None] <= g[None, :, 2])
        inside &= (cy[:, None] >= g[None, :, 1]) & (cy[:, None] <= g[None, :, 3])
        hit = ((box_iou_xyxy(d, g) >= HIT_IOU) | inside).any(axis=1)
        if hit.any():
            best = max(best, float(scores[hit].max()))
    return best


def image_alarms(alarms: Alarms) -> Alarms:
    """The per-image view of ``alarms`` (detections on images without fire, :func:`eval.operating.alarms_of`): one
    entry per image with a detection, its best score (its rate is then false-alarm *images* per 100)."""
    keep = np.zeros(len(alarms.image), dtype=bool)
    _, first = np.unique(alarms.image, return_index=True)  # best first: each image's first entry is its best
    keep[first] = True
    return Alarms(alarms.scores[keep], alarms.image[keep], alarms.images)


def image_operating_curve(hits: ImageHits, alarms: Alarms) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(false-alarm images per 100 (P,), image recall (P,)) at every threshold where either changes, from the
    highest down (``alarms``: :func:`image_alarms`)."""
    detected = np.sort(hits.best[hits.fire & np.isfinite(hits.best)])[::-1]
    thresholds = np.unique(np.concatenate([detected, alarms.scores]))[::-1]
    rate = 100.0 * np.searchsorted(-alarms.scores, -thresholds, side="right") / alarms.images
    recall = np.searchsorted(-detected, -thresholds, side="right") / max(int(hits.fire.sum()), 1)
    return rate.astype(np.float64), recall.astype(np.float64)


def paired_image_recall(
    a: Sequence[tuple[ImageHits, Alarms | float]],
    b: Sequence[tuple[ImageHits, Alarms | float]],
    rng: np.random.Generator,
    num_samples: int = 1000,
    budget: float = 10.0,
    mask: NDArray[np.bool_] | None = None,
    level: float = 0.95,
    seeds: bool = False,
) -> PairedDelta:
    """Paired bootstrap of the image-recall difference ``b - a`` on the images of ``mask`` (I,) (default all):
    each resample draws those images and, independently, the images without fire of each run's
    :class:`eval.operating.Alarms`, and reads each run at the threshold that keeps its false-alarm images within
    ``budget`` per 100 on the drawn ones; a run given a float is read at that fixed confidence instead. Each side
    may be several runs (seeds), averaged per resample; every run is scored on the same images. ``seeds``: each
    resample also draws the seeds (:func:`eval.stats.seed_picks`: run i of each side is seed i)."""
    runs = [*a, *b]
    if not a or not b:
        raise ValueError("paired bootstrap needs at least one run on each side")
    if any(not np.array_equal(h.image_ids, runs[0][0].image_ids) for h, _ in runs):
        raise ValueError("paired bootstrap needs every run scored on the same images")
    keep = np.ones(len(runs[0][0].image_ids), dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    where = np.flatnonzero(keep)
    free = next((al.images for _, al in runs if isinstance(al, Alarms)), 0)

    def mean_recall(side, w=None, wn=None, pick=None) -> float:
        chosen = side if pick is None else [side[i] for i in pick]
        return float(
            np.mean([h.recall(al.threshold(budget, wn) if isinstance(al, Alarms) else al, w) for h, al in chosen])
        )

    full = keep.astype(np.float64)
    samples = np.empty(num_samples)
    drawn = resample_weights(len(where), num_samples, rng)
    negatives = resample_weights(free, num_samples, rng) if free else [None] * num_samples
    picks = seed_picks(len(a), len(b), num_samples, rng, seeds)
    for s, (wd, wn) in enumerate(zip(drawn, negatives)):
        w = np.zeros(len(keep))
        w[where] = wd
        pick = None if picks is None else picks[s]
        samples[s] = mean_recall(b, w, wn, pick) - mean_recall(a, w, wn, pick)
    return paired_delta(mean_recall(b, full) - mean_recall(a, full), samples, level, resampled(picks))


@dataclass(frozen=True)
class ImageLevel:
    """One detector on an image-labelled set (or any set with fire), read per image: ``fire_images`` holding a
    scored class and the share detected (0..1) at confidence ``conf``; its ``free_images`` holding none and the
    share of them raising an alarm at ``conf``; with free images, ``budget_recall`` the image recall at the
    threshold ``budget_threshold`` where at most ``budget`` of 100 of them raise one (None without)."""

    fire_images: int
    conf: float
    recall_at_conf: float
    free_images: int
    alarm_share_at_conf: float | None
    budget: float
    budget_recall: float | None
    budget_threshold: float | None

    def to_dict(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def free_alarms(hits: ImageHits, records: Sequence[dict[str, Any]], cat_ids: Sequence[int]) -> Alarms:
    """The per-image alarms (:func:`image_alarms`) that COCO result ``records`` of the categories ``cat_ids`` raise on
    the images of ``hits`` without fire: a set's own images without a scored class."""
    free_ids = hits.image_ids[~hits.fire].tolist()
    cats, free = set(cat_ids), set(free_ids)
    return image_alarms(alarms_of([r for r in records if r["category_id"] in cats and r["image_id"] in free], free_ids))


def image_level(
    dataset: Dataset, records: Sequence[dict[str, Any]], cat_ids: Sequence[int], conf: float, budget: float
) -> ImageLevel:
    """:class:`ImageLevel` of COCO result ``records`` on ``dataset`` over the categories ``cat_ids``; its images
    without a scored class are its own images without fire (:func:`image_alarms`)."""
    hits = image_hits(dataset, records, cat_ids)
    alarms = free_alarms(hits, records, cat_ids)
    threshold = alarms.threshold(budget) if alarms.images else None
    return ImageLevel(
        int(hits.fire.sum()), conf, hits.recall(conf), alarms.images,
        alarms.per_100(conf) / 100.0 if alarms.images else None, budget,
        None if threshold is None else hits.recall(threshold), threshold,
    )  # fmt: skip

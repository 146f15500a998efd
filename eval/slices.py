"""Slices of a test set by what its images show (:mod:`eval.attributes`), and paired comparisons of two detectors
on each: on which fires does one beat the other, and how sure is that.

**Slices.** Each attribute cuts the images into one slice per value. Attributes of the fire (``size``,
``size_fine``, ``fires``, ``colour``) hold only images with fire; the others (``light``, ``sky``, ``blur``,
``source`` and a user's) hold every image with that value, fire-free ones included (their detections are false
positives there as everywhere). A slice with fewer than :data:`MIN_FIRE_IMAGES` fire images is merged: with its
smaller neighbour for an ordered attribute (:data:`ORDERED`: ``size=small,medium``), into ``other`` for the
rest; one still too
small is kept and marked (``too_few``) and never compared. An attribute left with one slice is no cut at all and
is dropped.

**Comparisons.** For each slice: the differences ``b - a`` of AP50, AP25 (:data:`ground.detect.cocoeval.LOOSE_IOU`)
and image recall (:mod:`eval.imagelevel`), each by the paired image-level bootstrap: every resample draws the
slice's images with replacement and scores both sides on them, each side the mean over its runs (seeds). Many
slices are many tests: each comparison's slices of one metric are one family, and a slice is called helped or
hurt only when its bootstrap p-value stays under 0.05 after **Holm's step-down correction** (family-wise error
rate 5 %); the 95 % intervals shown are per slice, not adjusted.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from eval.attributes import ATTRIBUTES, Attributes
from eval.imagelevel import ImageHits, paired_image_recall
from eval.operating import Alarms
from eval.stats import MatchTable, paired_bootstrap

MIN_FIRE_IMAGES = 20  # fire images a slice needs to be compared
FIRE_ATTRIBUTES = ("size", "size_fine", "fires", "colour")  # attributes only images with fire have
ORDERED = ("size", "size_fine", "fires", "light", "blur")  # attributes whose values have an order (merged in it)
ALPHA = 0.05  # family-wise error rate of Holm's correction
METRICS = ("AP50", "AP25", "image_recall")
FIRE_IMAGES = "fire images"  # what a slice's positive images are called in a fire-only study (positives_name)


def objects_name(classes: Sequence[str]) -> str:
    """What the objects of a study of ``classes`` are called: ``fire`` (one class), or ``fire or smoke``."""
    return "fire" if len(classes) < 2 else " or ".join(classes)


def positives_name(classes: Sequence[str]) -> str:
    """What a slice's ``fire_images`` count is called in a study of ``classes``: ``fire images``, or ``images with
    fire or smoke`` (an image holding any studied class, :func:`objects_name`)."""
    return FIRE_IMAGES if len(classes) < 2 else f"images with {objects_name(classes)}"


@dataclass(frozen=True)
class Slice:
    """The images of one value (or merged values) of an attribute: ``mask`` (I,) over the test images in the
    order of their ids, ``images`` and ``fire_images`` its counts; ``too_few``: under :data:`MIN_FIRE_IMAGES`
    fire images even after merging (shown, never compared)."""

    attribute: str
    value: str
    mask: NDArray[np.bool_]
    images: int
    fire_images: int
    too_few: bool = False

    @property
    def name(self) -> str:
        return f"{self.attribute}={self.value}"


def make_slices(
    attributes: Attributes, image_ids: NDArray[np.int64], fire: NDArray[np.bool_], minimum: int = MIN_FIRE_IMAGES
) -> list[Slice]:
    """The slices (module docstring) of the images ``image_ids`` (I,) (``fire`` (I,): which hold fire) by every
    attribute of ``attributes`` (image id -> attribute -> value), computed attributes first in
    :data:`eval.attributes.ATTRIBUTES` order, then the user's sorted by name."""
    given = {k for v in attributes.values() for k in v}
    names = [k for k in ATTRIBUTES if k in given] + sorted(given - set(ATTRIBUTES))
    out = []
    for attr in names:
        values = np.asarray([attributes.get(int(i), {}).get(attr) for i in image_ids], dtype=object)
        if attr in FIRE_ATTRIBUTES:
            values = np.where(fire, values, None)
        order = ATTRIBUTES.get(attr) or ()
        present = [v for v in order if v in set(values)] + sorted({v for v in values if v is not None} - set(order))
        groups = [([v], values == v) for v in present]
        groups = _merge(groups, fire, minimum, ordered=attr in ORDERED)
        if len(groups) < 2:
            continue
        for vals, mask in groups:
            n_fire = int((mask & fire).sum())
            out.append(Slice(attr, ",".join(vals), mask, int(mask.sum()), n_fire, n_fire < minimum))
    return out


def _merge(groups: list, fire: NDArray[np.bool_], minimum: int, ordered: bool) -> list:
    """Merge groups ((values, mask)) under ``minimum`` fire images: into the smaller neighbour when ``ordered``,
    else all small ones into ``other``."""
    count = lambda g: int((g[1] & fire).sum())  # noqa: E731
    if ordered:
        groups = list(groups)
        while len(groups) > 1 and min(map(count, groups)) < minimum:
            k = int(np.argmin([count(g) for g in groups]))
            near = [j for j in (k - 1, k + 1) if 0 <= j < len(groups)]
            j = min(near, key=lambda j: count(groups[j]))
            lo, hi = sorted((k, j))
            groups[lo : hi + 1] = [(groups[lo][0] + groups[hi][0], groups[lo][1] | groups[hi][1])]
        return groups
    big = [g for g in groups if count(g) >= minimum]
    small = [g for g in groups if count(g) < minimum]
    if small:
        mask = np.logical_or.reduce([g[1] for g in small])
        big.append((["other"] if len(small) > 1 else small[0][0], mask))
    return big


@dataclass(frozen=True)
class Side:
    """One side of a comparison, one entry per run (seed): its matches at IoU 0.5:0.95 (``ap50``) and at 0.25
    (``ap25``) (:class:`eval.stats.MatchTable`), and its image hits with its per-image alarms, or the fixed
    confidence it is read at when there is no set without fire (``hits``)."""

    ap50: Sequence[MatchTable]
    ap25: Sequence[MatchTable]
    hits: Sequence[tuple[ImageHits, Alarms | float]]


def compare_slices(
    a: Side,
    b: Side,
    slices: Sequence[Slice],
    rng: np.random.Generator,
    num_samples: int = 1000,
    metrics: Sequence[str] = METRICS,
) -> list[dict[str, Any]]:
    """One row per (slice, metric of ``metrics``) with enough fire images: ``slice``, ``attribute``, ``value``,
    ``images``, ``fire_images``, ``metric`` (:data:`METRICS`), ``delta`` (:meth:`eval.stats.PairedDelta.to_dict`
    of ``b - a``), ``p_holm`` (Holm-adjusted within the metric) and ``verdict`` (``helps``, ``hurts`` or ``-``).
    Leave AP50 out of ``metrics`` on a set with too few fire images for AP."""
    unknown = set(metrics) - set(METRICS)
    if unknown:
        raise ValueError(f"unknown slice metrics {sorted(unknown)}; known: {', '.join(METRICS)}")
    rows = []
    for s in (s for s in slices if not s.too_few):
        deltas = {}
        for metric in metrics:
            if metric == "image_recall":
                deltas[metric] = paired_image_recall(a.hits, b.hits, rng, num_samples, mask=s.mask)
                continue
            ta, tb = (a.ap50, b.ap50) if metric == "AP50" else (a.ap25, b.ap25)
            narrowed = [t.restricted([0], s.mask) for t in ta], [t.restricted([0], s.mask) for t in tb]
            deltas[metric] = paired_bootstrap(*narrowed, rng, num_samples, keep=s.mask)["AP50"]  # first threshold
        for metric, d in deltas.items():
            rows.append({"slice": s.name, "attribute": s.attribute, "value": s.value, "images": s.images,
                         "fire_images": s.fire_images, "metric": metric, "delta": d.to_dict()})  # fmt: skip
    for metric in metrics:
        family = [r for r in rows if r["metric"] == metric]
        for r, p in zip(family, holm([r["delta"]["p_value"] for r in family])):
            r["p_holm"] = p
            value = r["delta"]["value"]
            r["verdict"] = ("helps" if value > 0 else "hurts") if p < ALPHA and np.isfinite(value) else "-"
    return rows


def holm(p_values: Sequence[float]) -> list[float]:
    """Holm's step-down adjusted p-values (same order as given; NaN stays NaN): the k-th smallest of m is
    multiplied by m - k + 1, made non-decreasing, capped at 1."""
    p = np.asarray(p_values, dtype=np.float64)
    finite = np.flatnonzero(np.isfinite(p))
    out = np.full(len(p), np.nan)
    order = finite[np.argsort(p[finite], kind="stable")]
    m = len(order)
    running = 0.0
    for k, i in enumerate(order):
        running = max(running, min(1.0, (m - k) * p[i]))
        out[i] = running
    return out.tolist()


def slice_table(slices: Sequence[Slice]) -> list[dict[str, Any]]:
    """The slices as rows (attribute, value, images, fire images, too_few) for the report and ``slices.json``."""
    return [{"slice": s.name, "attribute": s.attribute, "value": s.value, "images": s.images,
             "fire_images": s.fire_images, "too_few": s.too_few} for s in slices]  # fmt: skip

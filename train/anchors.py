"""Anchor fit check and k-means anchors from training labels (YOLOv5's published metric, our code).

A label of size ``(w, h)`` fits an anchor ``(aw, ah)`` with ``r = min(w/aw, aw/w, h/ah, ah/h)``; it is
*recallable* when its best anchor has ``r > 1 / anchor_t``. Best possible recall (BPR) is the fraction of
recallable labels; the fitness of a set of anchors is the mean of the best ``r`` over recallable labels.
All sizes are in letterboxed input pixels.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ground.data.dataset import Dataset

#: Anchors are re-fitted when fewer than this fraction of labels can be matched by the default ones.
MIN_BPR = 0.98


def label_sizes(ds: Dataset, imgsz: int) -> NDArray[np.float64]:
    """(N, 2) box ``(w, h)`` after letterboxing each image to ``imgsz`` (longest side), crowd boxes left out."""
    scale = {img.id: imgsz / max(img.width, img.height) for img in ds.images}
    sizes = [(a.bbox[2] * scale[a.image_id], a.bbox[3] * scale[a.image_id]) for a in ds.annotations if not a.iscrowd]
    return np.asarray(sizes, dtype=np.float64).reshape(-1, 2)


def best_ratio(wh: NDArray[np.float64], anchors: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N,) best symmetric size ratio in (0, 1] of each label ``wh`` (N, 2) over ``anchors`` (K, 2)."""
    r = wh[:, None, :] / anchors[None, :, :]
    return np.minimum(r, 1.0 / r).min(axis=2).max(axis=1)


def anchor_fit(wh: NDArray[np.float64], anchors: NDArray[np.float64], anchor_t: float = 4.0) -> dict[str, float]:
    """``{"bpr", "fitness"}`` of ``anchors`` (K, 2) for labels ``wh`` (N, 2)."""
    if len(wh) == 0:
        return {"bpr": 1.0, "fitness": 0.0}
    best = best_ratio(wh, anchors)
    ok = best > 1.0 / anchor_t
    return {"bpr": float(ok.mean()), "fitness": float((best * ok).mean())}


def kmeans_anchors(
    wh: NDArray[np.float64], k: int, rng: np.random.Generator, iters: int = 30, restarts: int = 5
) -> NDArray[np.float64]:
    """(k, 2) anchors sorted by area: Lloyd's k-means on ``wh`` / std (``restarts`` seeded starts), the run
    with the best :func:`anchor_fit` fitness kept."""
    wh = wh[(wh >= 2.0).all(axis=1)]  # tiny boxes carry no size information
    if len(wh) < k:
        raise ValueError(f"k-means anchors need at least {k} labels of 2 px or more, got {len(wh)}")
    std = wh.std(axis=0) + 1e-9
    x = wh / std
    best, best_fit = None, -1.0
    for _ in range(restarts):
        centres = x[rng.choice(len(x), size=k, replace=False)]
        for _ in range(iters):
            nearest = ((x[:, None, :] - centres[None]) ** 2).sum(-1).argmin(1)
            centres = np.stack([x[nearest == i].mean(0) if (nearest == i).any() else centres[i] for i in range(k)])
        anchors = centres * std
        fit = anchor_fit(wh, anchors)["fitness"]
        if fit > best_fit:
            best, best_fit = anchors, fit
    assert best is not None
    return best[np.argsort(best.prod(axis=1))]


def check_anchors(
    wh: NDArray[np.float64],
    anchors: Sequence[Sequence[Sequence[float]]],
    rng: np.random.Generator,
    anchor_t: float = 4.0,
) -> tuple[NDArray[np.float64], dict[str, float]]:
    """The anchors to train with, shaped (levels, per_level, 2), and a report.

    Keeps ``anchors`` when their BPR is at least :data:`MIN_BPR`; otherwise fits k-means anchors and keeps
    whichever set has the higher BPR. Report keys: ``bpr``, ``fitness``, ``bpr_before``, ``refitted`` (0/1).
    """
    current = np.asarray(anchors, dtype=np.float64)
    flat = current.reshape(-1, 2)
    before = anchor_fit(wh, flat, anchor_t)
    report = {"bpr_before": before["bpr"], **before, "refitted": 0.0}
    if before["bpr"] >= MIN_BPR or len(wh) < len(flat):
        return current, report
    fitted = kmeans_anchors(wh, len(flat), rng)
    after = anchor_fit(wh, fitted, anchor_t)
    if after["bpr"] <= before["bpr"]:
        return current, report
    return fitted.reshape(current.shape), {"bpr_before": before["bpr"], **after, "refitted": 1.0}

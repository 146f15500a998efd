"""COCO box evaluation in vectorised numpy, equal to pycocotools' ``COCOeval`` (``evaluate`` + ``accumulate``).

:class:`FastCOCOeval` is a ``COCOeval`` whose ``evaluate`` and ``accumulate`` work on arrays instead of one
Python call per (image, category, area range): its ``evalImgs``, ``eval`` and (through the inherited
``summarize``) ``stats`` are pycocotools' to the last bit (``tests/test_ground_detect_fast_cocoeval.py`` compares
them with pycocotools on edge cases and on the shared test sets), so everything that reads a ``COCOeval``
reads it unchanged. Boxes only (``iouType="bbox"``, ``useCats=1``).

The rules it reproduces, per (image, category): detections best first (stable sort by score) and only the
first ``maxDets[-1]`` kept; the IoU of a detection with a crowd box is its intersection over the detection's
own area; for each IoU threshold t and area range, detections in score order each take, among the boxes
not taken yet (crowd boxes are never used up) with IoU >= min(t, 1 - 1e-10), the one of highest IoU — a
non-ignored box before any ignored one (crowd, or its area outside the range), the later box on equal IoU;
a detection matched to an ignored box, or unmatched with its area outside the range, is ignored.
Accumulation: per category, area range and ``maxDets`` entry, detections of every image sorted by score
(stable, images in ``imgIds`` order), cumulative TP/FP, precision made monotone, read at ``recThrs``.

Matching is greedy, so it runs in rounds: round r takes, in every (image, category) at once, the r-th
detection that overlaps any box at all enough to be matched; the others cannot match and need no round.
"""

from __future__ import annotations

import copy
import datetime
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pycocotools.cocoeval import COCOeval

from ground.data.dataset import Dataset


@dataclass(frozen=True)
class CocoBoxes:
    """Ground truth or detections as arrays, one row per box: ``ids`` (N,) (>= 1), ``image_ids`` (N,),
    ``category_ids`` (N,), ``bbox`` (N, 4) ``[x, y, w, h]`` pixels, ``area`` (N,), ``score`` (N,) (detections;
    zeros for ground truth) and ``iscrowd`` (N,) bool (ground truth; False for detections)."""

    ids: NDArray[np.int64]
    image_ids: NDArray[np.int64]
    category_ids: NDArray[np.int64]
    bbox: NDArray[np.float64]
    area: NDArray[np.float64]
    score: NDArray[np.float64]
    iscrowd: NDArray[np.bool_]

    def __len__(self) -> int:
        return len(self.ids)

    def take(self, rows: NDArray[np.int64]) -> CocoBoxes:
        return CocoBoxes(*(getattr(self, f)[rows] for f in self.__dataclass_fields__))


def ground_truth_boxes(dataset: Dataset) -> CocoBoxes:
    """Every annotation of ``dataset`` in its order (``area`` as ``Dataset.to_coco`` writes it)."""
    anns = dataset.annotations
    bbox = np.asarray([a.bbox for a in anns], dtype=np.float64).reshape(-1, 4)
    return CocoBoxes(
        ids=np.asarray([a.id for a in anns], dtype=np.int64),
        image_ids=np.asarray([a.image_id for a in anns], dtype=np.int64),
        category_ids=np.asarray([a.category_id for a in anns], dtype=np.int64),
        bbox=bbox,
        area=np.asarray([a.area for a in anns], dtype=np.float64),
        score=np.zeros(len(anns)),
        iscrowd=np.asarray([bool(a.iscrowd) for a in anns], dtype=bool),
    )


def detection_boxes(
    image_ids: NDArray, category_ids: NDArray, bbox_xywh: NDArray, scores: NDArray, ids: NDArray | None = None
) -> CocoBoxes:
    """Detections from arrays; ``area`` = w * h and ``ids`` 1..N unless given (as ``run_cocoeval`` loads them)."""
    bbox = np.asarray(bbox_xywh, dtype=np.float64).reshape(-1, 4)
    n = len(bbox)
    return CocoBoxes(
        ids=np.arange(1, n + 1, dtype=np.int64) if ids is None else np.asarray(ids, dtype=np.int64),
        image_ids=np.asarray(image_ids, dtype=np.int64).reshape(n),
        category_ids=np.asarray(category_ids, dtype=np.int64).reshape(n),
        bbox=bbox,
        area=bbox[:, 2] * bbox[:, 3],
        score=np.asarray(scores, dtype=np.float64).reshape(n),
        iscrowd=np.zeros(n, dtype=bool),
    )


def records_to_boxes(records: Sequence[dict[str, Any]]) -> CocoBoxes:
    """COCO result records ``{image_id, category_id, bbox: [x, y, w, h], score}`` -> detections, ids 1..N."""
    return detection_boxes(
        np.fromiter((r["image_id"] for r in records), np.int64, len(records)),
        np.fromiter((r["category_id"] for r in records), np.int64, len(records)),
        np.asarray([r["bbox"] for r in records], dtype=np.float64),
        np.fromiter((r["score"] for r in records), np.float64, len(records)),
    )


def boxes_to_records(dt: CocoBoxes) -> list[dict[str, Any]]:
    """Detections -> COCO result records ``{image_id, category_id, bbox: [x, y, w, h], score}``, in row order."""
    return [
        {"image_id": i, "category_id": c, "bbox": b, "score": s}
        for i, c, b, s in zip(dt.image_ids.tolist(), dt.category_ids.tolist(), dt.bbox.tolist(), dt.score.tolist())
    ]


def pair_iou(dt: NDArray[np.float64], gt: NDArray[np.float64], crowd: NDArray[np.bool_]) -> NDArray[np.float64]:
    """IoU of (P, 4) xywh detection and ground-truth boxes pairwise row by row, as pycocotools computes it
    (same operations in the same order, so the same doubles); against a crowd box, intersection over the
    detection's area."""
    w = np.minimum(dt[:, 2] + dt[:, 0], gt[:, 2] + gt[:, 0]) - np.maximum(dt[:, 0], gt[:, 0])
    h = np.minimum(dt[:, 3] + dt[:, 1], gt[:, 3] + gt[:, 1]) - np.maximum(dt[:, 1], gt[:, 1])
    inter = w * h
    da, ga = dt[:, 2] * dt[:, 3], gt[:, 2] * gt[:, 3]
    union = np.where(crowd, da, da + ga - inter)
    with np.errstate(divide="ignore", invalid="ignore"):
        iou = inter / union
    return np.where((w > 0) & (h > 0), iou, 0.0)


@dataclass
class _Groups:
    """Boxes of the evaluated images and categories sorted by group g = k * I + i (k category index, i image
    index): ground truth in its order, detections best first, at most ``max_det`` per group."""

    gt: CocoBoxes
    gt_group: NDArray[np.int64]
    dt: CocoBoxes
    dt_group: NDArray[np.int64]
    dt_rank: NDArray[np.int64]  # position of each detection within its group, best first


def _group_boxes(gt: CocoBoxes, dt: CocoBoxes, img_ids: Sequence, cat_ids: Sequence, max_det: int) -> _Groups:
    imgs, cats = np.asarray(img_ids, dtype=np.int64), np.asarray(cat_ids, dtype=np.int64)

    def group_of(boxes: CocoBoxes) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        i = np.searchsorted(imgs, boxes.image_ids).clip(0, max(len(imgs) - 1, 0))
        k = np.searchsorted(cats, boxes.category_ids).clip(0, max(len(cats) - 1, 0))
        ok = (imgs[i] == boxes.image_ids) & (cats[k] == boxes.category_ids) if len(imgs) and len(cats) else i < 0
        rows = np.flatnonzero(ok)
        return rows, k[rows] * len(imgs) + i[rows]

    rows, group = group_of(gt)
    order = np.argsort(group, kind="stable")
    gt_sorted, gt_group = gt.take(rows[order]), group[order]
    rows, group = group_of(dt)
    order = np.lexsort((-dt.score[rows], group))  # stable: ties keep the records' order
    rows, group = rows[order], group[order]
    starts = np.searchsorted(group, group, side="left")
    rank = np.arange(len(group)) - starts
    keep = rank < max_det
    return _Groups(gt_sorted, gt_group, dt.take(rows[keep]), group[keep], rank[keep])


def _candidate_pairs(g: _Groups, min_iou: float) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """(detection row, ground-truth row, IoU) of every same-group pair with IoU >= ``min_iou``, sorted by
    detection then ground-truth row."""
    n_groups = int(max(g.gt_group.max(initial=-1), g.dt_group.max(initial=-1))) + 1
    gt_start = np.searchsorted(g.gt_group, np.arange(n_groups), side="left")
    gt_count = np.bincount(g.gt_group, minlength=n_groups)
    per_dt = gt_count[g.dt_group]
    d = np.repeat(np.arange(len(g.dt)), per_dt)
    offset = np.arange(len(d)) - np.repeat(np.cumsum(per_dt) - per_dt, per_dt)
    t = gt_start[g.dt_group][d] + offset
    iou = pair_iou(g.dt.bbox[d], g.gt.bbox[t], g.gt.iscrowd[t])
    ok = iou >= min_iou
    return d[ok], t[ok], iou[ok]


def _match(g: _Groups, iou_thrs: NDArray, gt_ignore: NDArray[np.bool_]) -> tuple[NDArray, NDArray]:
    """Greedy matching of every (area range, threshold): ``dt_gt`` (A, T, D) the matched ground-truth row or
    -1, ``gt_dt`` (A, T, G) the matching detection row or -1. ``gt_ignore`` (A, G)."""
    num_a, num_g, num_d, num_t = gt_ignore.shape[0], len(g.gt), len(g.dt), len(iou_thrs)
    dt_gt = np.full((num_a, num_t, num_d), -1, dtype=np.int64)
    gt_dt = np.full((num_a, num_t, num_g), -1, dtype=np.int64)
    thr = np.minimum(np.asarray(iou_thrs, dtype=np.float64), 1 - 1e-10)
    d, t, iou = _candidate_pairs(g, float(thr.min(initial=1.0)))
    if not len(d):
        return dt_gt, gt_dt
    # One row per detection with candidates, its candidates padded to C columns (ground-truth order).
    dets, first, count = np.unique(d, return_index=True, return_counts=True)
    col = np.arange(len(d)) - np.repeat(first, count)
    cand = np.full((len(dets), int(count.max())), num_g, dtype=np.int64)  # num_g: a padding column
    cand_iou = np.full(cand.shape, -np.inf)
    row = np.repeat(np.arange(len(dets)), count)
    cand[row, col], cand_iou[row, col] = t, iou
    # Round of each detection: its position among its group's detections with candidates.
    grp = g.dt_group[dets]
    rounds = np.arange(len(dets)) - np.searchsorted(grp, grp, side="left")
    ignore = np.concatenate([gt_ignore, np.ones((num_a, 1), dtype=bool)], axis=1)  # (A, G + 1)
    crowd = np.append(g.gt.iscrowd, False)
    taken = np.zeros((num_a, num_t, num_g + 1), dtype=bool)
    a_idx, t_idx = np.arange(num_a)[:, None, None], np.arange(num_t)[None, :, None]
    by_round = np.argsort(rounds, kind="stable")
    bounds = np.searchsorted(rounds[by_round], np.arange(int(rounds.max()) + 2))
    for r in range(len(bounds) - 1):
        rows = by_round[bounds[r] : bounds[r + 1]]
        c, ci = cand[rows], cand_iou[rows]  # (n, C)
        free = ~taken[:, :, c] | crowd[c]  # (A, T, n, C)
        ok = free & (ci >= thr[:, None, None])
        ign = ignore[:, c][:, None]  # (A, 1, n, C)
        ok &= ~(ign & (ok & ~ign).any(axis=-1, keepdims=True))  # a non-ignored box first
        best = np.where(ok, ci, -np.inf).max(axis=-1, keepdims=True)
        last = ok & (ci == best)
        pick = last.shape[-1] - 1 - np.argmax(last[..., ::-1], axis=-1)  # (A, T, n): the later on equal IoU
        hit = ok.any(axis=-1)
        chosen = np.where(hit, c[np.arange(len(rows))[None, None, :], pick], num_g)
        taken[a_idx, t_idx, chosen] = True
        taken[:, :, num_g] = False
        a_hit, t_hit, n_hit = np.nonzero(hit)
        det_rows = dets[rows]
        dt_gt[a_hit, t_hit, det_rows[n_hit]] = chosen[a_hit, t_hit, n_hit]
        gt_dt[a_hit, t_hit, chosen[a_hit, t_hit, n_hit]] = det_rows[n_hit]
    return dt_gt, gt_dt


def _accumulate_one(
    matched: NDArray[np.bool_], ignored: NDArray[np.bool_], scores: NDArray, npig: int, rec_thrs: NDArray
) -> tuple[NDArray, NDArray, NDArray]:
    """One (category, area, maxDets) cell: ``matched``/``ignored`` (T, D) and ``scores`` (D,) already best
    first -> precision (T, R), recall (T,), scores (T, R), as pycocotools' accumulate computes them."""
    tps, fps = matched & ~ignored, ~matched & ~ignored
    tp_sum = np.cumsum(tps, axis=1).astype(float)
    fp_sum = np.cumsum(fps, axis=1).astype(float)
    num_t, nd = matched.shape
    rc = tp_sum / npig
    pr = tp_sum / (fp_sum + tp_sum + np.spacing(1))
    recall = rc[:, -1] if nd else np.zeros(num_t)
    pr = np.maximum.accumulate(pr[:, ::-1], axis=1)[:, ::-1]  # monotone, as pycocotools' backward loop
    precision, score_at = np.zeros((num_t, len(rec_thrs))), np.zeros((num_t, len(rec_thrs)))
    for t in range(num_t):
        inds = np.searchsorted(rc[t], rec_thrs, side="left")
        inside = inds < nd
        precision[t, inside] = pr[t, inds[inside]]
        score_at[t, inside] = scores[inds[inside]]
    return precision, recall, score_at


class FastCOCOeval(COCOeval):
    """``COCOeval`` for boxes over :class:`CocoBoxes`: set ``params`` as for pycocotools, then ``evaluate()``,
    ``accumulate()``, ``summarize()`` (inherited). ``cocoGt``/``cocoDt`` are None; ``evalImgs`` is built on
    first read (pycocotools' list of dicts, K x A x I, None where an image has neither box nor detection)."""

    def __init__(self, gt: CocoBoxes, dt: CocoBoxes) -> None:
        super().__init__(None, None, "bbox")
        self.gt_boxes, self.dt_boxes = gt, dt
        self._groups: _Groups | None = None

    @property
    def evalImgs(self) -> Any:  # noqa: N802 - pycocotools' name
        if self._eval_imgs is None:
            self._eval_imgs = self._build_eval_imgs()
        return self._eval_imgs

    @evalImgs.setter
    def evalImgs(self, value: Any) -> None:  # noqa: N802
        self._eval_imgs = value

    def evaluate(self) -> None:
        p = self.params
        if p.iouType != "bbox" or not p.useCats:
            raise ValueError(f"FastCOCOeval evaluates boxes per category only, not iouType={p.iouType!r} useCats=0")
        p.imgIds, p.catIds, p.maxDets = list(np.unique(p.imgIds)), list(np.unique(p.catIds)), sorted(p.maxDets)
        g = _group_boxes(self.gt_boxes, self.dt_boxes, p.imgIds, p.catIds, p.maxDets[-1])
        area_rng = np.asarray(p.areaRng, dtype=np.float64)  # (A, 2)
        gt_out = (g.gt.area[None] < area_rng[:, :1]) | (g.gt.area[None] > area_rng[:, 1:])
        self._gt_ignore = g.gt.iscrowd[None] | gt_out  # (A, G)
        self._dt_gt, self._gt_dt = _match(g, p.iouThrs, self._gt_ignore)
        dt_out = (g.dt.area[None] < area_rng[:, :1]) | (g.dt.area[None] > area_rng[:, 1:])  # (A, D)
        dt_ignore = np.take_along_axis(
            np.concatenate([self._gt_ignore, np.zeros((len(area_rng), 1), bool)], axis=1),
            self._dt_gt.reshape(len(area_rng), -1),
            axis=1,
        ).reshape(self._dt_gt.shape)  # -1 reads the padding column: False
        self._dt_ignore = dt_ignore | ((self._dt_gt < 0) & dt_out[:, None, :])  # (A, T, D)
        self._groups = g
        self._eval_imgs = None
        self.eval = {}
        self._paramsEval = copy.deepcopy(p)

    def accumulate(self, p: Any = None) -> None:
        if self._groups is None:
            raise RuntimeError("run evaluate() first")
        p = self.params if p is None else p
        g, num_i = self._groups, len(p.imgIds)
        num_t, num_r, num_k, num_a, num_m = (
            len(p.iouThrs),
            len(p.recThrs),
            len(p.catIds),
            len(p.areaRng),
            len(p.maxDets),
        )
        precision = -np.ones((num_t, num_r, num_k, num_a, num_m))
        recall = -np.ones((num_t, num_k, num_a, num_m))
        scores = -np.ones((num_t, num_r, num_k, num_a, num_m))
        gt_k, dt_k = g.gt_group // max(num_i, 1), g.dt_group // max(num_i, 1)
        for k in range(num_k):
            rows = np.flatnonzero(dt_k == k)  # image order, best first within an image
            rows = rows[np.argsort(-g.dt.score[rows], kind="stable")]
            in_k = gt_k == k
            for a in range(num_a):
                npig = int(np.count_nonzero(~self._gt_ignore[a, in_k]))
                if npig == 0:
                    continue
                for m, max_det in enumerate(p.maxDets):
                    sel = rows[g.dt_rank[rows] < max_det]
                    matched, ignored = self._dt_gt[a][:, sel] >= 0, self._dt_ignore[a][:, sel]
                    pr, rc, ss = _accumulate_one(matched, ignored, g.dt.score[sel], npig, p.recThrs)
                    precision[:, :, k, a, m], recall[:, k, a, m], scores[:, :, k, a, m] = pr, rc, ss
        self.eval = {
            "params": p,
            "counts": [num_t, num_r, num_k, num_a, num_m],
            "date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M:%S"),
            "precision": precision,
            "recall": recall,
            "scores": scores,
        }

    def _build_eval_imgs(self) -> list[dict[str, Any] | None]:
        """pycocotools' per (category, area, image) results from the arrays (ids for matches, ground truth
        with the area's ignored boxes last)."""
        g = self._groups
        if g is None:
            return []
        p = self.params
        num_i, num_a = len(p.imgIds), len(p.areaRng)
        n_groups = len(p.catIds) * num_i
        gt_bounds = np.searchsorted(g.gt_group, np.arange(n_groups + 1))
        dt_bounds = np.searchsorted(g.dt_group, np.arange(n_groups + 1))
        gt_id_of = np.append(g.gt.ids, 0).astype(np.float64)  # -1 (unmatched) reads 0
        dt_id_of = np.append(g.dt.ids, 0).astype(np.float64)
        out: list[dict[str, Any] | None] = [None] * (n_groups * num_a)
        for grp in np.flatnonzero((gt_bounds[1:] > gt_bounds[:-1]) | (dt_bounds[1:] > dt_bounds[:-1])):
            k, i = divmod(int(grp), num_i)
            gs, ds = slice(gt_bounds[grp], gt_bounds[grp + 1]), slice(dt_bounds[grp], dt_bounds[grp + 1])
            for a in range(num_a):
                gt_ig = self._gt_ignore[a, gs]
                order = np.argsort(gt_ig, kind="stable")
                out[(k * num_a + a) * num_i + i] = {
                    "image_id": p.imgIds[i],
                    "category_id": p.catIds[k],
                    "aRng": p.areaRng[a],
                    "maxDet": p.maxDets[-1],
                    "dtIds": g.dt.ids[ds].tolist(),
                    "gtIds": g.gt.ids[gs][order].tolist(),
                    "dtMatches": gt_id_of[self._dt_gt[a][:, ds]],
                    "gtMatches": dt_id_of[self._gt_dt[a][:, gs][:, order]],
                    "dtScores": g.dt.score[ds].tolist(),
                    "gtIgnore": gt_ig[order].astype(int),
                    "dtIgnore": self._dt_ignore[a][:, ds],
                }
        return out

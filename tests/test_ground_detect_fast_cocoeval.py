"""The vectorised COCO evaluation equals pycocotools' COCOeval: per-image matches, accumulated precision,
recall and scores, and every reported metric, on generated edge cases and on the shared test sets."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pytest
from factories_coco import reference
from pycocotools.cocoeval import COCOeval

from ground.data.dataset import DatasetBuilder
from ground.detect.cocoeval import LOOSE_IOU, run_cocoeval
from ground.detect.fast_cocoeval import FastCOCOeval, ground_truth_boxes, pair_iou, records_to_boxes

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"


def assert_same(ours: COCOeval, ref: COCOeval, tol: float = 1e-6) -> None:
    """Every reported number within ``tol`` (in practice equal) and the per-image matches identical."""
    np.testing.assert_allclose(ours.stats, ref.stats, rtol=0, atol=tol)
    for key in ("precision", "recall", "scores"):
        np.testing.assert_allclose(ours.eval[key], ref.eval[key], rtol=0, atol=tol, err_msg=key)
    assert len(ours.evalImgs) == len(ref.evalImgs)
    for i, (a, b) in enumerate(zip(ours.evalImgs, ref.evalImgs)):
        assert (a is None) == (b is None), i
        if a is None:
            continue
        assert (a["image_id"], a["category_id"], a["aRng"], a["maxDet"]) == (
            b["image_id"],
            b["category_id"],
            b["aRng"],
            b["maxDet"],
        ), i
        for key in ("dtIds", "gtIds", "dtScores"):
            assert list(a[key]) == list(b[key]), (i, key)
        for key in ("dtMatches", "gtMatches", "gtIgnore", "dtIgnore"):
            np.testing.assert_array_equal(np.asarray(a[key]), np.asarray(b[key]), err_msg=f"{i} {key}")


def edge_case_set(tmp_path, seed: int = 0):
    """Three classes; images with many boxes, one box, only a crowd box, none (negatives); boxes of every COCO
    size; detections with tied scores, duplicates, boxes across area ranges, more than 100 on an image, detections
    on negatives, for an unscored class and for an image not in the set; one image without detections."""
    rng = np.random.default_rng(seed)
    b = DatasetBuilder(tmp_path, ["fire", "smoke", "person"])
    records = []
    gt_boxes = []
    for n in range(14):
        image_id = b.add_image(f"{n}.jpg", 640, 480)
        kind = n % 7
        boxes = []
        if kind in (0, 1, 2):  # several boxes of every size, some overlapping each other
            for _ in range(int(rng.integers(2, 9))):
                size = float(rng.choice([12.0, 20.0, 31.9, 32.0, 50.0, 95.9, 96.0, 150.0, 300.0]))
                wh = np.array([size, size * rng.uniform(0.6, 1.4)])
                boxes.append((*rng.uniform(0, 300, 2).round(1), *wh.round(1)))
        elif kind == 3:
            boxes.append((100.0, 100.0, 40.0, 40.0))
        for box in boxes:
            cls = ("fire", "smoke", "person")[int(rng.integers(0, 3))]
            b.add_box(image_id, cls, box, iscrowd=int(rng.random() < 0.12))
            gt_boxes.append((image_id, 1 + ("fire", "smoke", "person").index(cls), box))
        if kind == 4:
            b.add_box(image_id, "fire", (0.0, 0.0, 320.0, 240.0), iscrowd=1)
            gt_boxes.append((image_id, 1, (0.0, 0.0, 320.0, 240.0)))
        if kind == 6:
            continue  # no detections here (a negative or not)
        clutter = 130 if n == 0 else int(rng.integers(0, 25))
        for _ in range(clutter):
            box = [*rng.uniform(0, 560, 2).round(1), *rng.uniform(4, 160, 2).round(1)]
            score = float(rng.choice([0.5, 0.25, 0.125, round(float(rng.random()), 2)]))
            records.append({"image_id": image_id, "category_id": int(rng.integers(1, 4)), "bbox": box, "score": score})
    for image_id, cat, (x, y, w, h) in gt_boxes:  # near-hits: jittered copies, some duplicated, tied scores
        for _ in range(int(rng.integers(0, 4))):
            jitter = [x + rng.normal(0, 0.15 * w), y + rng.normal(0, 0.15 * h), w * rng.uniform(0.6, 1.5), h]
            score = float(rng.choice([0.9, 0.7, round(float(rng.random()), 3)]))
            records.append(
                {"image_id": image_id, "category_id": cat, "bbox": [round(v, 2) for v in jitter], "score": score}
            )
    records.append({"image_id": 999, "category_id": 1, "bbox": [0, 0, 10, 10], "score": 0.99})  # not in the set
    records.append({"image_id": 1, "category_id": 7, "bbox": [0, 0, 10, 10], "score": 0.99})  # not a class
    order = rng.permutation(len(records))
    return b.build(), [records[i] for i in order]


def fast(ds, records, cat_ids, iou_thresholds=None) -> FastCOCOeval:
    ev = FastCOCOeval(ground_truth_boxes(ds), records_to_boxes(records))
    ev.params.imgIds = sorted(img.id for img in ds.images)
    ev.params.catIds = sorted(cat_ids)
    if iou_thresholds is not None:
        ev.params.iouThrs = np.asarray(iou_thresholds, dtype=np.float64)
    with contextlib.redirect_stdout(io.StringIO()):
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    return ev


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("iou_thresholds", [None, [LOOSE_IOU], [0.0, 0.5, 1.0]])
def test_parity_with_pycocotools_on_edge_cases(tmp_path, seed, iou_thresholds):
    ds, records = edge_case_set(tmp_path, seed)
    assert any(a.iscrowd for a in ds.annotations)
    ref = reference(ds, records, [1, 2, 3], iou_thresholds)
    ours = fast(ds, records, [1, 2, 3], iou_thresholds)
    assert_same(ours, ref)
    assert ref.stats[0] > 0  # the cases match something: the comparison is not of empty results


def test_parity_on_a_subset_of_classes_and_images(tmp_path):
    ds, records = edge_case_set(tmp_path, 5)
    part = ds.filter_images(lambda img: img.id % 2 == 0)
    assert_same(fast(part, records, [2, 3]), reference(part, records, [2, 3]))


def test_parity_without_detections_and_without_ground_truth(tmp_path):
    ds, records = edge_case_set(tmp_path, 6)
    assert_same(fast(ds, [], [1, 2]), reference(ds, [], [1, 2]))
    b = DatasetBuilder(tmp_path, ["fire"])
    for _ in range(3):
        b.add_image("neg.jpg", 100, 100)
    negatives = b.build()
    dets = [{"image_id": 1, "category_id": 1, "bbox": [1, 1, 5, 5], "score": 0.3}]
    ours, ref = fast(negatives, dets, [1]), reference(negatives, dets, [1])
    assert_same(ours, ref)
    assert ours.stats[0] == -1  # undefined without ground truth


def test_a_perfect_detector_scores_1_and_a_shifted_one_less(tmp_path):
    ds, _ = edge_case_set(tmp_path, 7)
    perfect = [
        {"image_id": a.image_id, "category_id": a.category_id, "bbox": list(a.bbox), "score": 0.5}
        for a in ds.annotations
        if not a.iscrowd
    ]
    assert fast(ds, perfect, [1, 2, 3]).stats[0] == pytest.approx(1.0)
    shifted = [{**r, "bbox": [r["bbox"][0] + 0.3 * r["bbox"][2], *r["bbox"][1:]]} for r in perfect]
    ours, ref = fast(ds, shifted, [1, 2, 3]), reference(ds, shifted, [1, 2, 3])
    assert_same(ours, ref)
    assert 0 < ours.stats[0] < 0.9


def test_pair_iou_of_crowd_boxes_is_over_the_detection():
    dt = np.array([[0.0, 0.0, 10.0, 10.0], [0.0, 0.0, 10.0, 10.0], [20.0, 20.0, 5.0, 5.0]])
    gt = np.array([[0.0, 0.0, 20.0, 20.0], [0.0, 0.0, 20.0, 20.0], [0.0, 0.0, 10.0, 10.0]])
    np.testing.assert_allclose(pair_iou(dt, gt, np.array([False, True, False])), [0.25, 1.0, 0.0])


def test_run_cocoeval_is_the_fast_evaluation(tmp_path):
    ds, records = edge_case_set(tmp_path, 8)
    ev = run_cocoeval(ds, records, [1, 2, 3])
    assert isinstance(ev, FastCOCOeval)
    assert_same(ev, reference(ds, records, [1, 2, 3]))


@pytest.mark.shared_data
@pytest.mark.skipif(not (SHARED / "fire-smoke-608").is_dir(), reason="../shared/data/fire-smoke-608 absent")
def test_parity_on_fire_smoke_608_with_many_low_confidence_detections():
    """The shared test set's ground truth against noisy detections: copies of its boxes, jittered, and up to 150
    low-score boxes per image (a weakly trained model at conf 0.001)."""
    from ground.data.formats.registry import read_dataset

    ds = read_dataset(SHARED / "fire-smoke-608").dataset
    rng = np.random.default_rng(0)
    records = []
    for a in ds.annotations:
        x, y, w, h = a.bbox
        for _ in range(int(rng.integers(0, 3))):
            box = [x + rng.normal(0, 0.1 * w), y + rng.normal(0, 0.1 * h), w * rng.uniform(0.7, 1.3), h]
            records.append({"image_id": a.image_id, "category_id": a.category_id, "bbox": box, "score": rng.random()})
    cats = [c.id for c in ds.categories]
    for img in ds.images:
        for _ in range(int(rng.integers(0, 150))):
            box = [*rng.uniform(0, 560, 2), *rng.uniform(4, 200, 2)]
            score = round(float(0.05 * rng.random()), 3)  # many ties
            records.append({"image_id": img.id, "category_id": int(rng.choice(cats)), "bbox": box, "score": score})
    for thresholds in (None, [LOOSE_IOU]):
        ours, ref = fast(ds, records, cats, thresholds), reference(ds, records, cats, thresholds)
        assert_same(ours, ref)
        assert ref.stats[0] > 0.05

"""COCO metrics: class matching by name, negatives, empty detections, per-class numbers."""

from __future__ import annotations

import numpy as np
import pytest

from ground.data.dataset import DatasetBuilder
from ground.detect.cocoeval import ClassMatchError, match_classes, run_cocoeval
from ground.detect.cocoeval import evaluate_predictions as evaluate
from ground.detect.detections import ImageDetections, Predictions


def make_dataset(tmp_path):
    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    a = b.add_image("a.jpg", 100, 100)
    b.add_box(a, "fire", (10, 10, 20, 20))
    b.add_box(a, "smoke", (50, 50, 40, 40))
    c = b.add_image("b.jpg", 100, 100)
    b.add_box(c, "fire", (0, 0, 60, 60))
    b.add_image("neg.jpg", 100, 100)
    return b.build()


def dets(rows):
    """rows: (xyxy, score, label) -> ImageDetections."""
    if not rows:
        return ImageDetections(np.zeros((0, 4)), np.zeros(0), np.zeros(0, np.int64))
    return ImageDetections(
        np.array([r[0] for r in rows], float), np.array([r[1] for r in rows]), np.array([r[2] for r in rows])
    )


def perfect(fire: int = 0, smoke: int = 1):
    """The ground truth as detections, with the model's class indices of fire and smoke."""
    return {
        1: dets([([10, 10, 30, 30], 0.9, fire), ([50, 50, 90, 90], 0.8, smoke)]),
        2: dets([([0, 0, 60, 60], 0.7, fire)]),
        3: dets([]),
    }


def test_ground_truth_gives_ap_1_including_negatives(tmp_path):
    m, _, records = evaluate(make_dataset(tmp_path), Predictions(("fire", "smoke"), perfect(), []))
    assert m.summary["AP"] == pytest.approx(1.0) and m.images == 3 and m.boxes == 3 and len(records) == 3
    assert m.per_class["smoke"] == {
        "AP": pytest.approx(1.0),
        "AP50": pytest.approx(1.0),
        "AP25": pytest.approx(1.0),
        "boxes": 1,
    }
    assert m.summary["AP25"] == pytest.approx(1.0)


def test_ap25_counts_a_fire_found_with_a_loose_box(tmp_path):
    """A box of IoU 0.36 with the ground truth is a miss at 0.5 and a hit at 0.25 (fire and smoke have no crisp
    edge; test sets draw them differently)."""
    by_image = perfect()
    by_image[2] = dets([([0, 0, 36, 60], 0.7, 0)])  # the 60 x 60 fire boxed 36 x 60: IoU 0.6 -> still a hit
    by_image[1] = dets([([10, 10, 30, 30], 0.9, 0), ([50, 50, 74, 74], 0.8, 1)])  # smoke 40 x 40 boxed 24 x 24
    m, _, _ = evaluate(make_dataset(tmp_path), Predictions(("fire", "smoke"), by_image, []))
    assert m.per_class["smoke"]["AP50"] == 0.0 and m.per_class["smoke"]["AP25"] == pytest.approx(1.0)
    assert m.per_class["fire"]["AP50"] == pytest.approx(1.0) and m.summary["AP25"] == pytest.approx(1.0)


def test_false_positive_on_a_negative_ranked_first_costs_ap(tmp_path):
    by_image = perfect()
    by_image[3] = dets([([5, 5, 50, 50], 0.95, 0)])
    m, _, _ = evaluate(make_dataset(tmp_path), Predictions(("fire", "smoke"), by_image, []))
    assert m.per_class["fire"]["AP"] < 0.99 and m.per_class["smoke"]["AP"] == pytest.approx(1.0)


def test_empty_detections_give_zero_not_an_error(tmp_path):
    empty = {i: dets([]) for i in (1, 2, 3)}
    m, _, records = evaluate(make_dataset(tmp_path), Predictions(("fire", "smoke"), empty, []))
    assert records == [] and m.summary["AP"] == 0.0 and m.per_class["fire"]["AP"] == 0.0
    ev = run_cocoeval(make_dataset(tmp_path), [], [1])
    assert ev.stats[0] == 0.0


def test_classes_matched_by_name_not_index(tmp_path):
    ds = make_dataset(tmp_path)
    names = ("Smoke", "background", "Flame")  # other order, case, a synonym, an extra class
    match = match_classes(names, ds)
    assert match.label_to_cat == {0: 2, 2: 1} and match.not_in_test == ("background",)
    m, _, _ = evaluate(ds, Predictions(names, perfect(fire=2, smoke=0), []))
    assert m.summary["AP"] == pytest.approx(1.0)


def test_test_classes_the_model_lacks_are_not_scored(tmp_path):
    ds = make_dataset(tmp_path)
    by_image = {1: dets([([10, 10, 30, 30], 0.9, 0)]), 2: dets([([0, 0, 60, 60], 0.7, 0)]), 3: dets([])}
    m, _, _ = evaluate(ds, Predictions(("fire",), by_image, []))
    assert m.summary["AP"] == pytest.approx(1.0) and list(m.per_class) == ["fire"] and m.boxes == 2
    assert m.extra["classes"]["not_in_model"] == ["smoke"]
    with pytest.raises(ClassMatchError, match="no class in common"):
        match_classes(["person"], ds)


def test_records_cocoeval_never_reads_are_left_out_with_identical_results(tmp_path):
    from factories_coco import reference

    from ground.detect.cocoeval import top_records

    rng = np.random.default_rng(0)
    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    records = []
    for _ in range(6):
        image_id = b.add_image("x.jpg", 200, 200)
        for _ in range(3):
            b.add_box(image_id, "fire", (*rng.uniform(0, 120, 2), *rng.uniform(5, 80, 2)))
        for _ in range(260):  # 130 per class on average: more than the 100 COCOeval reads
            box = [*np.round(rng.uniform(0, 150, 2), 1), *np.round(rng.uniform(2, 80, 2), 1)]
            score = float(rng.choice([0.5, 0.25, rng.uniform()]))  # many ties
            records.append({"image_id": image_id, "category_id": int(rng.integers(1, 3)), "bbox": box, "score": score})
    ds = b.build()
    kept = top_records(records, 100)
    assert len(kept) < len(records) and all(r in records for r in kept)
    ours = run_cocoeval(ds, records, [1, 2])
    ref = reference(ds, records, [1, 2])
    np.testing.assert_array_equal(ours.stats, ref.stats)
    np.testing.assert_array_equal(ours.eval["precision"], ref.eval["precision"])

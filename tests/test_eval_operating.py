"""The operating curve on planted detections: boxes found by COCO's matching (duplicates, misses, the other class
and crowd boxes as pycocotools counts them; recall at the lowest threshold is COCO's recall at IoU 0.5), the
threshold at an alarm budget (ties, no alarm, a budget under one alarm), and the curve's monotone steps."""

from __future__ import annotations

import numpy as np
import pytest
from factories import planted_dataset

from eval.operating import (
    Alarms,
    FoundScores,
    alarms_of,
    found_scores,
    operating_curve,
    operating_point,
    paired_recall_bootstrap,
    pooled,
    recall_at_rates,
)
from ground.data.dataset import DatasetBuilder
from ground.detect.cocoeval import run_cocoeval

FIRE, SMOKE = 1, 2


def _rec(image_id: int, cat: int, box: tuple[float, ...], score: float) -> dict:
    return {"image_id": image_id, "category_id": cat, "bbox": list(box), "score": score}


def test_found_boxes_follow_cocos_matching(tmp_path) -> None:
    ds = planted_dataset(
        tmp_path,
        [
            [(FIRE, (10, 10, 20, 20)), (FIRE, (50, 50, 20, 20))],  # 1: both found
            [(FIRE, (10, 10, 20, 20))],  # 2: found twice (the duplicate finds nothing more)
            [(FIRE, (0, 0, 20, 20))],  # 3: half-shifted (IoU 1/3): not found
            [(SMOKE, (10, 10, 20, 20))],  # 4: a smoke box, found by a fire detection: not a fire box found
            [],  # 5: no box
        ],
    )
    records = [
        _rec(1, FIRE, (10, 10, 20, 20), 0.9),
        _rec(1, FIRE, (52, 50, 20, 20), 0.4),
        _rec(2, FIRE, (10, 10, 20, 20), 0.7),
        _rec(2, FIRE, (11, 10, 20, 20), 0.8),  # higher: it takes the box, 0.7 is the duplicate
        _rec(3, FIRE, (10, 0, 20, 20), 0.95),
        _rec(4, FIRE, (10, 10, 20, 20), 0.6),
        _rec(5, FIRE, (10, 10, 5, 5), 0.5),
    ]
    found = found_scores(ds, records, [FIRE])
    assert found.boxes == 4 and found.scores.tolist() == [0.9, 0.8, 0.4]
    assert found.recall(0.0) == pytest.approx(run_cocoeval(ds, records, [FIRE], [0.5]).eval["recall"][0, 0, 0, -1])
    assert found.recall(0.85) == 0.25 and found.recall(0.8) == 0.5 and found.recall(0.99) == 0.0
    both = found_scores(ds, records, [FIRE, SMOKE])
    assert both.boxes == 5 and both.scores.tolist() == [0.9, 0.8, 0.4]  # the smoke box: no smoke detection


def test_a_crowd_box_is_not_a_box_to_find(tmp_path) -> None:
    builder = DatasetBuilder(tmp_path, ["fire"])
    for k, crowd in enumerate((0, 1)):
        builder.add_box(builder.add_image(f"{k}.jpg", 100, 100, "real:x", "test"), "fire", (10, 10, 20, 20), crowd)
    records = [_rec(1, FIRE, (10, 10, 20, 20), 0.9), _rec(2, FIRE, (10, 10, 20, 20), 0.8)]
    found = found_scores(builder.build({}), records, [FIRE])
    assert found.boxes == 1 and found.scores.tolist() == [0.9]


def _found(scores: list[float], boxes: int) -> FoundScores:
    """Found boxes one per image (``boxes`` images, the first ``len(scores)`` found)."""
    return FoundScores(np.array(scores), np.arange(len(scores)), np.ones(boxes, dtype=np.int64))


def _alarms(scores: list[float], images: int) -> Alarms:
    return alarms_of([{"image_id": k % images + 1, "score": s} for k, s in enumerate(scores)], range(1, images + 1))


def test_the_budget_sets_the_lowest_threshold_with_at_most_that_many_alarms() -> None:
    found = _found([0.9, 0.6, 0.5, 0.2], 8)
    alarms = _alarms([0.3, 0.7, 0.55, 0.55, 0.1], 20)
    assert alarms.scores.tolist() == [0.7, 0.55, 0.55, 0.3, 0.1] and alarms.image.tolist() == [1, 2, 3, 0, 4]
    # 20 images, 10 per 100: two alarms allowed; the second and third tie at 0.55, so only 0.7 stays
    point = operating_point(found, alarms, 10.0)
    assert 0.55 < point.threshold < 0.56 and point.alarms_per_100 == 5.0 and point.recall == pytest.approx(2 / 8)
    # 15 per 100: three allowed; the threshold lies just above the fourth alarm (0.3)
    point = operating_point(found, alarms, 15.0)
    assert 0.3 < point.threshold < 0.31 and point.alarms_per_100 == 15.0 and point.recall == pytest.approx(3 / 8)
    # every alarm within the budget: threshold 0, every kept detection
    assert operating_point(found, alarms, 25.0) == operating_point(found, alarms, 1e6)
    assert operating_point(found, alarms, 25.0).threshold == 0.0 and operating_point(found, alarms, 25.0).recall == 0.5
    # less than one alarm allowed: above the best alarm
    point = operating_point(found, alarms, 4.9)
    assert point.threshold > 0.7 and point.alarms_per_100 == 0.0 and point.recall == pytest.approx(1 / 8)
    assert operating_point(found, _alarms([], 5), 0.0).threshold == 0.0
    with pytest.raises(ValueError, match="at least one image"):
        operating_point(found, _alarms([], 0))
    with pytest.raises(ValueError, match=">= 0"):
        operating_point(found, alarms, -1.0)
    with pytest.raises(ValueError, match="image 9"):
        alarms_of([{"image_id": 9, "score": 0.5}], [1, 2])


def test_weights_count_an_image_as_often_as_it_is_drawn() -> None:
    found = FoundScores(np.array([0.9, 0.8, 0.4]), np.array([0, 1, 1]), np.array([1, 2, 1]))
    alarms = alarms_of([{"image_id": i, "score": s} for i, s in ((1, 0.7), (2, 0.6), (2, 0.5))], [1, 2, 3, 4])
    ones = np.ones(4)
    assert alarms.threshold(50.0, ones) == alarms.threshold(50.0) and found.recall(0.5, np.ones(3)) == found.recall(0.5)
    # image 2 (alarms 0.6, 0.5) drawn twice, image 1 not: 4 draws allow 2 alarms -> just above 0.5 (0.6 twice)
    assert 0.5 < alarms.threshold(50.0, np.array([0, 2, 1, 1])) < 0.51
    # the same as the images written out twice
    twice = alarms_of([{"image_id": i, "score": s} for i, s in ((2, 0.6), (2, 0.5), (5, 0.6), (5, 0.5))], [2, 5, 3, 4])
    assert alarms.threshold(50.0, np.array([0, 2, 1, 1])) == twice.threshold(50.0)
    # image 1 (two boxes, found at 0.8 and 0.4) drawn three times, image 0 not: 6 of the 7 boxes drawn found
    assert found.recall(0.4, np.array([0, 3, 1])) == pytest.approx(6 / 7)
    assert found.recall(0.85, np.array([0, 3, 1])) == 0.0


def test_pooled_sets_keep_their_images_apart() -> None:
    a, b = _alarms([0.9, 0.2], 2), _alarms([0.5], 3)
    both = pooled([a, b])
    assert both.images == 5 and both.scores.tolist() == [0.9, 0.5, 0.2] and both.image.tolist() == [0, 2, 1]
    with pytest.raises(ValueError, match="no set"):
        pooled([])


def test_the_point_lies_on_the_curve_and_the_curve_rises() -> None:
    rng = np.random.default_rng(0)
    found = _found(np.sort(rng.uniform(0, 1, 40))[::-1].tolist(), 60)
    alarms = _alarms(rng.uniform(0, 1, 30).tolist(), 50)
    rate, recall = operating_curve(found, alarms)
    assert np.all(np.diff(rate) >= 0) and np.all(np.diff(recall) >= 0)
    assert rate[-1] == 60.0 and recall[-1] == pytest.approx(40 / 60)
    for budget in (0.0, 5.0, 10.0, 33.0, 100.0):
        point = operating_point(found, alarms, budget)
        within = rate <= budget
        best = recall[within].max() if within.any() else 0.0
        assert point.alarms_per_100 <= budget and point.recall == pytest.approx(best)
    budgets = np.array([0.0, 1.9, 2.0, 5.0, 10.0, 33.0, 100.0])
    expected = [operating_point(found, alarms, b).recall for b in budgets]
    assert recall_at_rates(found, alarms, budgets).tolist() == pytest.approx(expected)
    top = _alarms([1.0], 50)  # the best score is an alarm: nothing is found within half an alarm per 100
    assert recall_at_rates(found, top, np.array([0.5, 2.0])).tolist() == [0.0, pytest.approx(40 / 60)]


def test_the_paired_bootstrap_brackets_the_difference_and_is_deterministic() -> None:
    rng = np.random.default_rng(1)
    alarms = _alarms(rng.uniform(0, 0.5, 40).tolist(), 60)
    weak = (_found(np.sort(rng.uniform(0, 1, 30))[::-1].tolist(), 100), alarms)
    strong = (_found(np.sort(rng.uniform(0.5, 1, 70))[::-1].tolist(), 100), alarms)
    d = paired_recall_bootstrap([weak], [strong], np.random.default_rng(0), 300)
    point = operating_point(*strong).recall - operating_point(*weak).recall
    assert d.interval.point == pytest.approx(point) and d.interval.low < point < d.interval.high
    assert d.interval.low > 0 and d.p_value < 0.01
    again = paired_recall_bootstrap([weak], [strong], np.random.default_rng(0), 300)
    assert again.to_dict() == d.to_dict() and np.array_equal(again.interval.samples, d.interval.samples)
    same = paired_recall_bootstrap([weak, strong], [weak, strong], np.random.default_rng(0), 50)
    assert same.interval.point == 0 and same.interval.low == same.interval.high == 0 and same.p_value == 1.0
    three = paired_recall_bootstrap([weak] * 3, [weak, strong, weak], np.random.default_rng(0), 300, seeds=True)
    fixed = paired_recall_bootstrap([weak] * 3, [weak, strong, weak], np.random.default_rng(0), 300)
    assert three.resampled == "images and seeds" and fixed.resampled == "images"
    assert three.interval.point == pytest.approx(fixed.interval.point) and fixed.interval.low > 0
    assert three.interval.low == 0  # (2/3)^3 of the resamples draw no strong seed: another training may not gain
    with pytest.raises(ValueError, match="same images"):
        paired_recall_bootstrap([weak], [(strong[0], _alarms([0.1], 10))], np.random.default_rng(0), 10)
    with pytest.raises(ValueError, match="at least one run"):
        paired_recall_bootstrap([], [weak], np.random.default_rng(0), 10)

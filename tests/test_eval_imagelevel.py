"""Image-level detection: the hit rule (IoU >= 0.1 or the detection's centre inside), per-image alarms, the curve
and the paired bootstrap."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from eval.imagelevel import (
    ImageHits,
    image_alarms,
    image_hits,
    image_level,
    image_operating_curve,
    paired_image_recall,
)
from eval.operating import Alarms, alarms_of
from ground.data.dataset import DatasetBuilder


def _set(tmp_path: Path):
    b = DatasetBuilder(tmp_path, ["fire"])
    big = b.add_image("region.jpg", 400, 400)
    b.add_box(big, "fire", [0, 0, 400, 400])  # a whole burning region
    small = b.add_image("flame.jpg", 400, 400)
    b.add_box(small, "fire", [100, 100, 20, 20])
    miss = b.add_image("missed.jpg", 400, 400)
    b.add_box(miss, "fire", [300, 300, 40, 40])
    b.add_image("free.jpg", 400, 400)
    return b.build(), (big, small, miss)


def _det(image: int, box: list[float], score: float) -> dict:
    return {"image_id": image, "category_id": 1, "bbox": box, "score": score}


def test_a_hit_by_overlap_or_by_centre_and_a_miss_far_away(tmp_path: Path) -> None:
    ds, (big, small, miss) = _set(tmp_path)
    records = [
        _det(big, [190, 190, 20, 20], 0.9),  # one flame inside the region: IoU 0.0025, centre inside -> hit
        _det(small, [95, 95, 60, 60], 0.6),  # a loose box round the flame: IoU 0.11 -> hit
        _det(small, [105, 105, 10, 10], 0.7),  # centre inside -> hit, the better score
        _det(miss, [0, 0, 30, 30], 0.95),  # elsewhere: no hit
    ]
    hits = image_hits(ds, records, [1])
    assert hits.fire.tolist() == [True, True, True, False]
    assert hits.best[:2].tolist() == [0.9, 0.7] and hits.best[2:].tolist() == [-np.inf, -np.inf]
    assert hits.recall(0.5) == pytest.approx(2 / 3) and hits.recall(0.8) == pytest.approx(1 / 3)
    assert hits.recall(0.5, np.array([0, 1, 1, 1])) == pytest.approx(1 / 2)  # a slice: the flame and the miss


def test_alarms_count_images_not_detections() -> None:
    records = [_det(7, [0, 0, 5, 5], s) for s in (0.9, 0.8, 0.3)] + [_det(8, [0, 0, 5, 5], 0.5)]
    alarms = image_alarms(alarms_of(records, [7, 8, 9]))
    assert alarms.scores.tolist() == [0.9, 0.5] and alarms.images == 3
    assert alarms.per_100(0.4) == pytest.approx(200 / 3)


def test_the_curve_rises_to_every_detected_image() -> None:
    hits = ImageHits(np.arange(4), np.array([True, True, True, False]), np.array([0.9, 0.4, -np.inf, -np.inf]))
    alarms = Alarms(np.array([0.6, 0.2]), np.array([0, 1]), 2)
    rate, recall = image_operating_curve(hits, alarms)
    assert rate.tolist() == [0.0, 50.0, 50.0, 100.0] and recall.tolist() == pytest.approx([1 / 3, 1 / 3, 2 / 3, 2 / 3])


def test_paired_recall_of_a_model_against_itself_is_zero_and_a_better_one_positive() -> None:
    rng = np.random.default_rng(0)
    fire = np.ones(40, dtype=bool)
    weak = ImageHits(np.arange(40), fire, np.where(np.arange(40) < 10, 0.9, -np.inf))
    strong = ImageHits(np.arange(40), fire, np.where(np.arange(40) < 30, 0.9, -np.inf))
    alarms = Alarms(np.array([0.95]), np.array([0]), 20)  # 5 per 100: within the budget at threshold 0
    same = paired_image_recall([(weak, alarms)], [(weak, alarms)], rng, 200)
    assert same.interval.point == 0 and same.interval.low == same.interval.high == 0
    better = paired_image_recall([(weak, alarms)], [(strong, 0.5)], rng, 200)
    assert better.interval.point == pytest.approx(0.5) and better.interval.low > 0.25 and better.p_value < 0.01
    half = paired_image_recall([(weak, 0.5)], [(strong, 0.5)], rng, 200, mask=np.arange(40) < 20)
    assert half.interval.point == pytest.approx(0.5)  # images 0..19: 10 of 20 against all 20
    with pytest.raises(ValueError, match="same images"):
        paired_image_recall([(weak, 0.5)], [(ImageHits(np.arange(3), fire[:3], weak.best[:3]), 0.5)], rng, 10)


def _photos(tmp_path: Path):
    """Four photos labelled fire at the image level (no boxes) and two without fire."""
    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    fires = [b.add_image(f"fire{i}.jpg", 100, 100, labels=("fire",)) for i in range(4)]
    free = [b.add_image(f"free{i}.jpg", 100, 100) for i in range(2)]
    return b.build(), fires, free


def test_an_image_labelled_photo_is_detected_by_any_detection_of_its_class(tmp_path: Path) -> None:
    ds, fires, free = _photos(tmp_path)
    records = [_det(fires[0], [0, 0, 5, 5], 0.9), _det(fires[1], [50, 50, 5, 5], 0.3),
               {**_det(fires[2], [0, 0, 5, 5], 0.95), "category_id": 2}, _det(free[0], [1, 1, 5, 5], 0.6)]  # fmt: skip
    hits = image_hits(ds, records, [1])
    assert hits.fire.tolist() == [True] * 4 + [False] * 2
    assert hits.best[:4].tolist() == [0.9, 0.3, -np.inf, -np.inf]  # a smoke detection does not find fire
    assert hits.recall(0.25) == 0.5
    level = image_level(ds, records, [1], 0.25, 50.0)
    assert (level.fire_images, level.recall_at_conf, level.free_images, level.alarm_share_at_conf) == (4, 0.5, 2, 0.5)
    assert level.budget_recall == 0.5 and level.budget_threshold == 0.0  # one of two free images allowed
    strict = image_level(ds, records, [1], 0.25, 10.0)  # no alarm allowed: read above the free photo's 0.6
    assert strict.budget_recall == 0.25 and strict.budget_threshold > 0.6

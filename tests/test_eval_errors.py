"""TIDE-style error breakdown on planted errors: each type counted where it was planted, its dAP50 what
pycocotools gives with it fixed by hand, nothing on a perfect detector, false alarms on negatives."""

from __future__ import annotations

import pytest
from factories import planted_dataset

from eval.errors import ERROR_TYPES, error_breakdown
from ground.data.dataset import DatasetBuilder
from ground.detect.cocoeval import run_cocoeval

FIRE, SMOKE = 1, 2


def _dataset(tmp_path, gts):
    return planted_dataset(tmp_path, gts)


def _rec(image_id, cat, box, score):
    return {"image_id": image_id, "category_id": cat, "bbox": list(box), "score": score}


def test_each_planted_error_is_found_where_it_was_planted(tmp_path):
    ds = _dataset(
        tmp_path,
        [
            [(FIRE, (10, 10, 20, 20))],  # 1: found, then found again (duplicate)
            [(FIRE, (10, 10, 20, 20))],  # 2: seen as smoke (classification)
            [(FIRE, (0, 0, 20, 20))],  # 3: box shifted by half (localisation, IoU 1/3)
            [(SMOKE, (0, 0, 20, 20))],  # 4: shifted and seen as fire (both); the smoke is missed
            [(FIRE, (30, 30, 10, 10))],  # 5: missed; a detection on nothing (background)
            [],  # 6: no fire: one alarm over 0.25, one below
            [(FIRE, (40, 40, 30, 30))],  # 7: found last, so every error above costs precision there
        ],
    )
    records = [
        _rec(1, FIRE, (10, 10, 20, 20), 0.9),
        _rec(1, FIRE, (11, 10, 20, 20), 0.8),
        _rec(2, SMOKE, (10, 10, 20, 20), 0.7),
        _rec(3, FIRE, (10, 0, 20, 20), 0.6),
        _rec(4, FIRE, (10, 0, 20, 20), 0.5),
        _rec(5, FIRE, (70, 70, 5, 5), 0.4),
        _rec(6, FIRE, (50, 50, 10, 10), 0.3),
        _rec(6, FIRE, (20, 50, 10, 10), 0.1),
        _rec(7, FIRE, (40, 40, 30, 30), 0.05),
    ]
    out = error_breakdown(ds, records, [FIRE, SMOKE])
    assert out.counts == {
        "classification": 1,
        "localisation": 1,
        "both": 1,
        "duplicate": 1,
        "background": 3,
        "missed": 2,
    }
    assert out.ap50 == pytest.approx(run_cocoeval(ds, records, [FIRE, SMOKE]).stats[1])
    assert all(out.delta_ap50[k] > 0 for k in ERROR_TYPES), out.delta_ap50
    assert out.negatives == 1 and out.false_alarms_per_100 == pytest.approx(100.0)
    assert out.alarm_image_share == pytest.approx(1.0)


def test_delta_is_the_ap_with_the_error_fixed_by_hand(tmp_path):
    ds = _dataset(tmp_path, [[(FIRE, (10, 10, 20, 20))], [(FIRE, (0, 0, 20, 20))]])
    records = [_rec(1, FIRE, (10, 10, 20, 20), 0.9), _rec(2, FIRE, (10, 0, 20, 20), 0.8)]
    out = error_breakdown(ds, records, [FIRE])
    by_hand = [records[0], _rec(2, FIRE, (0, 0, 20, 20), 0.8)]  # the shifted box put on its object
    fixed = run_cocoeval(ds, by_hand, [FIRE]).stats[1]
    assert fixed == pytest.approx(1.0) and out.ap50 == pytest.approx(51 / 101)  # 101-point: recall 0..0.5
    assert out.delta_ap50["localisation"] == pytest.approx(fixed - out.ap50)
    assert {k: v for k, v in out.counts.items() if v} == {"localisation": 1}
    assert out.negatives == 0 and out.false_alarms_per_100 is None


def test_a_perfect_detector_has_no_errors_and_crowd_boxes_absorb(tmp_path):
    builder = DatasetBuilder(tmp_path, ["fire"])
    image = builder.add_image("a.jpg", 100, 100, "real:x", "test")
    builder.add_box(image, "fire", (10, 10, 20, 20))
    builder.add_box(image, "fire", (50, 50, 40, 40), iscrowd=1)
    ds = builder.build({})
    records = [_rec(image, FIRE, (10, 10, 20, 20), 0.9), _rec(image, FIRE, (55, 55, 20, 20), 0.8)]
    out = error_breakdown(ds, records, [FIRE])
    assert out.ap50 == pytest.approx(1.0)
    assert all(v == 0 for v in out.counts.values()) and all(v == 0 for v in out.delta_ap50.values())


def test_worst_errors_are_the_top_false_alarms_and_the_largest_misses(tmp_path):
    from eval.errors import worst_errors

    ds = _dataset(
        tmp_path,
        [
            [(FIRE, (10, 10, 20, 20)), (FIRE, (50, 50, 40, 40))],  # the small box found, the large one missed
            [(FIRE, (0, 0, 10, 10))],  # missed, a weak detection beside it (localisation, not missed)
            [(SMOKE, (60, 0, 30, 30))],  # missed (a small one), nothing near it
            [],  # negative: two false alarms
        ],
    )
    records = [
        _rec(1, FIRE, (10, 10, 20, 20), 0.9),
        _rec(2, FIRE, (5, 5, 10, 10), 0.3),  # IoU 25/175 with its box: localisation
        _rec(4, FIRE, (0, 0, 10, 10), 0.8),
        _rec(4, SMOKE, (40, 40, 10, 10), 0.5),
        _rec(1, FIRE, (85, 85, 10, 10), 0.7),  # on (almost) nothing: IoU 25/1675 with the large box
    ]
    worst = worst_errors(ds, records, [FIRE, SMOKE], count=2)
    alarms, missed = worst["false_alarm"], worst["missed"]
    assert [(c.image_id, c.score) for c in alarms] == [(4, 0.8), (1, 0.7)]  # by score, cut at count
    assert [c.kind for c in alarms] == ["false_alarm"] * 2 and alarms[0].iou == 0.0
    assert alarms[1].iou == pytest.approx(25 / 1675)
    assert [(c.image_id, c.bbox) for c in missed] == [(1, (50, 50, 40, 40)), (3, (60, 0, 30, 30))]  # by area
    assert missed[0].other == (85.0, 85.0, 10.0, 10.0) and missed[0].score == 0.7  # its best same-class detection
    assert missed[0].iou == pytest.approx(25 / 1675)
    assert missed[1].other is None and missed[1].score is None and missed[1].iou == 0.0
    everything = worst_errors(ds, records, [FIRE, SMOKE], count=10)
    breakdown = error_breakdown(ds, records, [FIRE, SMOKE])
    assert len(everything["false_alarm"]) == breakdown.counts["background"] == 3
    assert len(everything["missed"]) == breakdown.counts["missed"] == 2  # the localised box is not missed


def test_an_image_labelled_fire_photo_is_no_false_alarm(tmp_path):
    """Detections on a photo labelled fire at the image level are not false alarms; on its unlabelled photos
    they are."""
    b = DatasetBuilder(tmp_path, ["fire"])
    fire = b.add_image("fire.jpg", 50, 50, labels=("fire",))
    free = b.add_image("free.jpg", 50, 50)
    records = [{"image_id": i, "category_id": 1, "bbox": [1, 1, 5, 5], "score": 0.9} for i in (fire, free)]
    out = error_breakdown(b.build(), records, [1])
    assert out.ap50 is None and out.negatives == 1 and out.false_alarms_per_100 == 100.0

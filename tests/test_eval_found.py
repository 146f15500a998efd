"""Boxes found at an operating point, box by box: each planted outcome is named where it was planted, low-scoring
detections do not count, and the size and crowding tables add up."""

from __future__ import annotations

from factories import planted_dataset

from eval.found import OUTCOMES, boxes_found, outcome

FIRE, SMOKE = 1, 2


def _dataset(tmp_path, gts):
    return planted_dataset(tmp_path, gts, size=200)


def _rec(image_id, cat, box, score=0.9):
    return {"image_id": image_id, "category_id": cat, "bbox": list(box), "score": score}


def test_each_planted_outcome_is_named():
    assert outcome((10, 10, 20, 20), [(10, 10, 20, 20)], []) == "missed"
    assert outcome((10, 10, 20, 20), [(10, 10, 20, 20)], [(11, 11, 20, 20)]) == "found"
    assert outcome((10, 10, 20, 20), [(10, 10, 20, 20)], [(100, 100, 5, 5)]) == "missed"  # IoU < 0.1
    two = [(10, 10, 20, 20), (32, 10, 20, 20)]
    assert outcome(two[0], two, [(8, 8, 46, 24)]) == "merged"  # one detection over both neighbours
    assert outcome((10, 10, 40, 20), [(10, 10, 40, 20)], [(10, 10, 19, 20), (31, 10, 19, 20)]) == "split"
    assert outcome((10, 10, 20, 20), [(10, 10, 20, 20)], [(5, 5, 40, 40)]) == "too_large"
    assert outcome((10, 10, 40, 40), [(10, 10, 40, 40)], [(10, 10, 20, 20)]) == "too_small"


def test_only_detections_above_the_threshold_count_and_the_tables_add_up(tmp_path):
    crowd = [(FIRE, (10 + 30 * k, 10, 20, 20)) for k in range(5)]  # five fires boxed one by one
    ds = _dataset(tmp_path, [crowd, [(FIRE, (50, 50, 100, 100)), (SMOKE, (0, 0, 50, 50))], []])
    records = [_rec(1, FIRE, b) for _, b in crowd[:2]] + [
        _rec(1, FIRE, crowd[2][1], score=0.1),  # below the threshold: not found
        _rec(2, FIRE, (50, 50, 100, 100)),
        _rec(2, SMOKE, (0, 0, 50, 50)),  # a class not scored
        _rec(3, FIRE, (0, 0, 10, 10)),  # a false alarm: no box to find
    ]
    found = boxes_found(ds, records, [FIRE], conf=0.25)
    assert found.boxes == 6 and found.outcomes == {**dict.fromkeys(OUTCOMES, 0), "found": 3, "missed": 3}
    assert found.by_crowding == {"1": (1, 1), "2": (0, 0), "3-4": (0, 0), "5+": (2, 5)}  # smoke is no fire box
    assert found.by_size["16-32"] == (2, 5) and found.by_size["64-128"] == (1, 1)
    assert sum(n for _, n in found.by_size.values()) == found.boxes == sum(found.outcomes.values())
    assert boxes_found(ds, records, [FIRE], conf=0.05).outcomes["found"] == 4
    assert found.to_dict()["by_crowding"]["5+"] == {"found": 2, "boxes": 5}

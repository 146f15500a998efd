"""Pictures of the worst errors: whole-factor enlargement, truth in green and the detection in red, unreadable
images reported instead of drawn."""

from __future__ import annotations

import json

import numpy as np
import pytest
from factories import write_image

from eval import error_pictures as E
from eval.draw import GROUND_TRUTH, PREDICTION
from eval.errors import ErrorCase
from ground.data.dataset import DatasetBuilder
from ground.image.imageio import read_image


@pytest.mark.parametrize(("w", "h", "k"), [(64, 32, 10), (640, 480, 1), (100, 300, 3), (2000, 10, 1), (639, 1, 2)])
def test_enlargement_is_the_smallest_whole_factor_reaching_min_side(w, h, k):
    assert E.enlargement(w, h) == k
    assert max(w, h) * k >= E.MIN_SIDE or k == 1  # large enough, or already was
    assert k == 1 or max(w, h) * (k - 1) < E.MIN_SIDE  # and no larger than needed


def _dataset(tmp_path):
    builder = DatasetBuilder(tmp_path, ["fire", "smoke"])
    write_image(tmp_path / "a.png", 80, 60)
    a = builder.add_image("a.png", 80, 60)
    builder.add_box(a, "fire", (10, 10, 20, 20))
    builder.add_box(a, "smoke", (40, 5, 30, 20))
    builder.add_image("gone.png", 80, 60)
    return builder.build()


def test_missed_box_is_labelled_and_its_nearest_detection_drawn_red(tmp_path):
    ds = _dataset(tmp_path)
    case = ErrorCase("missed", 1, (10.0, 10.0, 20.0, 20.0), 1, 0.3, 0.2, (20.0, 20.0, 20.0, 20.0))
    boxes, labels, colours = E.case_boxes(case, ds, {1: "fire", 2: "smoke"})
    assert labels == ["missed fire", "truth smoke", "fire 0.30 IoU 0.20"]
    assert colours == [GROUND_TRUTH, GROUND_TRUTH, PREDICTION] and boxes[-1] == (20.0, 20.0, 20.0, 20.0)
    picture = E.case_picture(case, ds, {1: "fire", 2: "smoke"})
    k = E.enlargement(80, 60)
    assert picture.shape == (60 * k, 80 * k, 3)
    assert tuple(picture[(20 + 20) * k - 1, 30 * k]) == PREDICTION  # the detection's bottom edge
    original = np.repeat(np.repeat(read_image(tmp_path / "a.png"), k, axis=0), k, axis=1)
    assert np.array_equal(picture[-5:], original[-5:])  # below every box: the enlarged image itself


def test_unreadable_images_are_reported_and_the_rest_written(tmp_path):
    ds = _dataset(tmp_path)
    records = [
        {"image_id": 2, "category_id": 1, "bbox": [1, 1, 5, 5], "score": 0.9},  # a false alarm on a missing file
        {"image_id": 1, "category_id": 1, "bbox": [10, 10, 20, 20], "score": 0.8},
    ]
    folder, problems = E.write_error_pictures(ds, records, [1, 2], tmp_path / "out")
    assert [p.reason.split(":")[0] for p in problems] == ["no error picture"] and "gone.png" in problems[0].path
    index = json.loads((folder / "index.json").read_text())
    assert [(e["kind"], e["category"], e["bbox"]) for e in index] == [("missed", "smoke", [40, 5, 30, 20])]
    assert sorted(p.name for p in folder.iterdir()) == ["index.json", "missed_01_a.png"]

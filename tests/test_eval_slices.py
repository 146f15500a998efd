"""Slices: merged when too small, never silently reported; per-slice paired comparisons find the slice where one
detector is better and only that one, with Holm's correction."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from eval.imagelevel import image_hits
from eval.slices import Side, compare_slices, holm, make_slices, objects_name, positives_name
from eval.stats import MatchTable
from ground.data.dataset import DatasetBuilder
from ground.detect.cocoeval import LOOSE_IOU, run_cocoeval


def test_small_slices_merge_with_their_smaller_neighbour_or_into_other() -> None:
    ids = np.arange(60)
    fire = ids < 50
    sizes = ["small"] * 5 + ["medium"] * 25 + ["large"] * 20 + [None] * 10
    colours = ["orange-red"] * 30 + ["chemical"] * 8 + ["yellow-white"] * 12 + [None] * 10
    attrs = {int(i): {"size": s, "colour": c, "light": "day"} for i, s, c in zip(ids, sizes, colours)}
    slices = {s.name: s for s in make_slices(attrs, ids, fire, minimum=20)}
    assert set(slices) == {"size=small,medium", "size=large", "colour=orange-red", "colour=other"}  # light: one value
    assert slices["size=small,medium"].fire_images == 30 and slices["colour=other"].fire_images == 20
    assert not any(s.too_few for s in slices.values())
    tiny = make_slices({int(i): {"sky": "sky" if i < 3 else "no sky"} for i in ids}, ids, fire, minimum=50)
    assert [(s.name, s.too_few) for s in tiny] == []  # merged into one slice: no cut left
    marked = make_slices({int(i): {"camera": "a" if i < 40 else "b"} for i in ids}, ids, fire, minimum=20)
    assert [(s.name, s.fire_images, s.too_few) for s in marked] == [("camera=a", 40, False), ("camera=b", 10, True)]


def test_holm_adjusts_step_down_and_keeps_order() -> None:
    assert holm([0.01, 0.04, 0.03, float("nan")]) == pytest.approx([0.03, 0.06, 0.06, float("nan")], nan_ok=True)
    assert holm([0.5, 0.9]) == [1.0, 1.0] or holm([0.5, 0.9]) == pytest.approx([1.0, 1.0])


def _study(tmp_path: Path):
    """60 images with one fire box each: 30 at night, 30 by day. Model a finds the day fires only, model b every
    fire; both raise one false positive per image, scored below every fire they find."""
    b = DatasetBuilder(tmp_path, ["fire"])
    for i in range(60):
        b.add_box(b.add_image(f"{i}.jpg", 100, 100), "fire", [10, 10, 40, 40])
    ds = b.build()

    def records(find_night: bool, seed: int) -> list[dict]:
        rng = np.random.default_rng(seed)
        out = []
        for img in ds.images:
            night = img.id <= 30
            if not night or find_night:
                out.append(
                    {"image_id": img.id, "category_id": 1, "bbox": [11, 11, 40, 40], "score": 0.5 + 0.4 * rng.random()}
                )
            out.append({"image_id": img.id, "category_id": 1, "bbox": [60, 60, 20, 20], "score": 0.4 * rng.random()})
        return out

    def side(find_night: bool) -> Side:
        runs = [records(find_night, s) for s in (0, 1)]
        return Side([MatchTable(run_cocoeval(ds, r, [1])) for r in runs],
                    [MatchTable(run_cocoeval(ds, r, [1], [LOOSE_IOU])) for r in runs],
                    [(image_hits(ds, r, [1]), 0.25) for r in runs])  # fmt: skip

    attrs = {img.id: {"light": "night" if img.id <= 30 else "day"} for img in ds.images}
    ids = np.asarray(sorted(img.id for img in ds.images))
    return side(False), side(True), make_slices(attrs, ids, np.ones(60, bool))


def test_the_slice_that_differs_is_found_and_the_other_is_not(tmp_path: Path) -> None:
    a, b, slices = _study(tmp_path)
    rows = compare_slices(a, b, slices, np.random.default_rng(0), 300)
    verdict = {(r["slice"], r["metric"]): r["verdict"] for r in rows}
    assert {k for k, v in verdict.items() if v == "helps"} == {
        ("light=night", "AP50"),
        ("light=night", "AP25"),
        ("light=night", "image_recall"),
    }
    assert not any(v == "hurts" for v in verdict.values())
    night = next(r for r in rows if r["slice"] == "light=night" and r["metric"] == "image_recall")
    assert night["delta"]["value"] == pytest.approx(1.0) and night["fire_images"] == 30
    day = next(r for r in rows if r["slice"] == "light=day" and r["metric"] == "AP50")
    assert day["delta"]["value"] == pytest.approx(0.0, abs=1e-12)
    again = compare_slices(a, b, slices, np.random.default_rng(0), 300)
    assert [r["delta"] for r in again] == [r["delta"] for r in rows]  # same rng, same numbers


def test_a_restricted_table_gives_the_ap_of_its_images(tmp_path: Path) -> None:
    a, b, slices = _study(tmp_path)
    night = next(s for s in slices if s.value == "night")
    table = b.ap50[0]
    weights = night.mask.astype(float)
    assert table.restricted([0], night.mask).precision(weights)[0] == pytest.approx(table.precision(weights)[0])


def test_a_slice_counts_the_images_of_every_studied_class_and_says_so() -> None:
    assert positives_name(["fire"]) == "fire images"
    assert positives_name(["fire", "smoke"]) == "images with fire or smoke"
    assert objects_name(["fire"]) == "fire" and objects_name(["fire", "smoke"]) == "fire or smoke"

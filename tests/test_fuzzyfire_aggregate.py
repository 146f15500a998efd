"""Aggregation: rows carry the tables their run's spec names, and when comparisons are skipped; a named set
without fire gives rows with its alarm rate and no comparison, and the sets with fire of a run scored on it their
recall at the alarm budget (read once, again when scored again)."""

from __future__ import annotations

from pathlib import Path

import pytest
from factories_experiment import toy_config

from eval.config import InferenceConfig
from fuzzyfire.aggregate import comparisons, result_rows, too_few_notes
from fuzzyfire.runs import EvalSet, RunSpec
from fuzzyfire.stages import DataRef
from train.config import TrainConfig


def _spec(out: Path, mixture: str, method: str | None, seed: int = 0, tables: tuple[str, ...] = ()) -> RunSpec:
    ref = DataRef(Path("/d"), {"kind": "x"})
    train = TrainConfig(seed=seed)
    tests = (EvalSet("common", ref), EvalSet("rare", ref))
    return RunSpec(mixture, method, ref, ref, tests, ("fire",), train, InferenceConfig(), out, tables=tables)


def _result(ap: float) -> dict:
    test = {"AP": ap, "AP50": 2 * ap, "scores": "scores/common"}
    return {"tests": {"common": test, "rare": {**test, "scores": "scores/rare"}}}


def test_rows_carry_the_tables_of_their_spec(tmp_path: Path) -> None:
    specs = [
        _spec(tmp_path, "R12_S0", None, tables=("table2",)),
        _spec(tmp_path, "R0_S12", "method2", tables=("table2", "table1")),
        _spec(tmp_path, "R0_S12", "method1", tables=("table1",)),
        _spec(tmp_path, "R6_S6", "method2", seed=1, tables=("table2",)),
    ]
    results = [_result(0.1), _result(0.3), _result(0.4), None]  # the last run failed
    rows = result_rows(specs, results, tmp_path)
    assert len(rows) == 6
    tables = {(r["mixture"], r["method"]): r["tables"] for r in rows}
    assert tables == {("R12_S0", "-"): ["table2"], ("R0_S12", "method2"): ["table2", "table1"],
                      ("R0_S12", "method1"): ["table1"]}  # fmt: skip
    first, folder = rows[0], specs[0].out.relative_to(tmp_path).as_posix()
    assert folder.startswith("runs/R12_S0/seed0-") and first["run"] == folder and first["AP50"] == 0.2
    assert first["matches"].endswith(f"{folder}/scores/common/matches.npz")


def test_no_comparisons_without_bootstrap_or_baseline(tmp_path: Path) -> None:
    specs = [_spec(tmp_path, "R6_S6", "method2", tables=("table2",))]
    rows = result_rows(specs, [_result(0.1)], tmp_path)
    assert comparisons(toy_config(mixtures=["R6_S6"]), rows) == []  # no real-only mixture: no baseline
    cfg = toy_config(mixtures=["R12_S0", "R6_S6"])
    no_bootstrap = cfg.__class__(**{**cfg.__dict__, "report": cfg.report.__class__(bootstrap=0)})
    assert comparisons(no_bootstrap, rows) == []


def test_a_named_set_without_fire_gives_alarm_rows_and_no_comparison(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from dataclasses import replace

    import eval.stats as stats
    from eval.errors import ALARMS

    ref = DataRef(Path("/d"), {"kind": "x"})
    specs = [
        replace(_spec(tmp_path, m, method, tables=("table2",)), evals=(EvalSet("fire-free", ref),))
        for m, method in (("R12_S0", None), ("R6_S6", "method2"))
    ]
    free = {"AP": None, "AP50": None, "AP25": None, ALARMS: 25.0, "scores": "scores/fire-free"}
    results = [{"tests": {**_result(0.1)["tests"], "fire-free": free}}, _result(0.2)]  # the second: not scored yet
    rows = result_rows(specs, results, tmp_path)
    assert [r["test_set"] for r in rows] == ["common", "rare", "fire-free", "common", "rare"]
    assert rows[2][ALARMS] == 25.0 and rows[2]["AP"] is None and not any(ALARMS in r for r in rows if r is not rows[2])
    loaded: list[str] = []
    monkeypatch.setattr(stats.MatchTable, "load", staticmethod(lambda path: loaded.append(Path(path).parent.name)))
    monkeypatch.setattr(stats, "paired_bootstrap", lambda *a, **k: {})
    assert comparisons(toy_config(mixtures=["R12_S0", "R6_S6"]), rows) == []
    assert sorted(set(loaded)) == ["common", "rare"]  # no AP on the set without fire: nothing to compare


def test_a_set_with_fire_carries_its_recall_at_the_alarm_budget(tmp_path: Path) -> None:
    import json
    from dataclasses import replace

    from factories import planted_dataset

    from eval.errors import ALARMS
    from eval.operating import RECALL_AT_ALARMS
    from fuzzyfire.aggregate import FOUND_FILE

    common = planted_dataset(tmp_path / "data", [[(1, (10, 10, 20, 20))], [(1, (50, 50, 20, 20))]])
    free_images = planted_dataset(tmp_path / "free", [[] for _ in range(20)])
    free_ref = DataRef(Path("/free"), {"kind": "free"})

    class Loader:  # Datasets.get: the test sets' images and boxes; counts the reads of sets with fire
        reads = 0
        classes = ("fire",)

        def get(self, ref: DataRef):
            if ref == free_ref:
                return free_images
            Loader.reads += 1
            return common

    with_free = replace(_spec(tmp_path, "R12_S0", None, tables=("table2",)), evals=(EvalSet("fire-free", free_ref),))
    without = _spec(tmp_path, "R6_S6", "method2", tables=("table2",))
    box = lambda i, b, s: {"image_id": i, "category_id": 1, "bbox": b, "score": s}  # noqa: E731
    for spec in (with_free, without):
        for name, records in (("common", [box(1, [10, 10, 20, 20], 0.9), box(2, [50, 50, 20, 20], 0.3)]),
                              ("rare", [box(1, [10, 10, 20, 20], 0.8)]),
                              ("fire-free", [box(1, [0, 0, 5, 5], s) for s in (0.95, 0.5, 0.4, 0.2)])):  # fmt: skip
            (spec.out / "scores" / name).mkdir(parents=True, exist_ok=True)
            (spec.out / "scores" / name / "predictions.json").write_text(json.dumps(records), encoding="utf-8")
    fire = {"AP": 0.5, "AP50": 0.5, "AP25": 0.5, "boxes": 2}
    free = {"AP": None, "AP50": None, ALARMS: 50.0, "images": 20, "scores": "scores/fire-free"}
    tests = {"common": {**fire, "scores": "scores/common"}, "rare": {**fire, "scores": "scores/rare"}}
    results = [{"tests": {**tests, "fire-free": free}}, {"tests": tests}]
    rows = result_rows([with_free, without], results, tmp_path, Loader(), 3)  # type: ignore[arg-type]
    at = {(r["mixture"], r["test_set"]): r.get(RECALL_AT_ALARMS) for r in rows}
    # 20 images without fire, 10 per 100: two alarms allowed, so the threshold lies just above 0.4 (the third)
    assert at == {("R12_S0", "common"): 0.5, ("R12_S0", "rare"): 0.5, ("R12_S0", "fire-free"): None,
                  ("R6_S6", "common"): None, ("R6_S6", "rare"): None}  # fmt: skip
    assert 0.4 < rows[0]["threshold_at_alarms"] < 0.41 and Loader.reads == 6  # 2 found scores, 4 image hits
    assert (with_free.out / "scores" / "common" / FOUND_FILE).is_file()
    # image recall: with the fire-free set, 1 of 20 images alarmed (5 per 100) lets every detection count;
    # without it, read at confidence 0.25 (image 2 of rare has no detection)
    recall = {(r["mixture"], r["test_set"]): r.get("image_recall") for r in rows}
    assert recall == {("R12_S0", "common"): 1.0, ("R12_S0", "rare"): 0.5, ("R12_S0", "fire-free"): None,
                      ("R6_S6", "common"): 1.0, ("R6_S6", "rare"): 0.5}  # fmt: skip
    assert rows[0]["fire_images"] == 2 and rows[0]["AP50"] is None  # under the minimum of 3 fire images: no AP
    assert result_rows([with_free], results[:1], tmp_path, Loader())[0][RECALL_AT_ALARMS] == 0.5  # type: ignore[arg-type]
    assert Loader.reads == 6  # read from found_scores.json and image_hits.json
    (with_free.out / "scores" / "common" / "predictions.json").write_text(
        json.dumps([box(1, [10, 10, 20, 20], 0.9), box(2, [50, 50, 20, 20], 0.6)]), encoding="utf-8"
    )  # scored again: read again
    assert result_rows([with_free], results[:1], tmp_path, Loader())[0][RECALL_AT_ALARMS] == 1.0  # type: ignore[arg-type]
    assert Loader.reads == 8  # found scores and image hits of the set scored again


def test_the_recall_at_the_alarm_budget_is_compared_when_every_run_has_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import json
    from dataclasses import replace

    from factories import planted_dataset

    import eval.stats as stats
    from eval.errors import ALARMS
    from eval.operating import RECALL_AT_ALARMS

    common = planted_dataset(tmp_path / "data", [[(1, (10, 10, 20, 20))], [(1, (50, 50, 20, 20))]])
    free_images = planted_dataset(tmp_path / "free", [[] for _ in range(20)])
    free_ref = DataRef(Path("/free"), {"kind": "free"})

    class Loader:  # Datasets.get
        classes = ("fire",)

        def get(self, ref: DataRef):
            return free_images if ref == free_ref else common

    box = lambda i, b, s: {"image_id": i, "category_id": 1, "bbox": b, "score": s}  # noqa: E731
    specs = [replace(_spec(tmp_path, m, method, tables=("table2",)), evals=(EvalSet("fire-free", free_ref),))
             for m, method in (("R12_S0", None), ("R6_S6", "method2"))]  # fmt: skip
    one = [box(1, [10, 10, 20, 20], 0.9)]
    found = {"R12_S0": one, "R6_S6": [*one, box(2, [50, 50, 20, 20], 0.8)]}
    for spec in specs:
        for name, records in (("common", found[spec.mixture]), ("rare", found[spec.mixture]),
                              ("fire-free", [box(1, [0, 0, 5, 5], 0.5)])):  # fmt: skip
            (spec.out / "scores" / name).mkdir(parents=True, exist_ok=True)
            (spec.out / "scores" / name / "predictions.json").write_text(json.dumps(records), encoding="utf-8")
    fire = {"AP": 0.5, "AP50": 0.5, "AP25": 0.5, "boxes": 2}
    free = {"AP": None, "AP50": None, ALARMS: 5.0, "images": 20, "scores": "scores/fire-free"}
    tests = {
        "common": {**fire, "scores": "scores/common"},
        "rare": {**fire, "scores": "scores/rare"},
        "fire-free": free,
    }
    rows = result_rows(specs, [{"tests": tests}, {"tests": tests}], tmp_path, Loader())  # type: ignore[arg-type]
    monkeypatch.setattr(stats.MatchTable, "load", staticmethod(lambda path: path))
    monkeypatch.setattr(stats, "paired_bootstrap", lambda *a, **k: {})  # the AP comparisons: their own tests
    out = comparisons(toy_config(mixtures=["R12_S0", "R6_S6"]), rows)
    assert [(c["test_set"], c["mixture"], c["baseline"], c["metric"]) for c in out] == [
        ("common", "R6_S6", "R12_S0", RECALL_AT_ALARMS), ("common", "R6_S6", "R12_S0", "image_recall"),
        ("rare", "R6_S6", "R12_S0", RECALL_AT_ALARMS), ("rare", "R6_S6", "R12_S0", "image_recall")]  # fmt: skip
    assert out[0]["delta"]["value"] == 0.5  # one alarm of 20 images allowed at 10 per 100: 2 of 2 found vs 1 of 2
    assert out[1]["delta"]["value"] == 0.5  # and 2 of 2 fire images detected against 1 of 2
    assert {c["delta"]["resampled"] for c in out} == {"images"}  # one seed a side
    seeded = [{**r, "seed": seed} for seed in range(3) for r in rows]  # three seeds a side, the same on both
    three = comparisons(toy_config(mixtures=["R12_S0", "R6_S6"]), seeded)
    assert {c["delta"]["resampled"] for c in three} == {"images and seeds"}  # recall at the budget too
    assert all(c["baseline_seeds"] == c["mixture_seeds"] == [0, 1, 2] for c in three)
    for row in rows:  # a run scored on no set without fire has none
        row.pop("operating", None)
    assert all(c["metric"] != RECALL_AT_ALARMS for c in comparisons(toy_config(mixtures=["R12_S0", "R6_S6"]), rows))
    for row in rows:  # nor image recall without its image hits
        row.pop("imagelevel", None)
    assert comparisons(toy_config(mixtures=["R12_S0", "R6_S6"]), rows) == []


def test_report_shows_the_pools_the_mixtures_trained_on() -> None:
    """With own cut-out pools the shared pool is named for the R0 mixtures it still serves, and each mixture's
    own pool of its first seed is shown beside it; without them the pools keep their method names."""
    from dataclasses import replace

    from fuzzyfire.aggregate import report_pools
    from fuzzyfire.stages import Prepared

    cfg = toy_config()
    cfg = replace(cfg, synth=replace(cfg.synth, method2=replace(cfg.synth.method2, flames=replace(
        cfg.synth.method2.flames, source="cutouts"))))  # fmt: skip
    shared, real = DataRef(Path("/pool"), {"kind": "pool"}), DataRef(Path("/real"), {"kind": "real"})
    data = Prepared(real, None, {"method2": shared})
    own = {("R6_S6", "method2", s): DataRef(Path(f"/own{s}"), {"seed": s}) for s in (2, 1)}
    assert report_pools(cfg, data, {}) == {"method2": shared}
    assert report_pools(cfg, data, own) == {
        "method2 simulated flames (R0 mixtures)": shared,
        "method2 flames.source=cutouts R6_S6 seed 1": own[("R6_S6", "method2", 1)],
    }


def test_ap25_of_a_run_scored_before_it_is_kept_with_the_digest_of_its_predictions(tmp_path: Path) -> None:
    import json

    from factories import planted_dataset

    from fuzzyfire.aggregate import LOOSE_FILE, run_ap25

    common = planted_dataset(tmp_path / "data", [[(1, (10, 10, 20, 20))], [(1, (50, 50, 20, 20))]])

    class Loader:  # Datasets.get, counting reads
        reads = 0

        def get(self, ref: DataRef):
            Loader.reads += 1
            return common

    folder, ref = tmp_path / "scores" / "common", DataRef(Path("/common"), {"kind": "common"})
    folder.mkdir(parents=True)
    found_one = [{"image_id": 1, "category_id": 1, "bbox": [14, 14, 20, 20], "score": 0.9}]  # IoU 0.47 with its box
    (folder / "predictions.json").write_text(json.dumps(found_one), encoding="utf-8")
    assert run_ap25(Loader(), folder, ref, {"AP25": 0.25}) == 0.25 and Loader.reads == 0  # the run's own figure
    first = run_ap25(Loader(), folder, ref, {})  # type: ignore[arg-type]
    assert first == pytest.approx(0.5, abs=0.01) and Loader.reads == 1
    assert run_ap25(Loader(), folder, ref, {}) == first and Loader.reads == 1  # type: ignore[arg-type]
    both = found_one + [{"image_id": 2, "category_id": 1, "bbox": [50, 50, 20, 20], "score": 0.8}]
    (folder / "predictions.json").write_text(json.dumps(both), encoding="utf-8")  # scored again: read again
    assert run_ap25(Loader(), folder, ref, {}) == pytest.approx(1.0) and Loader.reads == 2  # type: ignore[arg-type]
    (folder / LOOSE_FILE).write_text(json.dumps({"AP25": 0.1}), encoding="utf-8")  # kept before the digest
    assert run_ap25(Loader(), folder, ref, {}) == pytest.approx(1.0) and Loader.reads == 3  # type: ignore[arg-type]


def _two_class_matches(tmp_path: Path, name: str, found_smoke: bool) -> Path:
    """A match table of 4 images (2 fire boxes, 2 smoke boxes): every fire found; the smoke found or not."""
    from eval.stats import MatchTable
    from ground.data.dataset import DatasetBuilder
    from ground.detect.cocoeval import run_cocoeval

    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    records = []
    for i, cls in enumerate(("fire", "fire", "smoke", "smoke")):
        image_id = b.add_image(f"{i}.jpg", 100, 100)
        b.add_box(image_id, cls, (10.0, 10.0, 30.0, 30.0))
        if cls == "fire" or found_smoke:
            records.append({"image_id": image_id, "category_id": 1 + (cls == "smoke"), "bbox": [10, 10, 30, 30],
                            "score": 0.9})  # fmt: skip
    return MatchTable(run_cocoeval(b.build(), records, [1, 2])).save(tmp_path / f"{name}.npz")


def test_a_two_class_set_gives_per_class_columns_and_comparisons(tmp_path: Path) -> None:
    """Rows of a set boxing fire and smoke carry each class's AP50; the comparison adds a paired delta per class:
    here smoke gains the whole AP50 and fire nothing."""
    from eval.report import table_metrics
    from fuzzyfire.aggregate import per_class_ap

    scored = {"AP50": 0.5, "per_class": {"fire": {"AP50": 1.0}, "smoke": {"AP50": 0.0}}}
    assert per_class_ap(scored, True) == {"classes": ["fire", "smoke"], "AP50 fire": 1.0, "AP50 smoke": 0.0}
    assert per_class_ap(scored, False)["AP50 smoke"] is None  # too few fire images: no AP of any class
    assert per_class_ap({"per_class": {"fire": {"AP50": 1.0}}}, True) == {}  # one class: the set's AP is its AP
    rows = [
        {"mixture": mixture, "seed": 0, "test_set": "common", "tables": ["table2"], "fire_images": 4,
         "AP": ap, "AP50": ap, **per_class_ap({"per_class": {"fire": {"AP50": 1.0}, "smoke": {"AP50": ap * 2 - 1}}},
                                             True),
         "matches": _two_class_matches(tmp_path, mixture, found).as_posix()}
        for mixture, ap, found in (("R12_S0", 0.5, False), ("R6_S6", 1.0, True))
    ]  # fmt: skip
    assert table_metrics(rows) == ("AP", "AP50", "AP50 fire", "AP50 smoke")
    out = {c["metric"]: c for c in comparisons(toy_config(mixtures=["R12_S0", "R6_S6"]), rows)}
    assert set(out) == {"AP", "AP50", "AP50 fire", "AP50 smoke"}
    assert {(c["mixture"], c["baseline"]) for c in out.values()} == {("R6_S6", "R12_S0")}
    assert out["AP50 fire"]["delta"]["value"] == 0.0 and out["AP50 smoke"]["delta"]["value"] == 1.0
    assert out["AP50"]["delta"]["value"] == 0.5  # the mean over the two classes
    assert out["AP50 smoke"]["seeds"] == [{"seed": 0, "delta": 1.0}]
    assert out["AP50"]["baseline_seeds"] == out["AP50"]["mixture_seeds"] == [0]  # each side's seeds, named


def test_each_class_gets_its_false_alarms_and_image_recall(tmp_path: Path) -> None:
    """From a run's predictions: on a set without fire, each class's detections at ALARM_CONF per 100 images; on a
    set with boxes, each class's images found by a detection of that class at the run's operating threshold."""
    import json

    import cv2
    import numpy as np

    from fuzzyfire.aggregate import per_class_images
    from fuzzyfire.datasets import DataRef, Datasets
    from ground.data.dataset import DatasetBuilder
    from ground.data.writer import write_dataset
    from ground.image.imageio import unit_to_u8

    def written(name: str, classes: list[str]) -> DataRef:
        b = DatasetBuilder(tmp_path / f"src-{name}", ["fire", "smoke"])
        (tmp_path / f"src-{name}").mkdir()
        for i, cls in enumerate(classes):
            cv2.imwrite(str(tmp_path / f"src-{name}" / f"{i}.png"), unit_to_u8(np.full((100, 100, 3), 0.5)))
            image_id = b.add_image(f"{i}.png", 100, 100)
            if cls:
                b.add_box(image_id, cls, (10.0, 10.0, 30.0, 30.0))
        write_dataset(b.build(), tmp_path / name, ("coco",), "copy")
        return DataRef(tmp_path / name, {"kind": name}, "coco")

    boxed, free = written("boxed", ["fire", "smoke", "smoke", "smoke"]), written("free", ["", "", "", ""])
    datasets = Datasets(["fire", "smoke"])
    ids = {c.name: c.id for c in datasets.get(boxed).categories}
    folder = tmp_path / "scores"
    folder.mkdir()

    def det(image: int, cls: str, score: float) -> dict:
        return {"image_id": image, "category_id": ids[cls], "bbox": [10, 10, 30, 30], "score": score}

    images = sorted(i.id for i in datasets.get(boxed).images)
    found = [det(images[0], "fire", 0.9), det(images[1], "smoke", 0.8), det(images[2], "fire", 0.9)]  # a fire on smoke
    (folder / "predictions.json").write_text(json.dumps(found), encoding="utf-8")
    out = per_class_images(datasets, folder, boxed, 0.5, None)
    assert out["image_recall fire"] == 1.0 and out["image_recall smoke"] == pytest.approx(1 / 3)
    assert out["imagelevel smoke"][1] == 0.5 and out["imagelevel smoke"][0].fire.sum() == 3
    negatives = sorted(i.id for i in datasets.get(free).images)
    alarms = [det(negatives[0], "smoke", 0.3), det(negatives[1], "smoke", 0.2), det(negatives[2], "fire", 0.9)]
    (folder / "predictions.json").write_text(json.dumps(alarms), encoding="utf-8")
    out = per_class_images(datasets, folder, free, None, {"alarms_per_100": 50.0})
    assert out == {"alarms_per_100 fire": 25.0, "alarms_per_100 smoke": 25.0}  # the 0.2 one is below ALARM_CONF


def test_slices_left_uncompared_are_counted_in_the_studys_positive_images() -> None:
    sets = {"common": [{"slice": "colour=orange-red", "fire_images": 3, "too_few": True},
                       {"slice": "colour=red", "fire_images": 40, "too_few": False}]}  # fmt: skip
    assert too_few_notes(sets) == ["Not compared (fewer than 20 fire images even after merging): common: "
                                   "colour=orange-red (3)."]  # fmt: skip
    assert "fewer than 20 images with fire or smoke" in too_few_notes(sets, "images with fire or smoke")[0]
    assert too_few_notes({"common": sets["common"][1:]}) == []

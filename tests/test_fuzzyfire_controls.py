"""Control runs (``grid.control``): one per Table 2 mixture with real and synthetic images, trained on flame-free
copies of that mixture's own real training images (no flame box, only the images' own boxes), compared with the
mixture by the paired bootstrap, without changing any other run, pool or comparison."""

from __future__ import annotations

import contextlib
import io
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from factories_experiment import toy_dict

from eval.stats import MatchTable
from fuzzyfire.aggregate import comparisons, table_text
from fuzzyfire.controls import (
    CONTROL,
    CONTROL_TABLE,
    control_config,
    control_label,
    control_pools,
    has_control,
    kept_settings,
)
from fuzzyfire.datasets import Datasets
from fuzzyfire.experiment import grid_entries, needed_methods, prepare_data, write_mixtures
from fuzzyfire.experiment_config import ExperimentConfig, ExperimentConfigError
from ground.config.loader import build_config
from ground.data.dataset import DatasetBuilder
from ground.data.formats.coco import read_coco
from ground.detect.cocoeval import run_cocoeval

SEEDS = [0, 1]


def _config(control: bool = True, **synth: Any) -> ExperimentConfig:
    """The toy config (160x120 real images), no Method 1, ``grid.control`` as given."""
    d = toy_dict(mixtures=["R6_S0", "R6_S6", "R6_S3", "R0_S6"], table1=[], seeds=SEEDS)
    d["grid"]["control"] = control
    d["real"]["standin"].update(width=160, height=120, flame_height=[0.3, 0.6], negatives=0.0)
    d["synth"]["method1"] = None
    d["synth"]["method2"].update(synth)
    d["report"] = {"bootstrap": 0, "samples": False, "gap_draws": 0}
    return build_config(d, ExperimentConfig)


def test_only_mixtures_with_real_and_synthetic_images_get_a_control() -> None:
    entries = {(e.mixture, e.method): e.tables for e in grid_entries(_config())}
    assert entries == {
        ("R6_S0", None): ("table2",),
        ("R6_S6", "method2"): ("table2",),
        ("R6_S3", "method2"): ("table2",),
        ("R0_S6", "method2"): ("table2",),
        ("R6_S6", CONTROL): (CONTROL_TABLE,),
        ("R6_S3", CONTROL): (CONTROL_TABLE,),
    }
    plain = grid_entries(_config(control=False))
    assert [e for e in grid_entries(_config()) if e.method != CONTROL] == plain
    assert needed_methods(grid_entries(_config())) == ["method2"]  # a control has no shared pool to build
    assert [has_control(n) for n in ("R6_S0", "R0_S6", "R6_S6")] == [False, False, True]
    assert control_label("R200_S200") == "R200_S200 copies"


def test_a_control_needs_method2() -> None:
    d = toy_dict(mixtures=["R6_S6"], table1=[])
    d["grid"].update(control=True, synthetic="method1")
    d["synth"]["method2"] = None
    with pytest.raises(ExperimentConfigError, match="grid.control .* synth.method2 is null"):
        build_config(d, ExperimentConfig).check()


def test_the_control_pool_has_no_flame_and_keeps_the_rest_of_the_method2_config() -> None:
    m2 = _config(max_flames=2).synth.method2
    control = control_config(m2)
    assert (control.negatives, control.own_frames, control.backgrounds, control.labelled_frames) == (1.0, 1.0, (), ())
    assert control.flames.source == "simulated"
    assert kept_settings(control) == kept_settings(m2)
    own = replace(m2, own_frames=0.5, flames=replace(m2.flames, source="cutouts"))
    assert control_config(own) == control  # the variants of a study share their control
    places = replace(m2, environments=(Path("panoramas"),), backgrounds=(Path("photos"),), background_holdout=0.25)
    looks = replace(m2, max_flames=1, flame_height_m=(0.5, 0.6), flames=replace(m2.flames, exposed=True))
    assert control_config(places) == control_config(looks) == control  # places and flame looks: one control
    assert control_config(replace(m2, camera=replace(m2.camera, defocus=0.9))) != control  # what acts on copies counts


def test_a_pool_on_photos_only_has_a_control() -> None:
    m2 = _config().synth.method2
    photos = replace(m2, environments=(), scenes=0, backgrounds=(Path("photos"),))
    control = control_config(photos)  # no environment, photo or frame left: its own frames are its places
    assert (control.environments, control.backgrounds, control.scenes, control.own_frames) == ((), (), 0, 1.0)


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, dict, dict, str]:
    """(data, control pools, mixture refs, printed) of the toy config with controls, nothing trained."""
    out = tmp_path_factory.mktemp("controls")
    cfg = _config()
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        grid = grid_entries(cfg)
        data = prepare_data(cfg, out, out, needed_methods(grid))
        datasets = Datasets(cfg.classes)
        controlled = [e.mixture for e in grid if e.method == CONTROL]
        pools = control_pools(cfg, controlled, data.real.with_split(cfg.real.train_split), datasets, out, out)
        refs = write_mixtures(cfg, grid, data, datasets, out, pools)
    return data, pools, refs, printed.getvalue()


def test_a_control_trains_on_copies_of_its_own_real_images_with_their_own_boxes_only(built) -> None:
    data, pools, refs, printed = built
    assert sorted(pools) == sorted((m, CONTROL, s) for s in SEEDS for m in ("R6_S6", "R6_S3"))
    real = read_coco(data.real.path).dataset
    boxes = real.annotations_by_image()
    real_boxes = {real.image_path(i).resolve().as_posix(): len(boxes[i.id]) for i in real.images}
    for (name, _, seed), pool in pools.items():
        assert f"{CONTROL} {name} seed {seed}: control pool {pool.path}" in printed
        mixture = refs[(name, CONTROL, seed)]
        record = json.loads((mixture.path / "mixture.json").read_text())
        assert record["images"] and record == json.loads(
            (refs[(name, "method2", seed)].path / "mixture.json").read_text()
        ) | {"images": record["images"]}
        trained = {e["from"] for e in record["images"] if e["source"].startswith("real:")}
        assert trained == {e["from"] for e in json.loads(
            (refs[(name, "method2", seed)].path / "mixture.json").read_text())["images"]
            if e["source"].startswith("real:")}  # the same real images as the mixture it controls  # fmt: skip
        per_image = json.loads((pool.path / "manifest.json").read_text())["args"]["per_image"]
        assert {Path(m["photo"]).resolve().as_posix() for m in per_image} <= trained
        ds = read_coco(pool.path).dataset
        own = sum(len(m["frame_boxes"]) for m in per_image)
        assert own > 0 and len(ds.annotations) == own  # no flame box: only the frames' own fire boxes
        assert all(len(m["frame_boxes"]) <= real_boxes[Path(m["photo"]).resolve().as_posix()] for m in per_image)


def test_mixtures_sharing_a_real_subset_share_a_control_pool(built) -> None:
    _, pools, refs, _ = built
    for seed in SEEDS:
        assert pools[("R6_S6", CONTROL, seed)] == pools[("R6_S3", CONTROL, seed)]
        assert refs[("R6_S6", CONTROL, seed)].path.parent.parent.name.startswith(f"{CONTROL}-")
    assert pools[("R6_S6", CONTROL, 0)] != pools[("R6_S6", CONTROL, 1)]


def _matches(path: Path, found: int) -> str:
    """The pycocotools match table of 8 test images with one fire box each, of which a model found ``found``
    exactly (score 0.9), saved at ``path``."""
    b = DatasetBuilder(path.parent, ["fire"])
    records = []
    for i in range(8):
        image_id = b.add_image(f"{i}.jpg", 100, 100)
        b.add_box(image_id, "fire", (10.0, 10.0, 40.0, 40.0))
        if i < found:
            records.append({"image_id": image_id, "category_id": 1, "bbox": [10.0, 10.0, 40.0, 40.0], "score": 0.9})
    MatchTable(run_cocoeval(b.build(), records, [1])).save(path)
    return path.as_posix()


def _rows(tmp_path: Path, control: bool) -> list[dict]:
    rows = []
    found = {"R6_S0": 3, "R6_S6": 6, "R6_S6 copies": 4}
    for key, k in found.items():
        if key.endswith("copies") and not control:
            continue
        for seed in SEEDS:
            folder = tmp_path / key.replace(" ", "-") / str(seed)
            folder.mkdir(parents=True, exist_ok=True)
            rows.append({"mixture": key.split()[0], "seed": seed, "test_set": "common",
                         "tables": [CONTROL_TABLE if key.endswith("copies") else "table2"],
                         "matches": _matches(folder / "matches.npz", k)})  # fmt: skip
    return rows


def test_each_mixture_is_compared_with_its_control_and_the_rest_is_unchanged(tmp_path: Path) -> None:
    cfg = replace(_config(), report=replace(_config().report, bootstrap=50, baseline="R6_S0"))
    with_control = comparisons(cfg, _rows(tmp_path, True))
    without = comparisons(cfg, _rows(tmp_path, False))
    assert [(c["mixture"], c["baseline"]) for c in without] == [("R6_S6", "R6_S0")] * len(without)
    assert with_control[: len(without)] == without  # the baseline comparisons keep their numbers
    versus = {c["metric"]: c["delta"] for c in with_control[len(without) :]}
    assert {c["baseline"] for c in with_control[len(without) :]} == {"R6_S6 copies"}
    assert versus["AP50"]["value"] == pytest.approx((76 - 51) / 101)  # recall 6/8 vs 4/8 at precision 1, 101 points


def test_a_study_with_controls_trains_reports_and_compares_them(tmp_path: Path) -> None:
    """End to end with the fake ``yolo`` engine: the control run has its folder, its table and its comparison;
    the other runs are the runs of the study without controls (same hashes, not trained again)."""
    from factories_experiment import command_engine

    from fuzzyfire.executors import LocalExecutor
    from fuzzyfire.experiment import run_experiment

    def study(control: bool) -> ExperimentConfig:
        d = toy_dict(mixtures=["R6_S0", "R6_S6"], table1=[])
        d["grid"]["control"] = control
        d["synth"]["method1"] = None
        d.update(
            rare=None,
            engine=command_engine(),
            report={"bootstrap": 20, "samples": False, "gap_draws": 0, "min_fire_images": 1},
        )
        return build_config(d, ExperimentConfig)

    out = tmp_path / "study"
    plain = run_experiment(study(False), tmp_path, out, LocalExecutor())
    before = sorted(p.parent.name for p in (out / "runs").glob("*/*/results.json"))
    done = run_experiment(study(True), tmp_path, out, LocalExecutor())
    assert not plain.failed and not done.failed
    runs = sorted(p.parent.parent.name for p in (out / "runs").glob("*/*/results.json"))
    assert runs == ["R6_S0", "R6_S6-copies", "R6_S6-method2"]
    assert set(before) < {p.parent.name for p in (out / "runs").glob("*/*/results.json")}
    plain_rows = [{k: v for k, v in r.items() if k != "imagelevel"} for r in plain.rows]  # arrays: not comparable
    assert [
        {k: v for k, v in r.items() if k != "imagelevel"} for r in done.rows if "table2" in r["tables"]
    ] == plain_rows
    assert "| R6_S6 copies |" in (out / "tables" / "controls.md").read_text()
    assert "| R6_S6 copies |" in table_text(out)  # what `fuzzyfire experiment` prints at the end
    compared = (out / "tables" / "comparisons.csv").read_text().splitlines()
    assert any(line.startswith("common (stand-in),R6_S6,R6_S6 copies,AP50,") for line in compared)
    assert "Controls — the synthetic images replaced by flame-free copies" in (out / "report.html").read_text()

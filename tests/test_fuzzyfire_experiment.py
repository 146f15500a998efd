"""The experiment end to end on a toy grid: stages, mixtures, runs, report (with a fire-free test set and its
alarm column); resume after an interruption skips finished runs; the same seeds give byte-identical results.json
in another folder; stand-in data says so; a test set added to a finished study is scored without training."""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import replace
from pathlib import Path

import pytest
import yaml
from factories_experiment import toy_config, write_toy_config

import fuzzyfire.experiment as experiment
from eval.errors import ALARMS
from fuzzyfire.cli import main
from fuzzyfire.executors import LocalExecutor
from fuzzyfire.experiment import GridEntry, grid_entries, needed_methods, run_experiment
from fuzzyfire.experiment_config import ExperimentConfig
from fuzzyfire.stages import label

RUNS = ["R12_S0", "R6_S6-method2", "R0_S12-method1", "R0_S12-method2"]


def test_grid_entries_dedupe_name_their_tables_and_need_only_used_methods() -> None:
    cfg = toy_config(mixtures=["R12_S0", "R6_S6", "R0_S12"], table1=["R0_S12"])
    assert grid_entries(cfg) == [
        GridEntry("R12_S0", None, ("table2",)),
        GridEntry("R6_S6", "method2", ("table2",)),
        GridEntry("R0_S12", "method2", ("table2", "table1")),  # Table 2's synthetic-only run is Method 2's Table 1 row
        GridEntry("R0_S12", "method1", ("table1",)),
    ]
    assert needed_methods(grid_entries(cfg)) == ["method1", "method2"]
    assert needed_methods(grid_entries(toy_config(mixtures=["R12_S0"], table1=[]))) == []
    with pytest.raises(ValueError, match="Table 1 compares synthetic-only"):
        grid_entries(toy_config(table1=["R6_S6"]))


def test_labels_say_stand_in_once() -> None:
    assert label("common", True) == "common (stand-in)" and label("rare (stand-in)", True) == "rare (stand-in)"
    assert label("common", False) == "common"


@pytest.fixture(scope="module")
def full_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, Counter]:
    """The toy grid run through the CLI (4 runs); returns the folder, what the command printed and how often
    each dataset folder was read (every read of the dataset registry counted)."""
    import contextlib

    import ground.data.formats.registry as registry

    root = tmp_path_factory.mktemp("experiment")
    config = write_toy_config(root / "toy.yaml", fire_free=True)
    capture = root / "stdout.txt"
    reads: Counter = Counter()
    real_read = registry.read_coco

    def counting(path, **kwargs):
        reads[Path(path).resolve()] += 1
        return real_read(path, **kwargs)

    with pytest.MonkeyPatch.context() as mp, open(capture, "w") as fh, contextlib.redirect_stdout(fh):
        for name in ("read_yolo", "read_voc", "read_dfire"):  # the toy study is COCO only: anything else is a bug
            mp.setattr(registry, name, lambda *a, **k: pytest.fail(f"unexpected read {a}"))
        mp.setattr(registry, "read_coco", counting)
        code = main(["experiment", str(config), "--out", str(root / "A")])
    assert code == 0
    return root / "A", capture.read_text(), reads


@pytest.mark.slow
def test_each_dataset_is_read_once(full_run: tuple[Path, str, Counter]) -> None:
    """The real, rare and synthetic sets are read once for the whole study (checks, mixtures, every run's
    validation and test sets, the report); each mixture once, by its run."""
    out, _, reads = full_run
    data = {p.resolve() for p in (out / "data").glob("*-*") if p.is_dir()}
    mixtures = {p.parent.resolve() for p in (out / "mixtures").rglob("mixture.json")}
    assert len(data) == 5 and len(mixtures) == 4  # real, rare, fire-free, method1, method2; one mixture per run
    assert set(reads) == data | mixtures
    assert all(count == 1 for count in reads.values()), {p.name: c for p, c in reads.items() if c > 1}


def _results(out: Path) -> dict[str, bytes]:
    """Each run's own results.json (not train/results.json, which records the git commit), by run folder."""
    return {
        p.parent.relative_to(out / "runs").as_posix(): p.read_bytes() for p in (out / "runs").glob("*/*/results.json")
    }


@pytest.mark.slow
def test_report_files_exist_and_say_stand_in(full_run: tuple[Path, str, Counter]) -> None:
    out, printed, _ = full_run
    for name in ("table1.md", "table1.csv", "table1.tex", "table2.md", "table2.csv", "table2.tex"):
        assert (out / "tables" / name).stat().st_size > 0
        assert "(stand-in)" in (out / "tables" / name).read_text()
    figures = {p.name for p in (out / "figures").iterdir()}
    at_budget = {"figure5_recall_at_10_alarms.png", "operating_common__stand_in.png",
                 "image_operating_common__stand_in.png"}  # the rare stand-in has no box  # fmt: skip
    assert figures == {"figure5_AP.png", "figure5_AP50.png", "figure5_alarms_per_100.png", *at_budget}
    page = (out / "report.html").read_text()
    answer = (out / "answer.md").read_text()  # the report's first section, and the command's last lines
    assert page.index("<h2>The answer</h2>") < page.index("<h2>Table 2") and answer.startswith(
        "- Caveat first: 2 of 2 runs did not converge"
    )
    first = answer.split("### Details")[0]  # the first screen: what was compared, the classes, the leakage check
    assert "Compared over 1 seed: R12_S0 = 12 real training images; R6_S6 = the same 6 + 6 synthetic" in first
    assert "Classes studied: fire (as the config names them)" in first and "Leakage check" in first
    assert "- Best on common" in answer.split("### Details")[1]
    assert "R6_S6 against R12_S0" in answer and answer.splitlines()[0][2:] in printed
    assert json.loads((out / "leakage.json").read_text())["action"] == "drop"
    assert "STAND-IN DATA" in page and "Paired comparisons" in page and "R6_S6" in page
    gaps = json.loads((out / "tables" / "gap.json").read_text())["gaps"]
    assert [g["method"] for g in gaps] == ["method1", "method2"] and "Realism gap" in page
    assert all(g["frechet"]["synthetic"]["median"] > 0 for g in gaps)
    assert "STAND-IN DATA" in printed and f"report: {out.resolve() / 'report.html'}" in printed
    assert "**Table 2" in printed and "common (stand-in) AP" in printed and "fire-free (stand-in) alarms/100" in printed
    for table in ("table1.md", "table2.md"):  # the negatives set has one column: its alarm rate
        head = (out / "tables" / table).read_text().splitlines()[2]
        assert "fire-free (stand-in) alarms/100" in head and "fire-free (stand-in) AP" not in head
    assert "fire-free (stand-in) alarms/100" in page and "Samples: fire-free (stand-in)" in page
    pool = page.index("<h2>Samples: synthetic")  # the pools' thumbnails right under the answer's first screen
    assert page.index("<h2>The answer</h2>") < pool < page.index("<h2>Table 2")
    summary = json.loads((out / "experiment.json").read_text())
    assert summary["standin"] is True and [r["status"] for r in summary["runs"]] == ["done"] * 4
    rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    sets = {"common (stand-in)", "rare (stand-in)", "fire-free (stand-in)"}
    assert len(rows) == 12 and {r["test_set"] for r in rows} == sets
    free = [r for r in rows if r["test_set"] == "fire-free (stand-in)"]
    assert len(free) == 4 and all(r["AP"] is None and ALARMS in r for r in free)
    # a toy run that detects nothing at 0.25 anywhere has its false alarms not measured (None), never 0.0
    assert all((r[ALARMS] is None) == bool(r.get("silent")) and (r[ALARMS] or 0) >= 0 for r in free)
    common = [r for r in rows if r["test_set"] == "common (stand-in)"]  # read at 10 alarms per 100 fire-free images
    assert len(common) == 4 and all(0 <= r["recall_at_10_alarms"] <= 1 and "operating" not in r for r in common)
    assert "common (stand-in) recall@10 alarms/100" in page and "Fire found against false alarms" in page
    for run in (out / "runs").glob("*/*/results.json"):  # a set without boxes has its breakdown's alarm rate
        tests = json.loads(run.read_text())["tests"]
        for scored in tests.values():  # (the toy's rare stand-in has no box big enough to label either)
            breakdown = json.loads((run.parent / scored["scores"] / "errors.json").read_text())
            assert scored.get(ALARMS) == (breakdown["false_alarms_per_100_negatives"] if not scored["boxes"] else None)
        assert tests["fire-free (stand-in)"]["images"] == 6 and tests["common (stand-in)"]["boxes"] > 0
    assert sorted({k.split("/")[0] for k in _results(out)}) == sorted(RUNS)
    assert (out / "data").is_dir() and len(list((out / "data").glob("*/stage.json"))) == 5
    for data_yaml in (out / "mixtures").rglob("data.yaml"):  # ultralytics validates on the real valid split
        assert Path(yaml.safe_load(data_yaml.read_text())["val"]).parts[-2:] == ("images", "valid")
    errors = sorted((out / "runs").glob("*/*/scores/*/errors.json"))
    assert len(errors) == 12 and "Where AP50 goes" in page
    first = json.loads(errors[0].read_text())
    assert set(first["delta_AP50"]) == {"classification", "localisation", "both", "duplicate", "background", "missed"}


@pytest.mark.slow
def test_report_gives_runs_scored_before_the_breakdown_theirs(full_run: tuple[Path, str, Counter]) -> None:
    """A run scored without errors.json gets it from its predictions.json: the same numbers as at run time."""
    out, _, _ = full_run
    path = sorted((out / "runs").glob("*/*/scores/*/errors.json"))[0]
    at_run_time = json.loads(path.read_text())
    path.unlink()
    run_experiment(toy_config(fire_free=True), out.parent, out)  # report only
    assert json.loads(path.read_text()) == at_run_time


@pytest.mark.slow
def test_runs_scored_before_ap25_get_it_from_their_predictions(full_run: tuple[Path, str, Counter]) -> None:
    """A results.json without AP25 (as runs scored before it existed have) gets the run-time value back from the
    run's predictions.json, kept in scores/<test>/ap25.json."""
    out, _, _ = full_run
    path = sorted((out / "runs").glob("*/*/results.json"))[0]
    original = path.read_bytes()
    doc = json.loads(original)
    at_run_time = {name: m["AP25"] for name, m in doc["tests"].items() if ALARMS not in m}  # sets with fire
    try:
        for m in doc["tests"].values():
            del m["AP25"]
        path.write_text(json.dumps(doc))
        run_experiment(toy_config(fire_free=True), out.parent, out)  # report only
        run = path.parent.relative_to(out).as_posix()
        rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
        ap25 = {r["test_set"]: r["AP25"] for r in rows if r["run"] == run and r["test_set"] in at_run_time}
        assert ap25 == pytest.approx(at_run_time)
        assert len(list(path.parent.glob("scores/*/ap25.json"))) == len(at_run_time)
    finally:
        path.write_bytes(original)
        for extra in path.parent.glob("scores/*/ap25.json"):
            extra.unlink()


@pytest.mark.slow
def test_interrupted_grid_resumes_and_gives_identical_results(
    full_run: tuple[Path, str, Counter], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "B"
    real_execute = experiment.execute_task
    calls: list[str] = []

    def interrupted(task):
        if len(calls) == 2:
            raise KeyboardInterrupt  # Ctrl-C before the third run
        calls.append(task.spec.label)
        return real_execute(task)

    monkeypatch.setattr(experiment, "execute_task", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_experiment(toy_config(fire_free=True), tmp_path, out, LocalExecutor())
    first = _results(out)
    assert len(first) == 2
    stamps = {p: p.stat().st_mtime_ns for p in (out / "runs").glob("*/*/results.json")}
    partial = run_experiment(toy_config(fire_free=True), tmp_path, out)  # no executor: the finished runs only
    assert len(partial.failed) == 2 and len(partial.rows) == 6 and partial.report.is_file()

    skipped: list[bool] = []

    def recording(task):
        result = real_execute(task)
        skipped.append(result["skipped"])
        return result

    monkeypatch.setattr(experiment, "execute_task", recording)
    result = run_experiment(toy_config(fire_free=True), tmp_path, out, LocalExecutor())
    assert skipped == [True, True, False, False] and not result.failed
    assert all(p.stat().st_mtime_ns == t for p, t in stamps.items())  # finished runs untouched
    assert _results(out) == _results(full_run[0])  # same seeds, another folder: byte-identical results.json


def test_missing_test_split_fails_before_training(tmp_path: Path) -> None:
    from dataclasses import replace

    from factories_train import painted_dataset

    from fuzzyfire.experiment_config import RealConfig
    from ground.data.writer import write_dataset

    ds = painted_dataset(tmp_path / "src", 6, seed=0)
    images = tuple(replace(img, split="train" if img.id <= 4 else "valid") for img in ds.images)
    write_dataset(replace(ds, images=images), tmp_path / "real", ("coco",))
    cfg = replace(toy_config(mixtures=["R4_S0"], table1=[]), real=RealConfig(path=tmp_path / "real"), rare=None)
    with pytest.raises(ValueError, match="no split 'test'"):
        run_experiment(cfg, tmp_path, tmp_path / "out", LocalExecutor())
    assert not (tmp_path / "out" / "runs").exists()


def _fake_yolo_study(**doc) -> ExperimentConfig:
    """One run (R12_S0, seed 0) of the fake ``yolo`` engine on the toy's stand-in, no pools, no rare set."""
    from factories_experiment import command_engine, toy_dict

    from ground.config.loader import build_config

    base = {**toy_dict(mixtures=["R12_S0"], table1=[]), "rare": None, "engine": command_engine()}
    base["report"] = {"bootstrap": 0, "samples": False, "gap_draws": 0}
    return build_config({**base, **doc}, ExperimentConfig)


def test_a_test_set_added_to_a_finished_study_is_scored_without_training(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """The run keeps its identity and folder; --report-only says what is not scored yet; the next call scores the
    run's model on the new set, trains nothing, and the tables gain its alarm column."""
    from factories_experiment import fire_free_photos

    out = tmp_path / "study"
    first = run_experiment(_fake_yolo_study(), tmp_path, out, LocalExecutor())
    [run] = list((out / "runs").glob("*/*/results.json"))
    log = run.parent / "train" / "command.log"
    stamp = log.stat().st_mtime_ns
    fire_free_photos(tmp_path / "photos", 5)
    cfg = _fake_yolo_study(tests={"fire-free": {"path": "photos"}})
    capsys.readouterr()
    pending = run_experiment(cfg, tmp_path, out)  # report only
    assert "fire-free: 1 finished runs not scored on it yet" in capsys.readouterr().out
    assert [r["test_set"] for r in pending.rows] == [r["test_set"] for r in first.rows] == ["common (stand-in)"]
    done = run_experiment(cfg, tmp_path, out, LocalExecutor())
    assert "(trained before; scored now on fire-free)" in capsys.readouterr().out
    assert list((out / "runs").glob("*/*/results.json")) == [run] and log.stat().st_mtime_ns == stamp
    free = next(r for r in done.rows if r["test_set"] == "fire-free")
    assert free["AP"] is None and free[ALARMS] == 100.0  # the fake detector: one box at 0.5 in every photo
    assert "| fire-free alarms/100 |" in (out / "tables" / "table2.md").read_text()
    run_experiment(cfg, tmp_path, out, LocalExecutor())
    assert "(done before)" in capsys.readouterr().out


def test_no_test_set_changes_a_run_identity(tmp_path: Path) -> None:
    """Adding named sets, or dropping a test set's leaked images, changes no run's hash: no test set is in the
    identity (a test set does not change the model)."""
    from fuzzyfire.datasets import DataRef
    from fuzzyfire.experiment import plan_runs
    from fuzzyfire.stages import Prepared

    plain, named = toy_config(), toy_config(fire_free=True)
    ref = DataRef(tmp_path, {"kind": "standin", "hash": "x"}, "coco", standin=True)
    mixtures = {(e.mixture, e.method, 0): ref for e in grid_entries(plain)}
    pools = {"method1": ref, "method2": ref}
    before = plan_runs(plain, grid_entries(plain), Prepared(ref, ref, pools), mixtures, tmp_path)
    after = plan_runs(named, grid_entries(named), Prepared(ref, ref, pools, {"fire-free": ref}), mixtures, tmp_path)
    assert [s.hash() for s in before] == [s.hash() for s in after] and all(not s.evals for s in before)
    assert all([t.name for t in s.evals] == ["fire-free"] for s in after)
    assert set(before[0].identity()) == {"mixture", "method", "seed", "train_data", "val_data", "classes", "train",
                                         "score"}  # fmt: skip
    narrowed = replace(ref, exclude=("images/test/000001.jpg",))
    leaked = plan_runs(plain, grid_entries(plain), Prepared(ref, narrowed, pools), mixtures, tmp_path)
    assert [s.hash() for s in leaked] == [s.hash() for s in before] and leaked[0].tests[1].data.exclude


def test_real_finetune_reaches_only_the_runs_with_real_and_synthetic_images(tmp_path: Path) -> None:
    """Real-only and synthetic-only runs keep their identity (the setting changes nothing for them)."""
    from fuzzyfire.datasets import DataRef
    from fuzzyfire.experiment import plan_runs
    from fuzzyfire.stages import Prepared

    plain = toy_config()
    tuned = replace(plain, train=replace(plain.train, real_finetune=1))
    ref = DataRef(tmp_path, {"kind": "standin", "hash": "x"}, "coco", standin=True)
    mixtures = {(e.mixture, e.method, 0): ref for e in grid_entries(plain)}
    prepared = Prepared(ref, ref, {"method1": ref, "method2": ref})
    before = plan_runs(plain, grid_entries(plain), prepared, mixtures, tmp_path)
    after = plan_runs(tuned, grid_entries(tuned), prepared, mixtures, tmp_path)
    mixed = {s.mixture for s in before if "R0_" not in s.mixture and not s.mixture.endswith("_S0")}
    assert mixed and {s.mixture for s in before} - mixed  # the toy grid has both kinds of run
    for a, b in zip(before, after):
        assert (a.hash() == b.hash()) == (a.mixture not in mixed)
        assert b.train.real_finetune == (1 if a.mixture in mixed else 0)


def test_image_labelled_test_sets_report_image_recall_and_an_undeclared_folder_says_negatives(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """A classification layout (fire/ + normal/) and a folder declared ``label: fire`` are image-labelled test
    sets: no AP, image recall (the fake detector finds one box in every image: every fire image at 0.25) in the
    rows, Table 2 and the comparisons (image recall only); an undeclared folder without label files is read as
    negatives and the experiment says so."""
    from detector_factories import write_class_layout
    from factories_experiment import FLAMES, SIZE, fire_free_photos

    from eval.imagelevel import IMAGE_LABELLED, IMAGE_RECALL, IMAGE_RECALL_AT_CONF

    write_class_layout(tmp_path / "layout", (40, 80, 120, 160), (200, 240))
    fire_free_photos(tmp_path / "photos", 4)
    cfg = _fake_yolo_study(
        grid={"mixtures": ["R12_S0", "R6_S0"], "table1": [], "seeds": [0]},
        report={"bootstrap": 20, "samples": False, "gap_draws": 0, "min_fire_images": 1},
        tests={"broad": {"path": "layout"}, "declared": {"path": "layout/fire", "label": "fire"},
               "photos": {"path": "photos"}, "stand": {"standin": {"splits": {"test": 6}, "seed": 3, "negatives": 0.5, **SIZE, **FLAMES},
                         "label": "fire"}},
    )  # fmt: skip
    done = run_experiment(cfg, tmp_path, tmp_path / "out", LocalExecutor())
    printed = capsys.readouterr().out
    assert "data   test broad: classification layout: fire/ 4 images (fire), normal/ 2 images (no class)" in printed
    assert "data   test declared: 4 images, each declared 'fire' (label: fire): an image-labelled set" in printed
    assert "data   test photos: 4 images, no label files: a negatives-only set" in printed and "label: fire" in printed
    assert "data   test stand (stand-in): a stand-in read at the image level: " in printed
    for name in ("broad", "declared", "stand (stand-in)"):
        rows = [r for r in done.rows if r["test_set"] == name]
        assert len(rows) == 2 and all(r["AP"] is None and r["AP50"] is None and r[IMAGE_LABELLED] for r in rows)
        assert all(r["fire_images"] == (4 if name != "stand (stand-in)" else rows[0]["fire_images"]) for r in rows)
        assert all(0 < r["fire_images"] and r[IMAGE_RECALL_AT_CONF] == 1.0 for r in rows)
        assert all(r[IMAGE_RECALL] is not None and ALARMS not in r for r in rows)
    assert all(r[ALARMS] == 100.0 for r in done.rows if r["test_set"] == "photos")
    compared = (tmp_path / "out" / "tables" / "comparisons.csv").read_text().splitlines()
    for name in ("broad", "declared"):
        assert [line.split(",")[3] for line in compared if line.startswith(f"{name},")] == [IMAGE_RECALL]
    table = (tmp_path / "out" / "tables" / "table2.md").read_text()
    assert "broad" in table and "declared" in table


def test_pools_box_smoke_exactly_when_smoke_is_a_studied_class() -> None:
    from fuzzyfire.experiment_config import ExperimentConfigError

    cfg = toy_config(mixtures=["R6_S6"], table1=[], seeds=[0])
    fire = replace(cfg, classes=("fire",))
    assert experiment.pools_box_classes(fire) == fire and not fire.synth.method2.smoke_class
    both = experiment.pools_box_classes(replace(cfg, classes=("fire", "smoke")))
    assert all(both.synth.section(m).smoke_class for m in ("method1", "method2") if both.synth.section(m))
    told = replace(fire, synth=replace(fire.synth, method2=replace(fire.synth.method2, smoke_class=True)))
    with pytest.raises(ExperimentConfigError, match="synth.method2.smoke_class is true but smoke is not a studied"):
        experiment.pools_box_classes(told)


def test_too_few_real_training_images_fail_before_any_pool_is_built(tmp_path: Path) -> None:
    from dataclasses import replace

    from factories_train import painted_dataset

    from fuzzyfire.experiment_config import RealConfig
    from ground.data.writer import write_dataset

    ds = painted_dataset(tmp_path / "src", 8, seed=0)
    images = tuple(replace(img, split=("train", "train", "train", "train", "valid", "test")[min(img.id, 6) - 1])
                   for img in ds.images)  # fmt: skip
    write_dataset(replace(ds, images=images), tmp_path / "real", ("coco",))
    cfg = replace(
        toy_config(mixtures=["R6_S0", "R6_S6"], table1=[]), real=RealConfig(path=tmp_path / "real"), rare=None
    )
    with pytest.raises(ValueError, match=r"R6_S0 asks for 6 real training images but .* holds 4 in its 'train' split"):
        run_experiment(cfg, tmp_path, tmp_path / "out", LocalExecutor())
    assert not (tmp_path / "out" / "data").exists() or not any((tmp_path / "out" / "data").glob("method2-*"))
    assert not (tmp_path / "out" / "runs").exists()

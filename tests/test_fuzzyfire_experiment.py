"""The experiment end to end on a toy grid: stages, mixtures, runs, report; resume after an interruption skips
finished runs; the same seeds give byte-identical results.json in another folder; stand-in data says so."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest
import yaml
from factories_experiment import toy_config, write_toy_config

import fuzzyfire.experiment as experiment
from fuzzyfire.cli import main
from fuzzyfire.executors import LocalExecutor
from fuzzyfire.experiment import GridEntry, grid_entries, needed_methods, run_experiment
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

    import curate.core.formats.registry as registry

    root = tmp_path_factory.mktemp("experiment")
    config = write_toy_config(root / "toy.yaml")
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
    assert len(data) == 4 and len(mixtures) == 4  # real, rare, method1, method2; one mixture per run
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
    assert {p.name for p in (out / "figures").iterdir()} == {"figure5_AP.png", "figure5_AP50.png"}
    page = (out / "report.html").read_text()
    assert "STAND-IN DATA" in page and "Paired comparisons" in page and "R6_S6" in page
    gaps = json.loads((out / "tables" / "gap.json").read_text())["gaps"]
    assert [g["method"] for g in gaps] == ["method1", "method2"] and "Realism gap" in page
    assert all(g["frechet"]["synthetic"]["median"] > 0 for g in gaps)
    assert "STAND-IN DATA" in printed and f"report: {out.resolve() / 'report.html'}" in printed
    assert "**Table 2" in printed and "common (stand-in) AP" in printed
    summary = json.loads((out / "experiment.json").read_text())
    assert summary["standin"] is True and [r["status"] for r in summary["runs"]] == ["done"] * 4
    rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert len(rows) == 8 and {r["test_set"] for r in rows} == {"common (stand-in)", "rare (stand-in)"}
    assert sorted({k.split("/")[0] for k in _results(out)}) == sorted(RUNS)
    assert (out / "data").is_dir() and len(list((out / "data").glob("*/stage.json"))) == 4
    for data_yaml in (out / "mixtures").rglob("data.yaml"):  # ultralytics validates on the real valid split
        assert Path(yaml.safe_load(data_yaml.read_text())["val"]).parts[-2:] == ("images", "valid")
    errors = sorted((out / "runs").glob("*/*/scores/*/errors.json"))
    assert len(errors) == 8 and "Where AP50 goes" in page
    first = json.loads(errors[0].read_text())
    assert set(first["delta_AP50"]) == {"classification", "localisation", "both", "duplicate", "background", "missed"}


@pytest.mark.slow
def test_report_gives_runs_scored_before_the_breakdown_theirs(full_run: tuple[Path, str, Counter]) -> None:
    """A run scored without errors.json gets it from its predictions.json: the same numbers as at run time."""
    out, _, _ = full_run
    path = sorted((out / "runs").glob("*/*/scores/*/errors.json"))[0]
    at_run_time = json.loads(path.read_text())
    path.unlink()
    run_experiment(toy_config(), out.parent, out)  # report only
    assert json.loads(path.read_text()) == at_run_time


@pytest.mark.slow
def test_runs_scored_before_ap25_get_it_from_their_predictions(full_run: tuple[Path, str, Counter]) -> None:
    """A results.json without AP25 (as runs scored before it existed have) gets the run-time value back from the
    run's predictions.json, kept in scores/<test>/ap25.json."""
    out, _, _ = full_run
    path = sorted((out / "runs").glob("*/*/results.json"))[0]
    original = path.read_bytes()
    doc = json.loads(original)
    at_run_time = {name: m["AP25"] for name, m in doc["tests"].items()}
    try:
        for m in doc["tests"].values():
            del m["AP25"]
        path.write_text(json.dumps(doc))
        run_experiment(toy_config(), out.parent, out)  # report only
        run = path.parent.relative_to(out).as_posix()
        rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
        assert {r["test_set"]: r["AP25"] for r in rows if r["run"] == run} == pytest.approx(at_run_time)
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
        run_experiment(toy_config(), tmp_path, out, LocalExecutor())
    first = _results(out)
    assert len(first) == 2
    stamps = {p: p.stat().st_mtime_ns for p in (out / "runs").glob("*/*/results.json")}
    partial = run_experiment(toy_config(), tmp_path, out)  # no executor: report the finished runs only
    assert len(partial.failed) == 2 and len(partial.rows) == 4 and partial.report.is_file()

    skipped: list[bool] = []

    def recording(task):
        result = real_execute(task)
        skipped.append(result["skipped"])
        return result

    monkeypatch.setattr(experiment, "execute_task", recording)
    result = run_experiment(toy_config(), tmp_path, out, LocalExecutor())
    assert skipped == [True, True, False, False] and not result.failed
    assert all(p.stat().st_mtime_ns == t for p, t in stamps.items())  # finished runs untouched
    assert _results(out) == _results(full_run[0])  # same seeds, another folder: byte-identical results.json


def test_missing_test_split_fails_before_training(tmp_path: Path) -> None:
    from dataclasses import replace

    from factories_train import painted_dataset

    from curate.core.writer import write_dataset
    from fuzzyfire.experiment_config import RealConfig

    ds = painted_dataset(tmp_path / "src", 6, seed=0)
    images = tuple(replace(img, split="train" if img.id <= 4 else "valid") for img in ds.images)
    write_dataset(replace(ds, images=images), tmp_path / "real", ("coco",))
    cfg = replace(toy_config(mixtures=["R4_S0"], table1=[]), real=RealConfig(path=tmp_path / "real"), rare=None)
    with pytest.raises(ValueError, match="no split 'test'"):
        run_experiment(cfg, tmp_path, tmp_path / "out", LocalExecutor())
    assert not (tmp_path / "out" / "runs").exists()

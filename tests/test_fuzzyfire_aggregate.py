"""Aggregation: which runs feed Table 1 and Table 2, and when comparisons are skipped."""

from __future__ import annotations

from pathlib import Path

from factories_experiment import toy_config

from fuzzyfire.aggregate import comparisons, result_rows
from fuzzyfire.experiment_config import ScoreConfig
from fuzzyfire.runs import RunSpec
from fuzzyfire.stages import DataRef
from train.config import TrainConfig


def _spec(out: Path, mixture: str, method: str | None, seed: int = 0) -> RunSpec:
    ref = DataRef(Path("/d"), {"kind": "x"})
    folder = out / "runs" / mixture / f"seed{seed}"
    return RunSpec(mixture, method, seed, ref, ref, (), ("fire",), TrainConfig(), ScoreConfig(), folder)


def _result(ap: float) -> dict:
    test = {"AP": ap, "AP50": 2 * ap, "scores": "scores/common"}
    return {"tests": {"common": test, "rare": {**test, "scores": "scores/rare"}}}


def test_rows_are_sorted_into_the_two_tables(tmp_path: Path) -> None:
    cfg = toy_config(mixtures=["R12_S0", "R6_S6", "R0_S12"], table1=["R0_S12"])
    specs = [
        _spec(tmp_path, "R12_S0", None),
        _spec(tmp_path, "R6_S6", "method2"),
        _spec(tmp_path, "R0_S12", "method2"),
        _spec(tmp_path, "R0_S12", "method1"),
        _spec(tmp_path, "R6_S6", "method2", seed=1),
    ]
    results = [_result(0.1), _result(0.2), _result(0.3), _result(0.4), None]  # the last run failed
    rows = result_rows(cfg, specs, results, tmp_path)
    assert len(rows) == 8
    tables = {(r["mixture"], r["method"]): r["tables"] for r in rows}
    assert tables == {
        ("R12_S0", "-"): ["table2"],
        ("R6_S6", "method2"): ["table2"],
        ("R0_S12", "method2"): ["table2", "table1"],  # the Table 2 synthetic-only run is Method 2's Table 1 row
        ("R0_S12", "method1"): ["table1"],
    }
    first = rows[0]
    assert first["run"] == "runs/R12_S0/seed0" and first["AP50"] == 0.2
    assert first["matches"].endswith("runs/R12_S0/seed0/scores/common/matches.npz")


def test_no_comparisons_without_bootstrap_or_baseline(tmp_path: Path) -> None:
    specs = [_spec(tmp_path, "R6_S6", "method2")]
    rows = result_rows(toy_config(mixtures=["R6_S6"]), specs, [_result(0.1)], tmp_path)
    assert comparisons(toy_config(mixtures=["R6_S6"]), rows) == []  # no real-only mixture: no baseline
    cfg = toy_config(mixtures=["R12_S0", "R6_S6"])
    no_bootstrap = cfg.__class__(**{**cfg.__dict__, "report": cfg.report.__class__(bootstrap=0)})
    assert comparisons(no_bootstrap, rows) == []

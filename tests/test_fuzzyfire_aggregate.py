"""Aggregation: rows carry the tables their run's spec names, and when comparisons are skipped; a named set
without fire gives rows with its alarm rate and no comparison."""

from __future__ import annotations

from pathlib import Path

import pytest
from factories_experiment import toy_config

from eval.score import ScoreConfig
from fuzzyfire.aggregate import comparisons, result_rows
from fuzzyfire.runs import EvalSet, RunSpec
from fuzzyfire.stages import DataRef
from train.config import TrainConfig


def _spec(out: Path, mixture: str, method: str | None, seed: int = 0, tables: tuple[str, ...] = ()) -> RunSpec:
    ref = DataRef(Path("/d"), {"kind": "x"})
    train = TrainConfig(seed=seed)
    tests = (EvalSet("common", ref), EvalSet("rare", ref))
    return RunSpec(mixture, method, ref, ref, tests, ("fire",), train, ScoreConfig(), out, tables=tables)


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
    monkeypatch.setattr(stats, "paired_bootstrap", lambda *a: {})
    assert comparisons(toy_config(mixtures=["R12_S0", "R6_S6"]), rows) == []
    assert sorted(set(loaded)) == ["common", "rare"]  # no AP on the set without fire: nothing to compare


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

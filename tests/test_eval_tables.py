"""Tables 1 and 2: grouping and order, mean ± std over seeds, best bold / second italic in every format; a set
without fire as one alarm-rate column (per 100 images, lowest best)."""

from __future__ import annotations

import csv
import io

import pytest

from eval.errors import ALARMS
from eval.tables import marks, table1, table2, to_csv, to_latex, to_markdown


def results():
    """AP per (mixture, seed, test set): common is best for R500_S500, second for R1000_S0."""
    ap = {"R1000_S0": 0.50, "R500_S0": 0.40, "R750_S250": 0.45, "R500_S500": 0.55, "R0_S1000": 0.20}
    rare = {"R1000_S0": 0.10, "R500_S0": 0.05, "R750_S250": 0.30, "R500_S500": 0.25, "R0_S1000": 0.30}
    out = []
    for mix in ap:
        for seed, noise in ((0, -0.01), (1, 0.01)):
            out.append({"mixture": mix, "seed": seed, "test_set": "common", "AP": ap[mix] + noise, "AP50": 0.9})
            out.append({"mixture": mix, "seed": seed, "test_set": "rare", "AP": rare[mix] + noise, "AP50": None})
    return out


def test_table2_groups_strategies_in_the_papers_order():
    t = table2(results())
    assert [g for g, _ in t.row_groups] == ["Real only", "Real + synthetic", "Synthetic only"]
    assert t.rows == ["R500_S0", "R1000_S0", "R750_S250", "R500_S500", "R0_S1000"]
    cell = t.cell("R1000_S0", ("common", "AP"))
    assert cell.mean == pytest.approx(0.50) and cell.std == pytest.approx(0.02 / 2**0.5) and cell.n == 2
    assert t.cell("R1000_S0", ("rare", "AP50")) is None


def test_best_and_second_per_column_with_ties():
    mk = marks(table2(results()))
    assert mk[("R500_S500", "common/AP")] == "best" and mk[("R1000_S0", "common/AP")] == "second"
    assert mk[("R750_S250", "rare/AP")] == mk[("R0_S1000", "rare/AP")] == "best"  # a tie shares the mark
    assert mk[("R500_S500", "rare/AP")] == "second"
    assert all(mk[(row, "common/AP50")] == "best" for row in table2(results()).rows)
    assert ("R500_S0", "common/AP") not in mk


def test_markdown_latex_csv_mark_the_same_cells():
    t = table2(results())
    md = to_markdown(t)
    assert "| R500_S500 | **55.0 ± 1.4** |" in md and "| R1000_S0 | *50.0 ± 1.4* |" in md
    assert "| R500_S0 | 40.0 ± 1.4 |" in md and "–" in md
    tex = to_latex(t)
    assert r"R500\_S500 & \textbf{55.0 $\pm$ 1.4}" in tex and r"R1000\_S0 & \textit{50.0 $\pm$ 1.4}" in tex
    assert tex.startswith(r"\begin{tabular}{lcccc}") and r"\multicolumn{2}{c}{common}" in tex
    rows = list(csv.DictReader(io.StringIO(to_csv(t))))
    best = next(r for r in rows if r["row"] == "R500_S500")
    assert best["common AP rank"] == "best" and float(best["common AP mean"]) == pytest.approx(0.55)
    assert next(r for r in rows if r["row"] == "R500_S0")["common AP rank"] == ""


def test_table1_rows_per_method():
    res = [dict(r, method=m) for r in results() if r["mixture"] == "R0_S1000" for m in ("method1", "method2")]
    res = [dict(r, AP=r["AP"] + (0.1 if r["method"] == "method2" else 0.0)) for r in res]
    t = table1(res)
    assert [g for g, _ in t.row_groups] == ["Method 1 (3D)", "Method 2 (2D)"]
    md = to_markdown(t)
    assert "| *Method 2 (2D)* |" in md and "| R0_S1000 | **30.0 ± 1.4** |" in md
    assert marks(t)[("Method 1 (3D) R0_S1000", "common/AP")] == "second"


def _with_fire_free(rows):
    """``rows`` plus a fire-free set: false alarms per 100 images, fewest for R750_S250, AP undefined."""
    alarms = {"R1000_S0": 20.0, "R500_S0": 30.0, "R750_S250": 5.0, "R500_S500": 10.0, "R0_S1000": 80.0}
    extra = [
        {"mixture": m, "seed": s, "test_set": "fire-free", "AP": None, "AP50": None, ALARMS: a + 2 * s - 1}
        for m, a in alarms.items()
        for s in (0, 1)
    ]
    return [*rows, *extra]


def test_a_set_without_fire_has_one_column_its_alarm_rate_lowest_best():
    t = table2(_with_fire_free(results()), metrics=("AP", "AP50", "AP25"))
    assert [c for c in t.columns if c[0] == "fire-free"] == [("fire-free", ALARMS)]
    assert ("common", ALARMS) not in t.columns and ("common", "AP") in t.columns
    cell = t.cell("R750_S250", ("fire-free", ALARMS))
    assert cell.mean == pytest.approx(5.0) and cell.n == 2
    mk = marks(t)
    assert mk[("R750_S250", f"fire-free/{ALARMS}")] == "best" and mk[("R500_S500", f"fire-free/{ALARMS}")] == "second"
    assert ("R0_S1000", f"fire-free/{ALARMS}") not in mk
    md = to_markdown(t)  # per 100 images as they are, not in percent
    assert "fire-free alarms/100 |" in md.splitlines()[2] and "**5.0 ± 1.4**" in md and "80.0 ± 1.4" in md
    row = next(r for r in csv.DictReader(io.StringIO(to_csv(t))) if r["row"] == "R750_S250")
    assert float(row["fire-free alarms/100 mean"]) == pytest.approx(5.0) and row["fire-free alarms/100 rank"] == "best"
    assert r"\textbf{5.0 $\pm$ 1.4}" in to_latex(t) and "alarms/100" in to_latex(t)
    assert table2(results()).columns == table2(_with_fire_free(results())).columns[:4]  # the other sets unchanged


def test_a_study_of_several_classes_shows_each_classs_false_alarms_per_100_images():
    rows = [{**r, f"{ALARMS} fire": 1.0, f"{ALARMS} smoke": r[ALARMS] - 1.0} if r["test_set"] == "fire-free" else r
            for r in _with_fire_free(results())]  # fmt: skip
    t = table2(rows, metrics=("AP", "AP50"))
    shown = [c[1] for c in t.columns if c[0] == "fire-free"]
    assert shown == [ALARMS, f"{ALARMS} fire", f"{ALARMS} smoke"]
    assert t.cell("R750_S250", ("fire-free", f"{ALARMS} smoke")).mean == pytest.approx(4.0)
    assert "fire-free alarms/100 smoke |" in to_markdown(t).splitlines()[2]  # per 100 images, not in percent
    assert "4.0 ± 1.4" in to_markdown(t)
    assert marks(t)[("R750_S250", f"fire-free/{ALARMS} smoke")] == "best"  # the fewest alarms, as for all classes


def test_table1_has_the_alarm_column_too():
    res = [
        dict(r, method=m)
        for r in _with_fire_free(results())
        if r["mixture"] == "R0_S1000"
        for m in ("method1", "method2")
    ]
    t = table1(res)
    assert t.columns[-1] == ("fire-free", ALARMS) and t.cell("Method 1 (3D) R0_S1000", t.columns[-1]).mean == 80.0


def test_a_column_with_one_row_has_no_mark():
    one = [r for r in results() if r["mixture"] == "R500_S500"]
    assert marks(table2(one)) == {} and "| R500_S500 | 55.0 ± 1.4 |" in to_markdown(table2(one))


def test_a_mixture_with_a_run_that_did_not_converge_is_marked_in_every_format():
    from eval.tables import control_table

    rows = [dict(r, learning="still learning: …" if r["mixture"] == "R500_S0" and r["seed"] == 1 else None)
            for r in results()]  # fmt: skip
    t = table2(rows)
    assert t.label("R500_S0") == "R500_S0 (not converged)" and t.label("R1000_S0") == "R1000_S0"
    assert "| R500_S0 (not converged) |" in to_markdown(t) and "R500_S0 (not converged)" in to_csv(t)
    copies = control_table([r for r in rows if r["mixture"] in ("R500_S0", "R1000_S0")])
    assert copies.label("R500_S0") == "R500_S0 copies (not converged)" and copies.label("R1000_S0") == "R1000_S0 copies"


def test_an_image_labelled_set_has_its_image_recall_column_alone():
    from eval.imagelevel import IMAGE_LABELLED, IMAGE_RECALL

    broad = [{**r, "test_set": "broad", "AP": None, "AP50": None, IMAGE_RECALL: 0.4, IMAGE_LABELLED: True}
             for r in results() if r["test_set"] == "common"]  # fmt: skip
    t = table2([*results(), *broad], metrics=("AP", "AP50", IMAGE_RECALL))
    assert [c for c in t.columns if c[0] == "broad"] == [("broad", IMAGE_RECALL)]
    assert ("common", "AP") in t.columns and "broad image recall" in to_markdown(t).splitlines()[2]

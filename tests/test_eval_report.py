"""report.html pieces: marked tables, run list, sample thumbnails with boxes, the page and its notice."""

from __future__ import annotations

import numpy as np
from detector_factories import write_test_set
from PIL import Image

from eval.report import (
    figure_html,
    render_page,
    runs_html,
    samples_html,
    slice_sets_html,
    slices_html,
    table_html,
    write_study_report,
)
from eval.tables import table2
from ground.data.formats.registry import read_dataset


def test_table_html_marks_best_and_second():
    res = [
        {"mixture": m, "seed": s, "test_set": "common", "AP": ap}
        for m, ap in (("R1000_S0", 0.5), ("R500_S500", 0.6), ("R0_S1000", 0.2))
        for s in (0, 1)
    ]
    out = table_html(table2(res, metrics=("AP",)))
    assert "<td>R500_S500</td><td><b>60.0 ± 0.0</b></td>" in out
    assert "<td>R1000_S0</td><td><i>50.0 ± 0.0</i></td>" in out and "<td>20.0 ± 0.0</td>" in out
    assert '<tr class="group"><td colspan="2">Real + synthetic</td></tr>' in out


def test_runs_and_page_escape_text(tmp_path):
    runs = runs_html(
        [{"mixture": "R0_S1000", "seed": 0, "AP": 0.25, "status": "<done>"}], ["mixture", "seed", "AP", "status"]
    )
    assert "<td>25.0</td>" in runs and "&lt;done&gt;" in runs
    page = render_page("Study <1>", [("Runs", runs)], notice="stand-in data, not real fire photos")
    assert page.startswith("<!doctype html>") and "Study &lt;1&gt;" in page
    assert '<div class="notice">stand-in data, not real fire photos</div>' in page
    (tmp_path / "figures").mkdir()
    assert 'src="figures/a.png"' in figure_html(tmp_path / "figures" / "a.png", tmp_path, "AP")


def test_samples_are_thumbnails_with_boxes(tmp_path):
    ds = read_dataset(write_test_set(tmp_path / "test")).dataset
    body = samples_html(ds, tmp_path / "report" / "samples", tmp_path / "report", np.random.default_rng(0), count=3)
    files = sorted((tmp_path / "report" / "samples").glob("*.jpg"))
    assert len(files) == 3 and body.count("<figure>") == 3 and 'src="samples/' in body
    assert all(Image.open(f).size[1] == 160 for f in files)


def test_write_study_report_writes_tables_figures_and_page(tmp_path):
    ds = read_dataset(write_test_set(tmp_path / "test")).dataset
    results = [
        {"mixture": m, "seed": s, "test_set": t, "AP": 0.3 + 0.1 * i + 0.01 * s, "AP50": 0.6 + 0.01 * s}
        for i, m in enumerate(["R1000_S0", "R500_S500", "R0_S1000"])
        for s in (0, 1)
        for t in ("common", "rare")
    ]
    methods = [dict(r, method=m) for r in results if r["mixture"] == "R0_S1000" for m in ("method1", "method2")]
    delta = {"value": 0.05, "low": 0.01, "high": 0.09, "p_value": 0.02, "resampled": "images and seeds"}
    seeds = [{"seed": 0, "delta": 0.038}, {"seed": 1, "delta": 0.051}, {"seed": 2, "delta": -0.027}]
    comparisons = [{"test_set": "rare", "mixture": "R500_S500", "baseline": "R1000_S0", "metric": "AP", "delta": delta,
                    "seeds": seeds}]  # fmt: skip
    out = tmp_path / "study"
    page = write_study_report(
        out,
        results,
        np.random.default_rng(0),
        method_results=methods,
        gaps=[
            {
                "method": "method2",
                "size": 200,
                "frechet": {
                    "synthetic": {"median": 0.853, "low": 0.836, "high": 0.875},
                    "floor": {"median": 0.162, "low": 0.148, "high": 0.178},
                    "ratio": {"median": 5.27, "low": 4.8, "high": 5.79},
                },
            }
        ],
        comparisons=comparisons,
        samples={"common (stand-in)": ds},
        notice="STAND-IN DATA",
    )
    for name in ("table1.md", "table1.csv", "table1.tex", "table2.md", "table2.csv", "table2.tex"):
        assert (out / "tables" / name).stat().st_size > 0
    assert "**50.5 ± 0.7**" in (out / "tables" / "table2.md").read_text()
    csv = (out / "tables" / "comparisons.csv").read_text().splitlines()
    assert csv == [
        "test_set,mixture,baseline,metric,delta,low,high,p_value,resampled,per_seed",
        "rare,R500_S500,R1000_S0,AP,5.00,1.00,9.00,0.0200,images and seeds,0:+3.80 1:+5.10 2:-2.70",
    ]
    assert {p.name for p in (out / "figures").iterdir()} == {"figure5_AP.png", "figure5_AP50.png"}
    text = page.read_text()
    assert "STAND-IN DATA" in text and 'src="figures/figure5_AP.png"' in text and "<td>+5.0</td>" in text
    assert "Realism gap" in text and "<td>0.853 [0.836, 0.875]</td>" in text and "<td>5.27 [4.80, 5.79]</td>" in text
    assert text.count('src="samples/common__stand_in/') == 6 and text.count("<td>R0_S1000</td>") >= 4
    (out / "tables" / "notes.txt").write_text("mine\n")
    again = [r for r in results if r["mixture"] == "R1000_S0"]
    write_study_report(out, again, np.random.default_rng(0), comparisons=[], samples={})
    left = sorted(p.name for p in (out / "tables").iterdir())  # no Table 1 or comparison of the earlier report
    assert left == ["notes.txt", "table2.csv", "table2.md", "table2.tex"]


def test_errors_table_means_over_seeds() -> None:
    from eval.report import errors_html

    def doc(loc: float, alarms: float | None) -> dict:
        delta = dict.fromkeys(("classification", "localisation", "both", "duplicate", "background", "missed"), 0.0)
        return {"AP50": 0.3, "delta_AP50": {**delta, "localisation": loc}, "negatives": 40,
                "false_alarms_per_100_negatives": alarms}  # fmt: skip

    rows = [
        {"test_set": "rare", "label": "R400_S0", "seed": s, "errors": doc(loc, alarm)}
        for s, (loc, alarm) in enumerate([(0.1, 10.0), (0.3, 20.0)])
    ]
    page = errors_html(rows)
    assert "<td>rare</td><td>R400_S0</td><td>30.0</td>" in page
    assert "<td>20.0</td>" in page  # localisation: mean of 10 and 30 points
    assert "<td>15.0 (of 40)</td><td>2</td>" in page


def test_tables_show_ap25_only_when_every_run_has_it() -> None:
    from eval.report import table_metrics

    rows = [{"mixture": "R4_S0", "seed": s, "test_set": "rare", "AP": 0.1, "AP50": 0.2, "AP25": 0.5} for s in (0, 1)]
    assert table_metrics(rows) == ("AP", "AP50", "AP25")
    assert table_metrics([*rows, {**rows[0], "seed": 2, "AP25": None}]) == ("AP", "AP50")  # scored before AP25
    assert table_metrics([]) == ("AP", "AP50")


def test_a_set_without_fire_shows_its_alarm_rate_in_tables_figures_and_runs(tmp_path):
    from eval.errors import ALARMS
    from eval.report import table_metrics

    fire = [
        {"mixture": m, "seed": s, "test_set": "common", "AP": 0.3 + 0.1 * i, "AP50": 0.6, "AP25": 0.7}
        for i, m in enumerate(["R1000_S0", "R0_S1000"])
        for s in (0, 1)
    ]
    free = [
        {"mixture": m, "seed": s, "test_set": "fire-free", "AP": None, "AP50": None, "AP25": None, ALARMS: 12.5 + s}
        for m in ("R1000_S0", "R0_S1000")
        for s in (0, 1)
    ]
    assert table_metrics([*fire, *free]) == ("AP", "AP50", "AP25")  # the set without fire has no AP25 to lack
    out = tmp_path / "study"
    columns = ("mixture", "seed", "test_set", "AP", ALARMS)
    page = write_study_report(out, [*fire, *free], np.random.default_rng(0), run_columns=columns).read_text()
    figures = {p.name for p in (out / "figures").iterdir()}
    assert figures == {"figure5_AP.png", "figure5_AP50.png", "figure5_alarms_per_100.png"}
    assert "<th>fire-free alarms/100</th>" in page and "<td><b>13.0 ± 0.7</b></td>" in page  # as is, not in percent
    assert "<th>alarms/100</th>" in page and "<td>12.5</td>" in page and "<td>30.0</td>" in page  # the run list
    assert "fire-free alarms/100" in (out / "tables" / "table2.md").read_text()


def test_the_recall_at_the_alarm_budget_is_a_column_and_a_figure_when_every_fire_row_has_it(tmp_path):
    from eval.errors import ALARMS
    from eval.operating import RECALL_AT_ALARMS
    from eval.report import table_metrics

    fire = [
        {
            "mixture": m,
            "seed": s,
            "test_set": "common",
            "AP": 0.3,
            "AP50": 0.6,
            "AP25": 0.7,
            RECALL_AT_ALARMS: r + s / 10,
        }
        for m, r in (("R1000_S0", 0.2), ("R500_S500", 0.4))
        for s in (0, 1)
    ]
    free = [{**r, "test_set": "fire-free", "AP": None, "AP50": None, "AP25": None, ALARMS: 9.0} for r in fire]
    for r in free:
        del r[RECALL_AT_ALARMS]
    assert table_metrics([*fire, *free]) == ("AP", "AP50", "AP25", RECALL_AT_ALARMS)
    assert table_metrics([*fire, {**fire[0], "seed": 2, RECALL_AT_ALARMS: None}]) == ("AP", "AP50", "AP25")
    out = tmp_path / "study"
    page = write_study_report(out, [*fire, *free], np.random.default_rng(0)).read_text()
    assert (out / "figures" / f"figure5_{RECALL_AT_ALARMS}.png").is_file()
    assert "<th>common recall@10 alarms/100</th>" in page and "<td><b>45.0 ± 7.1</b></td>" in page  # in percent
    assert "common recall@10 alarms/100" in (out / "tables" / "table2.md").read_text()


def test_rows_with_their_operating_data_draw_the_recall_against_false_alarms(tmp_path):
    from eval.operating import OPERATING, FoundScores, alarms_of

    def row(mixture: str, seed: int, found: list[float]) -> dict:
        scores = np.array(found)
        operating = (FoundScores(scores, np.arange(len(found)), np.ones(10, dtype=np.int64)),
                     alarms_of([{"image_id": 1, "score": 0.5}], [1, 2, 3, 4]))  # fmt: skip
        return {"mixture": mixture, "seed": seed, "test_set": "common", "AP": 0.3, "AP50": 0.6, OPERATING: operating}

    rows = [row("R1000_S0", 0, [0.9, 0.4]), row("R1000_S0", 1, [0.6]), row("R500_S500", 0, [0.9, 0.8, 0.7])]
    out = tmp_path / "study"
    page = write_study_report(out, rows, np.random.default_rng(0)).read_text()
    assert (out / "figures" / "operating_common.png").is_file()
    assert "Fire found against false alarms" in page and "figures/operating_common.png" in page
    assert "fewer than 50 fire images has no AP" in page
    rows_two = [{**r, "classes": ["fire", "smoke"]} for r in rows]
    two = write_study_report(tmp_path / "two", rows_two, np.random.default_rng(0), positives="images with fire or smoke",
                             min_positives=20).read_text()  # fmt: skip
    assert "<h2>Images with fire or smoke found against false alarms</h2>" in two
    assert (tmp_path / "two" / "figures" / "operating_common.png").is_file()
    assert "the share of images with fire or smoke with a detection on a box of the detection" in two
    assert "fewer than 20 images with fire or smoke has no AP" in two and "fire images" not in two
    plain = tmp_path / "plain"
    write_study_report(plain, [{k: v for k, v in r.items() if k != OPERATING} for r in rows], np.random.default_rng(0))
    assert not (plain / "figures" / "operating_common.png").exists()


def test_the_box_level_operating_curves_name_the_classes_their_boxes_pool() -> None:
    from eval.report import found_objects

    assert found_objects([]) == "fire" and found_objects([{"AP50": 0.5}]) == "fire"  # a fire-only study
    two = [{"classes": ["fire", "smoke"]}, {"classes": ["fire", "smoke"]}, {"AP50": 0.1}]
    assert found_objects(two) == "fire or smoke"  # first seen order, each once


def test_a_set_without_fire_shows_no_ap50_in_the_error_breakdown() -> None:
    from eval.report import errors_html

    delta = dict.fromkeys(("classification", "localisation", "both", "duplicate", "background", "missed"), 0.0)
    doc = {"AP50": None, "delta_AP50": delta, "negatives": 68, "false_alarms_per_100_negatives": 9.3, "boxes": 0}
    page = errors_html([{"test_set": "fire-free", "label": "R200_S0", "seed": 0, "errors": doc}])
    assert "<td>fire-free</td><td>R200_S0</td><td>–</td>" in page and "0.0" not in page
    assert "<td>9.3 (of 68)</td>" in page


def test_the_page_lists_every_run_once_explains_its_marks_and_captions_figures_in_words(tmp_path):
    results = [
        {"mixture": m, "method": "method2", "seed": s, "test_set": "common", "AP": 0.3 + 0.1 * i, "AP50": 0.6,
         "run": f"{m}-{s}"}
        for i, m in enumerate(["R100_S0", "R0_S100"]) for s in (0, 1)
    ]  # fmt: skip
    method1 = [dict(r, method="method1", run=f"m1-{r['seed']}") for r in results if r["mixture"] == "R0_S100"]
    method2 = [r for r in results if r["mixture"] == "R0_S100"]  # the same runs as Table 2's
    columns = ("mixture", "method", "seed", "test_set", "AP", "run")
    page = write_study_report(
        tmp_path, results, np.random.default_rng(0), method_results=[*method1, *method2], samples={},
        run_columns=columns,
    ).read_text()  # fmt: skip
    runs = page.split("<h2>Runs</h2>")[1]
    assert runs.count("<tr><td>") == 6  # 4 Table 2 runs + the 2 Method 1 runs; Table 1's Method 2 rows are theirs
    assert runs.count("<td>method1</td>") == 2
    assert "<b>bold</b>: the best mean of its column" in page
    assert (
        "<figcaption>Figure 5 — AP per training mixture" in page and "<figcaption>figure5_AP</figcaption>" not in page
    )


def test_the_slice_tables_name_what_a_slice_counts() -> None:
    delta = {"value": 0.05, "low": -0.01, "high": 0.1}
    rows = [{"test_set": "t", "mixture": "B", "baseline": "A", "slice": "smoke_colour=grey", "fire_images": 31,
             "metric": "AP50", "delta": delta, "verdict": "-"}]  # fmt: skip
    sets = {"t": [{"slice": "smoke_colour=grey", "images": 40, "fire_images": 31, "too_few": False}]}
    two = slices_html(rows, "images with fire or smoke") + slice_sets_html(sets, "images with fire or smoke")
    assert "fire images" not in two and two.count("<th>images with fire or smoke</th>") == 2
    assert "<td>31</td>" in two and "fewer than 20 images with fire or smoke" in two
    one = slices_html(rows) + slice_sets_html(sets)
    assert one.count("<th>fire images</th>") == 2

"""PNG figures are written: valid PNG files of a sensible size."""

from __future__ import annotations

import numpy as np
from PIL import Image

from eval.plots import plot_bars, plot_figure5, plot_pr_curves, pr_curves_from_eval


def _png(path) -> tuple[int, int]:
    with Image.open(path) as im:
        assert im.format == "PNG"
        return im.size


def test_pr_curves_skip_classes_without_ground_truth(tmp_path):
    precision = -np.ones((10, 101, 2, 4, 3))
    precision[0, :, 0, 0, -1] = np.linspace(1, 0, 101)
    curves = pr_curves_from_eval(precision, ["fire", "smoke"])
    assert list(curves) == ["fire (AP50 0.500)"]
    w, h = _png(plot_pr_curves(np.linspace(0, 1, 101), curves, tmp_path / "pr.png", "t"))
    assert w > 300 and h > 300


def test_figure5_and_bars(tmp_path):
    results = [
        {"mixture": m, "seed": s, "test_set": t, "AP": 0.1 * (i + 1) + 0.01 * s}
        for i, m in enumerate(["R1000_S0", "R500_S500", "R0_S1000"])
        for s in (0, 1)
        for t in ("common", "rare")
    ]
    _png(plot_figure5(results, tmp_path / "fig5.png"))
    _png(plot_bars(["a", "b"], {"x": ([1.0, 2.0], [0.1, float("nan")])}, tmp_path / "bars.png"))


def test_figure5_of_a_metric_has_a_bar_per_set_that_has_it(tmp_path, monkeypatch):
    import eval.plots as plots
    from eval.errors import ALARMS

    drawn = {}

    def record(groups, series, path, ylabel="AP", title=""):
        drawn[ylabel] = {name: means for name, (means, _) in series.items()}
        return plot_bars(groups, series, path, ylabel, title)

    monkeypatch.setattr(plots, "plot_bars", record)
    rows = [{"mixture": m, "seed": 0, "test_set": "common", "AP": 0.25} for m in ("R1000_S0", "R0_S1000")]
    rows += [{"mixture": m, "seed": 0, "test_set": "free", "AP": None, ALARMS: 40.0} for m in ("R1000_S0", "R0_S1000")]
    _png(plot_figure5(rows, tmp_path / "ap.png", "AP"))
    _png(plot_figure5(rows, tmp_path / "alarms.png", ALARMS))
    assert drawn == {"AP (%)": {"common": [25.0, 25.0]}, "false alarms per 100 images": {"free": [40.0, 40.0]}}


def test_operating_curves_draw_a_line_per_label_and_a_band_over_several_runs(tmp_path, monkeypatch):
    from matplotlib.axes import Axes

    from eval.plots import plot_operating_curves

    rates = np.linspace(0, 100, 11)
    bands: list[int] = []
    original = Axes.fill_between
    monkeypatch.setattr(
        Axes, "fill_between", lambda self, x, lo, hi, **k: bands.append(len(x)) or original(self, x, lo, hi, **k)
    )
    curves = {"two runs": np.stack([rates / 200, rates / 100]), "one run": rates[None] / 150}
    w, h = _png(plot_operating_curves(curves, rates, tmp_path / "op.png", 10.0))
    assert w > 300 and h > 300 and bands == [11]  # the range of the two runs; one run has none


def test_a_long_title_is_wrapped_within_the_figure_and_keeps_its_words(tmp_path, monkeypatch):
    from matplotlib.axes import Axes

    from eval.plots import TITLE_CHARS, plot_operating_curves

    titles: list[str] = []
    original = Axes.set_title
    monkeypatch.setattr(Axes, "set_title", lambda self, text, **k: titles.append(text) or original(self, text, **k))
    title = "fire-smoke: images with fire or smoke detected against false-alarm images"
    rates = np.linspace(0, 100, 11)
    plot_operating_curves({"a": rates[None] / 100}, rates, tmp_path / "op.png", 10.0, title)
    assert len(titles) == 1 and "\n" in titles[0] and titles[0].split() == title.split()
    assert max(len(line) for line in titles[0].splitlines()) <= TITLE_CHARS
    plot_operating_curves({"a": rates[None] / 100}, rates, tmp_path / "short.png", 10.0, "common: fire found")
    assert titles[1] == "common: fire found"

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

"""The curves PNG is written from metrics rows."""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from train.plots import plot_curves


def test_plot_curves_writes_a_png(tmp_path: Path) -> None:
    rows = [
        {
            "epoch": e,
            "loss_box": 0.1 / (e + 1),
            "loss_obj": 0.01,
            "loss_cls": 0.0,
            "AP50": 0.1 * e,
            "AP": 0.05 * e,
            "fitness": 0.06 * e,
        }
        for e in range(4)
    ]
    path = plot_curves(rows, tmp_path / "curves.png", title="run")
    with Image.open(path) as im:
        assert im.format == "PNG" and im.size[0] > 500

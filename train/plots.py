"""``RUN/curves.png``: losses and validation AP / AP50 per epoch (matplotlib Figure, no pyplot state)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def read_metrics(path: Path) -> list[dict[str, Any]]:
    """The rows of a ``metrics.jsonl`` file."""
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


def plot_curves(rows: list[dict[str, Any]], path: Path, title: str = "") -> Path:
    """Two panels: training losses (box, obj, cls) and validation AP50 / AP, with the best epoch marked."""
    fig = Figure(figsize=(9, 3.5), dpi=110)
    FigureCanvasAgg(fig)
    epochs = [r["epoch"] for r in rows]  # counted from 1
    losses, scores = fig.subplots(1, 2)
    for key in ("loss_box", "loss_obj", "loss_cls"):
        losses.plot(epochs, [r[key] for r in rows], label=key.removeprefix("loss_"))
    losses.set_xlabel("epoch")
    losses.set_title("training loss (gain-weighted)")
    losses.legend()
    for key in ("AP50", "AP"):
        scores.plot(epochs, [r[key] for r in rows], marker="o", markersize=3, label=key)
    if rows:
        best = max(rows, key=lambda r: r["fitness"])
        scores.axvline(best["epoch"], color="grey", linestyle="--", label=f"best (epoch {best['epoch']})")
    scores.set_xlabel("epoch")
    scores.set_ylim(0, 1)
    scores.set_title("validation (EMA model)")
    scores.legend()
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path)
    return path

"""PNG figures: precision-recall curves of one evaluation, Figure-5-style bars with error bars, and recall against
false alarms (:mod:`eval.operating`).

matplotlib's object API only (``Figure``), so plotting touches no global state.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

TITLE_CHARS = 56  # a line plot's title wraps past this many characters (wider is cut off at the figure's edges)


def wrapped(title: str) -> str:
    """``title`` broken into lines of at most :data:`TITLE_CHARS` characters at spaces."""
    return textwrap.fill(title, TITLE_CHARS)


def plot_pr_curves(
    recall: NDArray[np.float64], precision: Mapping[str, NDArray[np.float64]], path: Path, title: str = ""
) -> Path:
    """Write a PNG of precision (R,) against ``recall`` thresholds (R,), one line per label."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5.5, 4.5), dpi=110)
    ax = fig.add_subplot()
    for label, prec in precision.items():
        ax.plot(recall, prec, label=label)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    return _save_lines(fig, ax, path, ("recall", "precision"), title, "lower left" if precision else None)


def _save_lines(fig, ax, path: Path, labels: tuple[str, str], title: str, legend: str | None) -> Path:
    """Finish a line plot: axis ``labels`` (x, y), a light grid, ``title`` (:func:`wrapped`), the legend at
    ``legend`` (None: no legend); write ``fig`` to ``path`` (its folder made)."""
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.grid(alpha=0.3)
    ax.set_title(wrapped(title))
    if legend is not None:
        ax.legend(loc=legend, fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path


def pr_curves_from_eval(precision: NDArray[np.float64], class_names: Sequence[str]) -> dict[str, NDArray]:
    """COCOeval ``precision`` (T, R, K, A, M) -> ``{"<class> AP50 …": (R,)}`` at IoU 0.5, area all, 100 dets.

    Classes without ground truth (precision -1) are left out."""
    curves = {}
    for k, name in enumerate(class_names):
        prec = precision[0, :, k, 0, -1]
        if np.all(prec > -1):
            area = float(prec.mean())
            curves[f"{name} (AP50 {area:.3f})"] = prec
    return curves


def plot_bars(
    groups: Sequence[str],
    series: Mapping[str, tuple[Sequence[float], Sequence[float]]],
    path: Path,
    ylabel: str = "AP",
    title: str = "",
) -> Path:
    """Grouped bars with error bars (Figure 5 of the paper): one group per x label (e.g. a mixture),
    one bar per series (e.g. a test set). ``series[name] = (means, stds)`` aligned with ``groups``;
    NaN std draws no error bar; a NaN mean draws no bar and says "not measured" where it would stand (an empty
    place must not read as 0)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(max(6.0, 0.6 * len(groups) * max(1, len(series))), 4.2), dpi=110)
    ax = fig.add_subplot()
    x = np.arange(len(groups), dtype=float)
    width = 0.8 / max(1, len(series))
    for i, (name, (means, stds)) in enumerate(series.items()):
        offset = (i - (len(series) - 1) / 2) * width
        err = np.nan_to_num(np.asarray(stds, dtype=float), nan=0.0)
        ax.bar(x + offset, means, width, yerr=err, capsize=3, label=name)
        for at in x[np.isnan(np.asarray(means, dtype=float))] + offset:
            ax.text(at, 0, "not\nmeasured", ha="center", va="bottom", fontsize=7, color="0.4")
    ax.set_xlim(-0.5, len(groups) - 0.5)  # every group keeps its place, a bar missing or not
    ax.set_xticks(x, list(groups), rotation=30, ha="right")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(axis="y", alpha=0.3)
    if series:
        ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path


def plot_figure5(results: Sequence[Mapping[str, object]], path: Path, metric: str = "AP", title: str = "") -> Path:
    """Figure 5 of the paper: ``metric`` (mean ± std over seeds) per training mixture, one bar per test set that
    has it, mixtures in Table 2 order. ``results`` as for :func:`eval.tables.table2`; AP metrics in percent,
    :data:`eval.errors.ALARMS` (the sets without fire) as false alarms per 100 images."""
    from eval.errors import ALARMS
    from eval.tables import METRIC_LABELS, shown_scale, table2

    table = table2(results, metrics=(metric,))  # type: ignore[arg-type]
    groups = table.rows
    f = shown_scale(metric, 100.0)
    series = {}
    for test_set, _ in (c for c in table.columns if c[1] == metric):
        cells = [table.cell(row, (test_set, metric)) for row in groups]
        means = [c.mean * f if c else np.nan for c in cells]
        stds = [c.std * f if c and c.std is not None else np.nan for c in cells]
        series[test_set] = (means, stds)
    ylabel = "false alarms per 100 images" if metric == ALARMS else f"{METRIC_LABELS.get(metric, metric)} (%)"
    name = "false alarms" if metric == ALARMS else METRIC_LABELS.get(metric, metric)
    labels = [table.label(row) for row in groups]  # a mixture with a run that did not converge says so
    return plot_bars(labels, series, path, ylabel=ylabel, title=title or f"{name} by training mixture")


def plot_operating_curves(
    curves: Mapping[str, NDArray[np.float64]],
    rates: NDArray[np.float64],
    path: Path,
    budget: float | None = None,
    title: str = "",
    labels: tuple[str, str] = ("false alarms per 100 images without fire", "fire boxes found at IoU 0.5 (%)"),
) -> Path:
    """Recall (in percent) against false alarms per 100 images without fire: per label (e.g. a mixture) its runs'
    recall (N, R) at the alarm rates ``rates`` (R,), the mean as a line and the runs' range as a band; a dotted
    line at ``budget``; ``labels``: the x and y axes' titles."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5.8, 4.4), dpi=110)
    ax = fig.add_subplot()
    for label, recall in curves.items():
        runs = 100.0 * np.atleast_2d(recall)
        (line,) = ax.plot(rates, runs.mean(axis=0), label=f"{label} ({len(runs)} run{'s' * (len(runs) > 1)})")
        if len(runs) > 1:
            ax.fill_between(rates, runs.min(axis=0), runs.max(axis=0), color=line.get_color(), alpha=0.15)
    if budget is not None:
        ax.axvline(budget, color="0.4", linestyle=":", linewidth=1)
    ax.set_xlim(float(rates[0]), float(rates[-1]))
    ax.set_ylim(bottom=0)
    return _save_lines(fig, ax, path, labels, title, "lower right" if curves else None)


def plot_forest(panels: Mapping[str, Sequence[Mapping[str, object]]], path: Path, title: str = "") -> Path:
    """A forest plot: per panel (a metric, e.g. ``"AP50"``) its rows (:func:`eval.slices.compare_slices`: ``slice``,
    ``fire_images``, ``delta`` {value, low, high} in 0..1, ``verdict``) as points with their 95 % intervals, in
    points (x 100), one line per slice (the same slices in every panel, top to bottom in the first panel's
    order); a filled point is a slice the pool helps or hurts after Holm's correction, an open one is not; the
    dotted line is no difference."""
    from matplotlib.figure import Figure

    from eval.tables import METRIC_LABELS

    names = list(dict.fromkeys(str(r["slice"]) for rows in panels.values() for r in rows))
    fire = {str(r["slice"]): r["fire_images"] for rows in panels.values() for r in rows}
    fig = Figure(figsize=(3.2 * max(len(panels), 1) + 2.2, 0.28 * len(names) + 1.4), dpi=110)
    axes = fig.subplots(1, max(len(panels), 1), sharey=True, squeeze=False)[0]
    y = {name: len(names) - 1 - k for k, name in enumerate(names)}
    for ax, (metric, rows) in zip(axes, panels.items()):
        for r in rows:
            d = r["delta"]
            value, low, high = (100.0 * float(d[k]) for k in ("value", "low", "high"))  # type: ignore[index]
            colour = {"helps": "tab:green", "hurts": "tab:red"}.get(str(r.get("verdict")), "0.35")
            yy = y[str(r["slice"])]
            ax.plot([low, high], [yy, yy], color=colour, linewidth=1.4)
            filled = r.get("verdict") in ("helps", "hurts")
            ax.plot([value], [yy], "o", color=colour, markerfacecolor=colour if filled else "white", markersize=5)
        ax.axvline(0.0, color="0.4", linestyle=":", linewidth=1)
        ax.set_xlabel(f"Δ {METRIC_LABELS.get(metric, metric)} (points)")
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks([y[n] for n in names], [f"{n} ({fire[n]})" for n in names], fontsize=8)
    axes[0].set_ylim(-0.7, len(names) - 0.3)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path

"""The paper's tables from per-run results: Table 1 (Method 1 vs Method 2, synthetic only) and Table 2
(three strategies x mixtures), each cell mean ± sample std over seeds, best per column in bold, second in
italic; rendered as Markdown, CSV and LaTeX.

A run result is a mapping with ``mixture`` (``R750_S250``), ``seed``, ``test_set`` and metric values
(``AP``, ``AP50`` in [0, 1]); Table 1 results also carry ``method`` (``method1`` / ``method2``). A result of a
test set without fire carries :data:`eval.errors.ALARMS` (false alarms per 100 images) instead of AP: that set's
one column is its alarm rate, shown as is (not in percent), lower being better. A test set with fire may also
carry :data:`eval.operating.RECALL_AT_ALARMS`, the share of its boxes found at the run's threshold for 10 alarms per
100 images without fire (in percent, like AP).
"""

from __future__ import annotations

import csv
import io
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from curate.mix import Mixture, parse_mixture
from eval.errors import ALARMS
from eval.imagelevel import IMAGE_LABELLED, IMAGE_RECALL
from eval.operating import ALARM_BUDGET, RECALL_AT_ALARMS
from eval.stats import MeanStd, mean_std

Key = tuple[str, str]  # (row label, column label)
MIN_AP_IMAGES = 50  # a test set with fewer images holding a studied class has no AP or AP50 (–): too few for an
# interval that tells mixtures apart (the default of ``report.min_fire_images``)
STRATEGIES: tuple[str, ...] = ("Real only", "Real + synthetic", "Synthetic only")
METHOD_LABELS: Mapping[str, str] = {"method1": "Method 1 (3D)", "method2": "Method 2 (2D)"}
METRIC_LABELS: Mapping[str, str] = {
    ALARMS: "alarms/100",
    RECALL_AT_ALARMS: f"recall@{ALARM_BUDGET:g} alarms/100",
    IMAGE_RECALL: "image recall",
}  # column headings of metrics not named as they are keyed


@dataclass(frozen=True)
class Table:
    """Rows in labelled groups; columns ``(group, metric)`` such as ``("common", "AP")``; cells by
    ``(row, "group/metric")``. Higher values are better, but for :data:`eval.errors.ALARMS`."""

    title: str
    row_groups: tuple[tuple[str, tuple[str, ...]], ...]
    columns: tuple[tuple[str, str], ...]
    cells: Mapping[Key, MeanStd]
    row_labels: Mapping[str, str] = field(default_factory=dict)

    def label(self, row: str) -> str:
        return self.row_labels.get(row, row)

    @property
    def rows(self) -> list[str]:
        return [row for _, rows in self.row_groups for row in rows]

    def cell(self, row: str, column: tuple[str, str]) -> MeanStd | None:
        return self.cells.get((row, "/".join(column)))


def is_alarms(metric: str) -> bool:
    """Whether ``metric`` is a false-alarm rate (:data:`eval.errors.ALARMS`, or a class's): per 100 images, lower is
    better."""
    return metric == ALARMS or metric.startswith(f"{ALARMS} ")


def shown_scale(metric: str, scale: float) -> float:
    """The factor a metric is shown with: ``scale`` for a fraction (AP), 1 for a rate already per 100 images."""
    return 1.0 if is_alarms(metric) else scale


#: The metrics a result row carries per class when its test set boxes more than one class.
CLASS_METRICS: tuple[str, ...] = ("AP50",)


def class_metric(metric: str, name: str) -> str:
    """The key of ``metric`` for the class ``name`` alone in a result row, and its column's title: ``AP50 smoke``."""
    return f"{metric} {name}"


def heading(column: tuple[str, str]) -> str:
    """``"<test set> <metric>"`` as a column is titled (a class's metric: ``"<test set> <metric> <class>"``)."""
    metric, _, name = column[1].partition(" ")
    return f"{column[0]} {METRIC_LABELS.get(metric, metric)}{f' {name}' if name else ''}"


def marks(table: Table, scale: float = 100.0, digits: int = 1) -> dict[Key, str]:
    """``"best"`` / ``"second"`` per column by mean as displayed (``mean * scale`` rounded to ``digits``, so
    cells that read the same share a mark; the lowest alarm rates are best); unmarked cells are not listed. A
    column with fewer than two rows has no mark (nothing to compare)."""
    out: dict[Key, str] = {}
    for col in table.columns:
        f = shown_scale(col[1], scale)
        values = {row: round(c.mean * f, digits) for row in table.rows if (c := table.cell(row, col)) is not None}
        if len(values) < 2:
            continue
        ranked = sorted(set(values.values()), reverse=not is_alarms(col[1]))
        for row, v in values.items():
            if v == ranked[0]:
                out[(row, "/".join(col))] = "best"
            elif len(ranked) > 1 and v == ranked[1]:
                out[(row, "/".join(col))] = "second"
    return out


def _collect(results: Sequence[Mapping[str, Any]], row_of, metrics: Sequence[str]) -> dict[Key, MeanStd]:
    values: dict[Key, list[float]] = defaultdict(list)
    for r in results:
        for metric in metrics:
            if r.get(metric) is not None:
                values[(row_of(r), f"{r['test_set']}/{metric}")].append(float(r[metric]))
    return {key: mean_std(v) for key, v in values.items()}


def _with_alarms(results: Sequence[Mapping[str, Any]], metrics: Sequence[str]) -> tuple[str, ...]:
    """``metrics``, the false alarms of the sets without fire and, in a study of several classes, each class's."""
    per_class = (k for r in results for k in r if is_alarms(k))
    return tuple(dict.fromkeys((*metrics, ALARMS, *per_class)))


def strategy(mix: Mixture) -> str:
    """The paper's strategy of a mixture: real only, real + synthetic, or synthetic only."""
    return STRATEGIES[0] if mix.synth == 0 else STRATEGIES[2] if mix.real == 0 else STRATEGIES[1]


def _columns(results: Sequence[Mapping[str, Any]], test_sets, metrics) -> tuple[tuple[str, str], ...]:
    """Test set x ``metrics``; a set without fire (its results carry :data:`eval.errors.ALARMS`) has the alarm
    columns alone (all classes', then each class's), an image-labelled set (:data:`eval.imagelevel.IMAGE_LABELLED`: no boxes) its image recall."""
    sets = list(test_sets) if test_sets else list(dict.fromkeys(r["test_set"] for r in results))
    negatives = {r["test_set"] for r in results if ALARMS in r}
    labelled = {r["test_set"] for r in results if r.get(IMAGE_LABELLED)}

    def shown(s: str) -> Sequence[str]:
        if s in negatives:  # its false alarms, and each class's in a study of several (class_metric)
            return tuple(dict.fromkeys(k for r in results if r["test_set"] == s for k in (ALARMS, *r) if is_alarms(k)))
        return [m for m in metrics if m != ALARMS and (s not in labelled or m == IMAGE_RECALL)]

    return tuple((s, m) for s in sets for m in shown(s))


def table2(
    results: Sequence[Mapping[str, Any]], test_sets: Sequence[str] = (), metrics: Sequence[str] = ("AP", "AP50")
) -> Table:
    """Table 2: one row per mixture, grouped by strategy (real only by size, mixtures by synthetic share,
    synthetic only by size); columns test set x metric."""
    mixtures = sorted(
        {parse_mixture(r["mixture"]) for r in results}, key=lambda m: (STRATEGIES.index(strategy(m)), m.synth, m.real)
    )
    groups = tuple(
        (s, tuple(m.name for m in mixtures if strategy(m) == s))
        for s in STRATEGIES
        if any(strategy(m) == s for m in mixtures)
    )
    cells = _collect(results, lambda r: r["mixture"], _with_alarms(results, metrics))
    return Table(
        "Table 2: AP by training mixture (mean ± std over seeds)",
        groups,
        _columns(results, test_sets, metrics),
        cells,
        unlearned_labels(results),
    )


UNLEARNED = "learning"  # a result's key: what is wrong with its run's training (None: it learned)
UNLEARNED_MARK = " (not converged)"  # after the label of a row with such a run: its figures are not results


def unlearned_labels(results: Sequence[Mapping[str, Any]]) -> dict[str, str]:
    """Row labels of the mixtures with a run that did not learn (:data:`UNLEARNED`): ``R200_S0 (not converged)``."""
    return {r["mixture"]: r["mixture"] + UNLEARNED_MARK for r in results if r.get(UNLEARNED)}


def control_table(
    results: Sequence[Mapping[str, Any]], test_sets: Sequence[str] = (), metrics: Sequence[str] = ("AP", "AP50")
) -> Table:
    """The control runs: one row per mixture (labelled ``<mixture> copies``) whose synthetic images were replaced
    by flame-free copies of its own real images, by synthetic share; columns as :func:`table2`."""
    mixtures = sorted({parse_mixture(r["mixture"]) for r in results}, key=lambda m: (m.synth, m.real))
    names = tuple(m.name for m in mixtures)
    cells = _collect(results, lambda r: r["mixture"], _with_alarms(results, metrics))
    return Table(
        "Controls: AP by training mixture, its synthetic images replaced by flame-free copies of its real images",
        (("real + copies of the real", names),),
        _columns(results, test_sets, metrics),
        cells,
        {n: f"{n} copies" + (UNLEARNED_MARK if n in unlearned_labels(results) else "") for n in names},
    )


def table1(
    results: Sequence[Mapping[str, Any]], test_sets: Sequence[str] = (), metrics: Sequence[str] = ("AP", "AP50")
) -> Table:
    """Table 1: synthetic-only training with Method 1 vs Method 2; one row per (method, mixture)."""

    def row(r: Mapping[str, Any]) -> str:
        return f"{METHOD_LABELS.get(r['method'], r['method'])} {r['mixture']}"

    methods = list(dict.fromkeys(r["method"] for r in results))
    groups = []
    for method in sorted(methods):
        mixes = sorted({parse_mixture(r["mixture"]) for r in results if r["method"] == method}, key=lambda m: m.synth)
        label = METHOD_LABELS.get(method, method)
        groups.append((label, tuple(f"{label} {m.name}" for m in mixes)))
    cells = _collect(results, row, _with_alarms(results, metrics))
    labels = {key: key.split(" ")[-1] for _, rows in groups for key in rows}
    title = "Table 1: synthetic-only training, Method 1 vs Method 2 (mean ± std over seeds)"
    return Table(title, tuple(groups), _columns(results, test_sets, metrics), cells, labels)


def _text(cell: MeanStd | None, mark: str | None, scale: float, digits: int, style: Mapping[str, str]) -> str:
    if cell is None:
        return "–"
    text = cell.format(scale, digits)
    return style[mark].format(text) if mark else text


def _cell_text(
    table: Table, row: str, col: tuple[str, str], mk: Mapping[Key, str], scale: float, digits: int, style
) -> str:
    """The text of one cell as :func:`_text` gives it, at the column's own scale (:func:`shown_scale`)."""
    return _text(table.cell(row, col), mk.get((row, "/".join(col))), shown_scale(col[1], scale), digits, style)


def to_markdown(table: Table, scale: float = 100.0, digits: int = 1) -> str:
    """A GitHub Markdown table: a bold group row before each group, values in percent by default."""
    mk = marks(table, scale, digits)
    style = {"best": "**{}**", "second": "*{}*"}
    head = ["", *[heading(c) for c in table.columns]]
    lines = [f"**{table.title}**", "", "| " + " | ".join(head) + " |", "|" + "---|" + "---:|" * len(table.columns)]
    for group, rows in table.row_groups:
        lines.append(f"| *{group}* |" + " |" * len(table.columns))
        for row in rows:
            cells = [_cell_text(table, row, c, mk, scale, digits, style) for c in table.columns]
            lines.append("| " + " | ".join([table.label(row), *cells]) + " |")
    return "\n".join(lines) + "\n"


def to_csv(table: Table) -> str:
    """One line per row: group, row, then ``<set> <metric> mean``, ``std``, ``n``, ``rank`` per column
    (raw values: AP in [0, 1], alarm rates per 100 images; rank is best/second/empty)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    header = ["group", "row"]
    for col in table.columns:
        header += [f"{heading(col)} {part}" for part in ("mean", "std", "n", "rank")]
    writer.writerow(header)
    mk = marks(table, 1.0, 6)
    for group, rows in table.row_groups:
        for row in rows:
            line: list[Any] = [group, table.label(row)]
            for col in table.columns:
                c = table.cell(row, col)
                std = "" if c is None or c.std is None else f"{c.std:.6f}"
                line += [
                    "" if c is None else f"{c.mean:.6f}",
                    std,
                    0 if c is None else c.n,
                    mk.get((row, "/".join(col)), ""),
                ]
            writer.writerow(line)
    return buf.getvalue()


def _tex(text: str) -> str:
    for a, b in (("\\", r"\textbackslash{}"), ("_", r"\_"), ("%", r"\%"), ("&", r"\&"), ("#", r"\#")):
        text = text.replace(a, b)
    return text


def to_latex(table: Table, scale: float = 100.0, digits: int = 1) -> str:
    """A booktabs ``tabular``: test sets as multicolumn headers, ``\\pm`` cells, groups between rules."""
    mk = marks(table, scale, digits)
    style = {"best": r"\textbf{{{}}}", "second": r"\textit{{{}}}"}
    sets = list(dict.fromkeys(g for g, _ in table.columns))
    per_set = [sum(1 for g, _ in table.columns if g == s) for s in sets]
    lines = [r"\begin{tabular}{l" + "c" * len(table.columns) + "}", r"\toprule"]
    lines.append(" & " + " & ".join(rf"\multicolumn{{{n}}}{{c}}{{{_tex(s)}}}" for s, n in zip(sets, per_set)) + r" \\")
    lines.append(" & " + " & ".join(_tex(METRIC_LABELS.get(m, m)) for _, m in table.columns) + r" \\")
    for group, rows in table.row_groups:
        lines += [r"\midrule", rf"\multicolumn{{{len(table.columns) + 1}}}{{l}}{{\emph{{{_tex(group)}}}}} \\"]
        for row in rows:
            cells = []
            for col in table.columns:
                text = _cell_text(table, row, col, {}, scale, digits, style).replace("±", r"$\pm$")
                mark = mk.get((row, "/".join(col)))
                cells.append(style[mark].format(text) if mark else text)
            lines.append(" & ".join([_tex(table.label(row)), *cells]) + r" \\")
    lines += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(lines) + "\n"

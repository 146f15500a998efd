"""Pieces of ``report.html``: tables with best/second marked, figures, sample images with their boxes,
the run list, and the page that ties them together (one self-contained folder; images by relative link).
"""

from __future__ import annotations

import html
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from eval.draw import draw_boxes
from eval.errors import ALARMS
from eval.imagelevel import IMAGE_LABELLED, IMAGE_RECALL, IMAGELEVEL, image_operating_curve
from eval.operating import ALARM_BUDGET, OPERATING, RECALL_AT_ALARMS, Alarms, curve_at_rates, recall_at_rates
from eval.slices import FIRE_IMAGES, MIN_FIRE_IMAGES, objects_name
from eval.tables import (
    CLASS_METRICS,
    METRIC_LABELS,
    MIN_AP_IMAGES,
    Table,
    class_metric,
    heading,
    marks,
    shown_scale,
    to_csv,
    to_latex,
    to_markdown,
)
from ground.data.dataset import Dataset
from ground.image.imageio import ImageError, read_image

_CSS = """body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1100px;color:#222}
table{border-collapse:collapse;margin:1em 0}td,th{padding:.3em .7em;border-bottom:1px solid #ddd;text-align:right}
td:first-child,th:first-child{text-align:left}tr.group td{font-style:italic;background:#f4f4f4;text-align:left}
.notice{background:#fff4d6;border:1px solid #e0b040;padding:.8em 1em;margin:1em 0}
figure{display:inline-block;margin:.5em}figcaption{font-size:.85em;color:#555}img{max-width:100%}"""


#: What a table's marked cells mean (:func:`eval.tables.marks`), printed under every table that marks any.
MARKS_LEGEND = "<b>bold</b>: the best mean of its column; <i>italic</i>: the second (alarm columns: the fewest)."


def table_html(table: Table, scale: float = 100.0, digits: int = 1) -> str:
    """An HTML table of ``table``: best cells bold, second italic, a shaded row per group."""
    mk = marks(table, scale, digits)
    head = "".join(f"<th>{html.escape(heading(c))}</th>" for c in table.columns)
    rows = [f"<caption>{html.escape(table.title)}</caption>", f"<tr><th></th>{head}</tr>"]
    for group, members in table.row_groups:
        rows.append(f'<tr class="group"><td colspan="{len(table.columns) + 1}">{html.escape(group)}</td></tr>')
        for row in members:
            cells = []
            for col in table.columns:
                cell = table.cell(row, col)
                text = html.escape(cell.format(shown_scale(col[1], scale), digits)) if cell else "–"
                tag = {"best": "b", "second": "i"}.get(mk.get((row, "/".join(col)), ""))
                cells.append(f"<td><{tag}>{text}</{tag}></td>" if tag else f"<td>{text}</td>")
            rows.append(f"<tr><td>{html.escape(table.label(row))}</td>{''.join(cells)}</tr>")
    legend = f'<p class="legend">{MARKS_LEGEND}</p>' if mk else ""
    return "<table>" + "".join(rows) + "</table>" + legend


def figure_html(path: Path, base: Path, caption: str = "") -> str:
    """An ``<img>`` linking ``path`` relative to the report folder ``base``."""
    rel = Path(path).resolve().relative_to(base.resolve()).as_posix()
    cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
    return f'<figure><img src="{html.escape(rel)}" alt="{html.escape(caption or rel)}">{cap}</figure>'


def runs_html(runs: Sequence[Mapping[str, Any]], columns: Sequence[str]) -> str:
    """The run list: one row per run, the given ``columns`` (floats in [0, 1] shown as percent, alarm rates as
    they are: per 100 images)."""

    def show(v: Any, column: str) -> str:
        if v is None:
            return "–"
        return f"{shown_scale(column, 100.0) * v:.1f}" if isinstance(v, float) else html.escape(str(v))

    head = "".join(f"<th>{html.escape(METRIC_LABELS.get(c, c))}</th>" for c in columns)
    body = "".join("<tr>" + "".join(f"<td>{show(r.get(c), c)}</td>" for c in columns) + "</tr>" for r in runs)
    return f"<table><tr>{head}</tr>{body}</table>"


def samples_html(
    dataset: Dataset, out_dir: Path, base: Path, rng: np.random.Generator, count: int = 8, height: int = 160
) -> str:
    """Write ``count`` randomly chosen images of ``dataset`` with their boxes as JPEG thumbnails into
    ``out_dir`` and return their figures (unreadable images are skipped)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    by_image = dataset.annotations_by_image()
    names = {c.id: c.name for c in dataset.categories}
    pick = rng.choice(len(dataset.images), size=min(count, len(dataset.images)), replace=False)
    figures = []
    for i in sorted(int(j) for j in pick):
        img = dataset.images[i]
        try:
            pixels = read_image(dataset.image_path(img), min_side=height)  # a big JPEG decodes at 1/2..1/8
        except ImageError:
            continue
        anns = by_image[img.id]
        f = pixels.shape[0] / img.height  # decoded pixels per image pixel
        drawn = draw_boxes(pixels, [[v * f for v in a.bbox] for a in anns])
        scale = height / drawn.shape[0]
        thumb = cv2.resize(drawn, (max(1, round(drawn.shape[1] * scale)), height), interpolation=cv2.INTER_AREA)
        path = out_dir / f"sample_{img.id}.jpg"
        cv2.imwrite(str(path), thumb[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, 85])
        label = ", ".join(sorted({names[a.category_id] for a in anns})) or "negative"
        figures.append(figure_html(path, base, f"{Path(img.file_name).name} ({img.source or 'unknown'}): {label}"))
    return "".join(figures)


def render_page(title: str, sections: Sequence[tuple[str, str]], notice: str = "") -> str:
    """A complete HTML page: ``sections`` are ``(heading, html body)``; ``notice`` is shown at the top
    (e.g. that the demo's "real" data is a generated stand-in)."""
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"]
    parts.append(f"<style>{_CSS}</style></head><body><h1>{html.escape(title)}</h1>")
    if notice:
        parts.append(f'<div class="notice">{html.escape(notice)}</div>')
    parts += [f"<h2>{html.escape(heading)}</h2>{body}" for heading, body in sections]
    parts.append("</body></html>\n")
    return "".join(parts)


def write_table_files(table: Table, out_dir: Path, stem: str) -> dict[str, Path]:
    """``<stem>.md``, ``<stem>.csv`` and ``<stem>.tex`` of ``table`` in ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    files = {"md": out_dir / f"{stem}.md", "csv": out_dir / f"{stem}.csv", "tex": out_dir / f"{stem}.tex"}
    files["md"].write_text(to_markdown(table), encoding="utf-8")
    files["csv"].write_text(to_csv(table), encoding="utf-8")
    files["tex"].write_text(to_latex(table), encoding="utf-8")
    return files


def gaps_html(rows: Sequence[Mapping[str, Any]]) -> str:
    """The realism gap of each synthetic pool: rows as :meth:`synth.gap.GapReport.to_json` gives them (plus
    ``method``); Fréchet distances with their 2.5–97.5 % range, and the ratio to the real-vs-real floor."""
    head = (
        "<tr><th>pool</th><th>images per side</th><th>synthetic vs real</th><th>real vs real (floor)</th>"
        "<th>ratio</th></tr>"
    )
    body = []
    for r in rows:
        f = r["frechet"]
        cells = [f"{f[k]['median']:.3f} [{f[k]['low']:.3f}, {f[k]['high']:.3f}]" for k in ("synthetic", "floor")]
        ratio = f"{f['ratio']['median']:.2f} [{f['ratio']['low']:.2f}, {f['ratio']['high']:.2f}]"
        body.append(
            f"<tr><td>{html.escape(str(r['method']))}</td><td>{r['size']}</td><td>{cells[0]}</td>"
            f"<td>{cells[1]}</td><td>{ratio}</td></tr>"
        )
    caption = (
        "<caption>Fréchet distance between CNN embeddings (ImageNet EfficientNet-Lite0) of each synthetic pool and "
        "half of the real training split, next to the other half's (the floor a perfect generator reaches); "
        "median and 2.5–97.5 % range over random equal-size draws. Lower is closer to real.</caption>"
    )
    return f"<table>{caption}{head}{''.join(body)}</table>"


def errors_html(rows: Sequence[Mapping[str, Any]]) -> str:
    """Where AP50 goes, per test set and mixture: rows with ``test_set``, ``label`` (mixture and pool), ``seed``
    and an :meth:`eval.errors.ErrorBreakdown.to_dict`; means over seeds, in AP50 points (false alarms per 100
    images without fire at the breakdown's alarm confidence)."""
    from eval.errors import ERROR_TYPES

    groups: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["test_set"], r["label"]), []).append(r["errors"])
    head = "<tr><th>test set</th><th>mixture</th><th>AP50</th>" + "".join(f"<th>{k}</th>" for k in ERROR_TYPES)
    head += "<th>false alarms / 100 negatives (of N)</th><th>seeds</th></tr>"
    body = []
    for (test, name), docs in groups.items():
        alarms = [d["false_alarms_per_100_negatives"] for d in docs if d["false_alarms_per_100_negatives"] is not None]
        alarm = f"{np.mean(alarms):.1f} (of {docs[0]['negatives']})" if alarms else "–"
        if any(d["AP50"] is None for d in docs):  # no box to find (a fire-free set): AP50 is undefined
            ap50, cells = "–", "<td>–</td>" * len(ERROR_TYPES)
        else:
            mean = {k: 100 * float(np.mean([d["delta_AP50"][k] for d in docs])) for k in ERROR_TYPES}
            cells = "".join(f"<td>{mean[k]:.1f}</td>" for k in ERROR_TYPES)
            ap50 = f"{100 * float(np.mean([d['AP50'] for d in docs])):.1f}"
        body.append(
            f"<tr><td>{html.escape(test)}</td><td>{html.escape(name)}</td><td>{ap50}</td>{cells}"
            f"<td>{alarm}</td><td>{len(docs)}</td></tr>"
        )
    caption = (
        "<caption>AP50 points gained if each kind of error were fixed alone (TIDE's definitions, eval/errors.py): "
        "classification, localisation (IoU 0.1–0.5 with its box), both, duplicate, background (IoU &lt; 0.1 with "
        "every box), missed boxes; and detections at confidence ≥ 0.25 per 100 test images without fire. Means "
        "over seeds.</caption>"
    )
    return f"<table>{caption}{head}{''.join(body)}</table>"


def comparisons_html(rows: Sequence[Mapping[str, Any]]) -> str:
    """Paired comparisons: rows with ``test_set``, ``mixture``, ``baseline``, ``metric`` and a
    :meth:`eval.stats.PairedDelta.to_dict` (``value``, ``low``, ``high``, ``p_value``), in AP (or recall) points."""
    head = ("<tr><th>test set</th><th>mixture</th><th>vs</th><th>metric</th><th>Δ</th><th>95% CI</th><th>p</th>"
            "<th>per seed</th><th>resampled</th></tr>")  # fmt: skip
    body = []
    for r in rows:
        d, metric = r["delta"], METRIC_LABELS.get(r["metric"], str(r["metric"]))
        body.append(
            f"<tr><td>{html.escape(str(r['test_set']))}</td><td>{html.escape(str(r['mixture']))}</td>"
            f"<td>{html.escape(str(r['baseline']))}</td><td>{html.escape(metric)}</td>"
            f"<td>{100 * d['value']:+.1f}</td><td>[{100 * d['low']:+.1f}, {100 * d['high']:+.1f}]</td>"
            f"<td>{d['p_value']:.3f}</td><td>{html.escape(per_seed_text(r))}</td>"
            f"<td>{html.escape(str(d.get('resampled', 'images')))}</td></tr>"
        )
    return f"<table>{head}{''.join(body)}</table>"


def per_seed_text(row: Mapping[str, Any]) -> str:
    """A comparison's per-seed differences in points, ``seed 0 +3.8, seed 1 +5.1, seed 2 -2.7`` ("" for none)."""
    return ", ".join(f"seed {s['seed']} {100 * s['delta']:+.1f}" for s in row.get("seeds", ()))


COMPARISON_COLUMNS = ("test_set", "mixture", "baseline", "metric", "delta", "low", "high", "p_value", "resampled",
                      "per_seed")  # fmt: skip


def comparisons_csv(rows: Sequence[Mapping[str, Any]]) -> str:
    """The paired comparisons (:func:`comparisons_html` rows) as CSV: deltas and their 95 % interval in AP
    points, the bootstrap p-value, what the bootstrap resampled (images, or images and seeds) and the per-seed
    differences (``seed:delta`` in points, separated by spaces)."""
    lines = [",".join(COMPARISON_COLUMNS)]
    for r in rows:
        d = r["delta"]
        scaled = [f"{100 * d[k]:.2f}" for k in ("value", "low", "high")]
        seeds = " ".join(f"{s['seed']}:{100 * s['delta']:+.2f}" for s in r.get("seeds", ()))
        lines.append(",".join([str(r["test_set"]), str(r["mixture"]), str(r["baseline"]), str(r["metric"]), *scaled,
                               f"{d['p_value']:.4f}", str(d.get("resampled", "images")), seeds]))  # fmt: skip
    return "\n".join(lines) + "\n"


FIRST_SAMPLES = "synthetic"  # samples whose label starts so follow the answer: the pools its first screen names


def write_study_report(
    out: Path,
    results: Sequence[Mapping[str, Any]],
    rng: np.random.Generator,
    *,
    method_results: Sequence[Mapping[str, Any]] = (),
    controls: Sequence[Mapping[str, Any]] = (),
    gaps: Sequence[Mapping[str, Any]] = (),
    comparisons: Sequence[Mapping[str, Any]] = (),
    errors: Sequence[Mapping[str, Any]] = (),
    samples: Mapping[str, Dataset] | None = None,
    run_columns: Sequence[str] = ("mixture", "seed", "test_set", "AP", "AP50"),
    notice: str = "",
    title: str = "fuzzyfire study",
    answer: Sequence[str] = (),
    answer_details: Sequence[str] = (),
    slices: Sequence[Mapping[str, Any]] = (),
    slice_sets: Mapping[str, Sequence[Mapping[str, Any]]] | None = None,
    forests: Sequence[tuple[Path, str]] = (),
    positives: str = FIRE_IMAGES,
    min_positives: int = MIN_AP_IMAGES,
) -> Path:
    """Write ``out/tables/table{1,2}.{md,csv,tex}`` (AP, AP50 and, when every run has it, AP25),
    ``out/figures/figure5_{AP,AP50}.png``, sample thumbnails and ``out/report.html``, and remove the table files of
    an earlier report that this one does not write (:func:`drop_stale_tables`); returns the page's path.

    ``results``: one mapping per (run, test set) as :func:`eval.tables.table2` takes (also the run list);
    ``method_results``: Table 1 rows (with ``method``); ``controls``: rows of the control runs (Table 2 mixtures
    whose synthetic images were replaced by flame-free copies of their own real images), a table of their own
    (``out/tables/controls.{md,csv,tex}``, rows labelled ``<mixture> copies``) and listed with the runs;
    ``gaps``: see :func:`gaps_html` (also written as ``out/tables/gap.json``); ``comparisons``: see :func:`comparisons_html` (also written as
    ``out/tables/comparisons.csv``, :func:`comparisons_csv`); ``errors``: see :func:`errors_html`;
    ``samples``: datasets to show a few images of, by label; ``notice``: shown at the top of the page. Rows of sets
    with fire that carry :data:`eval.operating.OPERATING` also draw ``out/figures/operating_<test set>.png``
    (:func:`operating_figures`). ``answer``: the study's answer in sentences, the page's first section, and
    ``answer_details`` the rest of it, folded below;
    ``slices``: the slice comparisons (:func:`slices_html`), ``slice_sets`` the slices of each test set
    (:func:`slice_sets_html`) and ``forests`` their forest plots with captions, the section after Table 2;
    ``positives``: what a slice's count is called (:func:`eval.slices.positives_name`); ``min_positives``: how many
    of them a set needs for AP (``report.min_fire_images``), as Table 2's legend says."""
    from eval.plots import plot_figure5
    from eval.tables import control_table, table1, table2

    parts = {"table1": method_results, "table2": results, "controls": controls}
    drop_stale_tables(out / "tables", [stem for stem, rows in parts.items() if rows], bool(comparisons))
    sections: list[tuple[str, str]] = []
    if answer or answer_details:
        first = "<ul>" + "".join(f"<li>{html.escape(a)}</li>" for a in answer) + "</ul>"
        more = "".join(f"<li>{html.escape(a)}</li>" for a in answer_details)
        folded = f"<details><summary>Details: every comparison, slices, false alarms</summary><ul>{more}</ul></details>"
        sections.append(("The answer", first + (folded if more else "")))
    if results:
        metrics = table_metrics(results)
        t2 = table2(results, metrics=metrics)
        write_table_files(t2, out / "tables", "table2")
        sections.append(("Table 2 — training mixtures", table_html(t2) + table2_legend(positives, min_positives)))
        if slices or slice_sets:
            body = "".join(figure_html(f, out, c) for f, c in forests) + slices_html(slices, positives)
            sections.append((f"On which {positives} — slices", body + slice_sets_html(slice_sets or {}, positives)))
    if method_results:
        t1 = table1(method_results, metrics=table_metrics(method_results))
        write_table_files(t1, out / "tables", "table1")
        sections.append(("Table 1 — Method 1 vs Method 2", table_html(t1)))
    if gaps:
        sections.append(("Realism gap of the synthetic pools", gaps_html(gaps)))
    if results:
        alarms = (ALARMS,) if any(ALARMS in r for r in results) else ()
        labelled = (IMAGE_RECALL,) if any(r.get(IMAGE_LABELLED) for r in results) else ()  # broad fires per image
        shown = ("AP", "AP50", *alarms, *(m for m in metrics if m == RECALL_AT_ALARMS), *labelled)
        figures = [plot_figure5(results, out / "figures" / f"figure5_{m}.png", m) for m in shown]
        captions = [_figure5_caption(m) for m in shown]
        sections.append(("Figure 5", "".join(figure_html(f, out, c) for f, c in zip(figures, captions))))
        curves = operating_figures(results, out / "figures") + image_operating_figures(
            results, out / "figures", positives
        )
        if curves:
            caption = f"the dotted line: {ALARM_BUDGET:g} alarms per 100, where Table 2 reads the recall"
            sections.append((found_title(positives), "".join(figure_html(f, out, caption) for f in curves)))
    if controls:
        tc = control_table(controls, metrics=table_metrics(controls))
        write_table_files(tc, out / "tables", "controls")
        sections.append(("Controls — the synthetic images replaced by flame-free copies of the real ones",
                         table_html(tc)))  # fmt: skip
    if comparisons:
        sections.append(("Paired comparisons (image-level bootstrap)", comparisons_html(comparisons)))
        (out / "tables").mkdir(parents=True, exist_ok=True)
        (out / "tables" / COMPARISONS_FILE).write_text(comparisons_csv(comparisons), encoding="utf-8")
    if errors:
        sections.append(("Where AP50 goes (error breakdown)", errors_html(errors)))
    under = 1 if sections and sections[0][0] == "The answer" else None
    for label, ds in (samples or {}).items():
        shown = (f"Samples: {label}", samples_html(ds, out / "samples" / _slug(label), out, rng))
        if label.startswith(FIRST_SAMPLES) and under is not None:
            sections.insert(under, shown)  # what a synthetic pool's images are: a row of them under the first screen
            under += 1
        else:
            sections.append(shown)
    if results or method_results or controls:
        sections.append(("Runs", runs_html(_every_run(results, method_results, controls), run_columns)))
    page = out / "report.html"
    out.mkdir(parents=True, exist_ok=True)
    page.write_text(render_page(title, sections, notice), encoding="utf-8")
    return page


def table2_legend(positives: str = FIRE_IMAGES, min_positives: int = MIN_AP_IMAGES) -> str:
    """The legend under Table 2, its counts called ``positives`` (:func:`eval.slices.positives_name`: ``fire
    images``, or ``images with fire or smoke`` in a study of two classes); a set with fewer than ``min_positives``
    of them has no AP (``report.min_fire_images``)."""
    what = "their fire" if positives == FIRE_IMAGES else "a box of the detection's class"
    return (
        f'<p class="legend">image recall: the share of {html.escape(positives)} with a detection on {what} '
        "(IoU ≥ 0.1 with a box, or its centre inside one) at the threshold where at most 10 of 100 fire-free images "
        "raise an alarm (at confidence 0.25 without a fire-free set); it does not hang on how a set's boxes are "
        f"drawn. A set with fewer than {min_positives} {html.escape(positives)} has no AP or AP50 (–): too few for "
        "an interval that tells mixtures apart.</p>"
    )


def found_title(positives: str = FIRE_IMAGES) -> str:
    """The title of the section of operating curves: ``Fire found against false alarms``, or ``Images with fire or
    smoke found against false alarms`` in a study of two classes."""
    return (
        "Fire found against false alarms"
        if positives == FIRE_IMAGES
        else f"{positives.capitalize()} found against false alarms"
    )


def slices_html(rows: Sequence[Mapping[str, Any]], positives: str = FIRE_IMAGES) -> str:
    """The slice comparisons (:func:`eval.slices.compare_slices` rows with ``test_set``, ``mixture``,
    ``baseline``): one row per (comparison, test set, slice), a column per metric with Δ and its 95 % interval in
    points, bold where Holm's correction keeps it (helps or hurts); the slice's count headed ``positives``."""
    if not rows:
        return ""
    metrics = list(dict.fromkeys(r["metric"] for r in rows))
    grouped: dict[tuple[str, str, str, str], dict[str, Mapping[str, Any]]] = {}
    for r in rows:
        grouped.setdefault((r["test_set"], r["mixture"], r["baseline"], r["slice"]), {})[r["metric"]] = r
    head = f"<tr><th>test set</th><th>mixture</th><th>vs</th><th>slice</th><th>{html.escape(positives)}</th>"
    head += "".join(f"<th>Δ {html.escape(METRIC_LABELS.get(m, m))}</th>" for m in metrics) + "</tr>"
    body = []
    for (test, mixture, base, name), by_metric in grouped.items():
        first = next(iter(by_metric.values()))
        cells = []
        for m in metrics:
            r = by_metric.get(m)
            if r is None:
                cells.append("<td>–</td>")
                continue
            d = r["delta"]
            text = f"{100 * d['value']:+.1f} [{100 * d['low']:+.1f}, {100 * d['high']:+.1f}]"
            cells.append(f"<td><b>{text}</b></td>" if r["verdict"] != "-" else f"<td>{text}</td>")
        body.append(f"<tr><td>{html.escape(test)}</td><td>{html.escape(mixture)}</td><td>{html.escape(base)}</td>"
                    f"<td>{html.escape(name)}</td><td>{first['fire_images']}</td>{''.join(cells)}</tr>")  # fmt: skip
    caption = ("<caption>Each comparison slice by slice: Δ (points) with its 95 % paired bootstrap interval over the "
               "slice's images and the seeds. <b>Bold</b>: the difference holds after Holm's correction over the "
               "slices of one comparison and metric (family-wise error 5 %).</caption>")  # fmt: skip
    return f"<table>{caption}{head}{''.join(body)}</table>"


def slice_sets_html(sets: Mapping[str, Sequence[Mapping[str, Any]]], positives: str = FIRE_IMAGES) -> str:
    """The slices of each test set (images, and ``positives``: fire images, or images with fire or smoke); those
    with too few of them to compare are marked."""
    body = []
    for test, rows in sets.items():
        for r in rows:
            mark = " (too few to compare)" if r["too_few"] else ""
            body.append(f"<tr><td>{html.escape(test)}</td><td>{html.escape(r['slice'])}</td><td>{r['images']}</td>"
                        f"<td>{r['fire_images']}{mark}</td></tr>")  # fmt: skip
    if not body:
        return ""
    caption = ("<caption>The slices: attributes computed from each image and its boxes (docs/scoring.md); slices "
               f"with fewer than {MIN_FIRE_IMAGES} {html.escape(positives)} are merged with a neighbour or into "
               "'other'.</caption>")  # fmt: skip
    head = f"<tr><th>test set</th><th>slice</th><th>images</th><th>{html.escape(positives)}</th></tr>"
    return f"<details><summary>Slices of each test set</summary><table>{caption}{head}{''.join(body)}</table></details>"


def _figure5_caption(metric: str) -> str:
    """What a Figure 5 panel shows, in words."""
    what = METRIC_LABELS.get(metric, metric)
    return f"Figure 5 — {what} per training mixture, one bar per test set: mean ± sd over the seeds"


def _every_run(*groups: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The rows of every table once (a run in Table 1 and Table 2 is one run), in table order; a row is one
    (run, test set)."""
    seen: set[tuple[Any, Any]] = set()
    out = []
    for rows in groups:
        for r in rows:
            key = (r.get("run"), r.get("test_set"))
            if key[0] is None or key not in seen:
                seen.add(key)
                out.append(r)
    return out


#: The files of ``out/tables`` a study report writes (and removes when this report has none of them).
TABLE_STEMS: tuple[str, ...] = ("table1", "table2", "controls")
TABLE_SUFFIXES: tuple[str, ...] = (".md", ".csv", ".tex")
COMPARISONS_FILE = "comparisons.csv"


def drop_stale_tables(folder: Path, written: Collection[str], comparisons: bool) -> None:
    """Remove the table files of ``folder`` that this report will not write again: those of the
    :data:`TABLE_STEMS` not in ``written``, and ``comparisons.csv`` unless ``comparisons``, so a study re-reported
    with fewer runs or another config never shows an earlier report's table beside its own. Other files stay."""
    stale = [folder / f"{stem}{suffix}" for stem in TABLE_STEMS if stem not in written for suffix in TABLE_SUFFIXES]
    for path in stale + ([] if comparisons else [folder / COMPARISONS_FILE]):
        path.unlink(missing_ok=True)


OPERATING_RATES = np.linspace(0.0, 100.0, 401)  # alarms per 100 images at which the operating curves are drawn


def found_objects(results: Sequence[Mapping[str, Any]]) -> str:
    """What the boxes of the sets ``results`` score are called (:func:`eval.slices.objects_name` of their rows'
    ``classes``, which :func:`fuzzyfire.aggregate.per_class_ap` gives a set of several): ``fire``, or e.g. ``fire or
    smoke`` in a study of two classes."""
    return objects_name(list(dict.fromkeys(name for r in results for name in r.get("classes", ()))))


def operating_figures(results: Sequence[Mapping[str, Any]], folder: Path) -> list[Path]:
    """``folder/operating_<test set>.png`` per set with fire whose rows carry :data:`eval.operating.OPERATING`:
    each mixture's recall of the set's boxes (every class's, pooled) against false alarms per 100 images without
    them (:func:`eval.plots.plot_operating_curves`, its seeds' mean and range), up to 100 alarms per 100 images;
    titles and axes name the boxes' classes (:func:`found_objects`)."""
    from eval.plots import plot_operating_curves

    by_test: dict[str, dict[str, list]] = {}
    for r in (r for r in results if r.get(OPERATING) is not None):
        recall = recall_at_rates(*r[OPERATING], OPERATING_RATES)
        by_test.setdefault(r["test_set"], {}).setdefault(r["mixture"], []).append(recall)
    paths = []
    for test, curves in by_test.items():
        objects = found_objects([r for r in results if r["test_set"] == test])
        labels = (f"false alarms per 100 images without {objects}", f"{objects} boxes found at IoU 0.5 (%)")
        paths.append(plot_operating_curves({m: np.stack(c) for m, c in curves.items()}, OPERATING_RATES,
                                           folder / f"operating_{_slug(test)}.png", ALARM_BUDGET,
                                           f"{test}: {objects} found against false alarms", labels))  # fmt: skip
    return paths


def image_operating_figures(
    results: Sequence[Mapping[str, Any]], folder: Path, positives: str = FIRE_IMAGES
) -> list[Path]:
    """``folder/image_operating_<test set>.png`` per set with fire whose rows carry
    :data:`eval.imagelevel.IMAGELEVEL` with per-image alarms: each mixture's image recall against false-alarm
    images per 100 images without fire (:func:`eval.imagelevel.image_operating_curve`, seeds' mean and range);
    ``positives``: what the detected images are called in the title and axis."""
    from eval.plots import plot_operating_curves

    by_test: dict[str, dict[str, list]] = {}
    for r in results:
        level = r.get(IMAGELEVEL)
        if level is None or not isinstance(level[1], Alarms):
            continue
        curve = curve_at_rates(*image_operating_curve(*level), OPERATING_RATES)
        by_test.setdefault(r["test_set"], {}).setdefault(r["mixture"], []).append(curve)
    return [
        plot_operating_curves({m: np.stack(c) for m, c in curves.items()}, OPERATING_RATES,
                              folder / f"image_operating_{_slug(test)}.png", ALARM_BUDGET,
                              f"{test}: {positives} detected against false-alarm images",
                              ("fire-free images with a false alarm, per 100", f"{positives} detected (%)"))
        for test, curves in by_test.items()
    ]  # fmt: skip


def table_metrics(results: Sequence[Mapping[str, Any]]) -> tuple[str, ...]:
    """The paper's AP and AP50, then AP25 (:mod:`ground.detect.cocoeval`; runs scored before it existed lack it),
    the recall at 10 alarms per 100 images without fire (:mod:`eval.operating`; only studies with a set without
    fire have it) and the image recall (:mod:`eval.imagelevel`), each when every row of a set with boxes has it,
    then in a study of several classes each class's image recall; the sets without fire have their alarm columns
    and the image-labelled sets their image recall whatever this says."""
    fire = [r for r in results if ALARMS not in r and not r.get(IMAGE_LABELLED)]
    extra = [m for m in ("AP25", RECALL_AT_ALARMS, IMAGE_RECALL) if fire and all(r.get(m) is not None for r in fire)]
    names = dict.fromkeys(name for r in fire for name in r.get("classes", ()))
    per_class = [class_metric(k, name) for name in names for k in CLASS_METRICS]
    recall = [class_metric(IMAGE_RECALL, n) for n in names if IMAGE_RECALL in extra]
    return ("AP", "AP50", *per_class, *extra, *(k for k in recall if any(r.get(k) is not None for r in fire)))


def _slug(label: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in label).strip("_") or "samples"

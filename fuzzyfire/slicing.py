"""On which fires: the study's slices. Every test set with fire gets its images' attributes (:mod:`eval.attributes`,
computed once per set and kept in ``OUT/slices/``, plus the user's from ``report.attributes``), its slices
(:mod:`eval.slices`), and every comparison the study makes (each Table 2 mixture against the baseline, each
against its control) is repeated slice by slice (:func:`eval.slices.compare_slices`), written to
``OUT/tables/slices.csv`` and drawn as one forest plot per (comparison, test set).

A run's views of a test set are derived once from its ``predictions.json`` and kept beside it with the
predictions' digest (:mod:`fuzzyfire.kept`): its matches at IoU 0.25 (``matches25.npz``) and its image hits
(``image_hits.json``, :class:`eval.imagelevel.ImageHits`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from eval.attributes import Attributes, dataset_attributes, merged, read_attributes_csv
from eval.imagelevel import IMAGE_LABELLED, IMAGE_RECALL, IMAGELEVEL, ImageHits, image_hits
from eval.slices import FIRE_IMAGES, METRICS, Side, compare_slices, make_slices, slice_table
from eval.stats import MatchTable
from fuzzyfire.datasets import DataRef, Datasets
from fuzzyfire.kept import keep, kept
from fuzzyfire.stages import digest

ATTRIBUTES_VERSION = 5  # bumped when an attribute's definition changes: kept attributes are computed again
HITS_FILE = "image_hits.json"
MATCHES25_FILE = "matches25.npz"
SLICES_FILE = "slices.csv"


def set_attributes(datasets: Datasets, ref: DataRef, out: Path, user: Path | None = None) -> Attributes:
    """The attributes of every image of the test set ``ref``: computed once and kept in
    ``out/slices/<digest of the set>.json``, with the user's CSV ``user`` (:func:`eval.attributes.read_attributes_csv`)
    added when given."""
    ds = datasets.get(ref)
    path = out / "slices" / f"attributes-{digest({'set': ref.key(), 'version': ATTRIBUTES_VERSION})}.json"
    if path.is_file():
        computed = {int(k): v for k, v in json.loads(path.read_text(encoding="utf-8")).items()}
    else:
        computed = dataset_attributes(ds)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({str(k): v for k, v in computed.items()}, indent=0) + "\n", encoding="utf-8")
    return merged(computed, read_attributes_csv(user, ds)) if user is not None else computed


def run_hits(datasets: Datasets, folder: Path, ref: DataRef) -> ImageHits:
    """A run's :class:`eval.imagelevel.ImageHits` on the test set ``ref`` (scored into ``folder``), kept in
    ``folder/image_hits.json``."""
    predictions = (folder / "predictions.json").read_bytes()
    if (known := kept(folder / HITS_FILE, predictions)) is not None:
        best = np.asarray([-np.inf if v is None else v for v in known["best"]], dtype=np.float64)
        return ImageHits(np.asarray(known["image_ids"], np.int64), np.asarray(known["fire"], bool), best)
    ds = datasets.get(ref)
    hits = image_hits(ds, json.loads(predictions), [c.id for c in ds.categories])
    doc = {"image_ids": hits.image_ids.tolist(), "fire": hits.fire.tolist(),
           "best": [None if not np.isfinite(v) else float(v) for v in hits.best]}  # fmt: skip
    keep(folder / HITS_FILE, predictions, doc)
    return hits


def run_matches25(datasets: Datasets, folder: Path, ref: DataRef) -> MatchTable:
    """A run's matches at IoU 0.25 on the test set ``ref`` (:class:`eval.stats.MatchTable`), kept in
    ``folder/matches25.npz`` (its predictions' digest in ``folder/matches25.json``)."""
    from ground.detect.cocoeval import LOOSE_IOU, run_cocoeval

    predictions = (folder / "predictions.json").read_bytes()
    npz, stamp = folder / MATCHES25_FILE, folder / "matches25.json"
    if npz.is_file() and kept(stamp, predictions) is not None:
        return MatchTable.load(npz)
    ds = datasets.get(ref)
    table = MatchTable(run_cocoeval(ds, json.loads(predictions), [c.id for c in ds.categories], [LOOSE_IOU]))
    table.save(npz)
    keep(stamp, predictions, {})
    return table


def study_slices(
    rows: Sequence[Mapping[str, Any]],
    pairs: Sequence[tuple[str, str, str, str]],
    tests: Mapping[str, DataRef],
    datasets: Datasets,
    out: Path,
    rng: np.random.Generator,
    num_samples: int,
    user: Mapping[str, Path] | None = None,
) -> tuple[list[dict[str, Any]], dict[str, list[dict[str, Any]]]]:
    """Slice comparisons of every ``pairs`` entry (baseline's table, baseline mixture, its label, compared
    mixture: :func:`fuzzyfire.aggregate.comparison_pairs`) on every test set of ``tests`` (label -> data) with fire;
    ``rows``: the study's rows with :data:`IMAGELEVEL` (:func:`fuzzyfire.aggregate.result_rows`). Returns the
    comparison rows (each with ``test_set``, ``mixture``, ``baseline``) and the slices of each test set
    (:func:`eval.slices.slice_table`)."""
    out_rows: list[dict[str, Any]] = []
    tables: dict[str, list[dict[str, Any]]] = {}
    for test, ref in tests.items():
        scored = [r for r in rows if r["test_set"] == test and r.get(IMAGELEVEL) is not None]
        if not scored:
            continue
        hits = scored[0][IMAGELEVEL][0]
        boxed = not scored[0].get(IMAGE_LABELLED)  # an image-labelled set is sliced by image recall only
        metrics = METRICS if all(r["AP50"] is not None for r in scored) else tuple(m for m in METRICS if m != "AP50")
        metrics = metrics if boxed else (IMAGE_RECALL,)
        attrs = set_attributes(datasets, ref, out, (user or {}).get(test))
        slices = make_slices(attrs, hits.image_ids, hits.fire)
        tables[test] = slice_table(slices)
        needed = {(table, base) for table, base, _, _ in pairs} | {("table2", name) for *_, name in pairs}
        sides = _sides(scored, needed, datasets, ref, boxed)
        for table, base, base_label, name in pairs:
            a, b = sides.get((table, base)), sides.get(("table2", name))
            if a is None or b is None:
                continue
            for r in compare_slices(a, b, slices, rng, num_samples, metrics):
                out_rows.append({"test_set": test, "mixture": name, "baseline": base_label, **r})
    return out_rows, tables


def _sides(
    rows: Sequence[Mapping[str, Any]], needed: set[tuple[str, str]], datasets: Datasets, ref: DataRef, boxed: bool
) -> dict[tuple[str, str], Side]:
    """The :class:`eval.slices.Side` of every (table, mixture) of ``needed`` among ``rows`` (one test set), its
    seeds in order (the runs of Table 1 and other uncompared ones get no loose matches; on a set without boxes,
    ``boxed`` False, no run has matches)."""
    by: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for r in rows:
        for table in r["tables"]:
            if (table, r["mixture"]) in needed:
                by.setdefault((table, r["mixture"]), []).append(r)
    sides = {}
    for key, group in by.items():
        group = sorted(group, key=lambda r: r["seed"])
        folders = [Path(r["matches"]).parent for r in group]
        sides[key] = Side(
            [MatchTable.load(Path(r["matches"])) for r in group] if boxed else [],
            [run_matches25(datasets, f, ref) for f in folders] if boxed else [],
            [r[IMAGELEVEL] for r in group],
        )
    return sides


def slices_csv(rows: Sequence[Mapping[str, Any]]) -> str:
    """The slice comparisons as CSV: deltas and 95 % interval in points, bootstrap and Holm p-values, verdict."""
    import csv
    import io

    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["test_set", "mixture", "baseline", "slice", "images", "fire_images", "metric", "delta", "low",
                     "high", "p_value", "p_holm", "verdict"])  # fmt: skip
    for r in rows:
        d = r["delta"]
        writer.writerow([r["test_set"], r["mixture"], r["baseline"], r["slice"], r["images"], r["fire_images"],
                         r["metric"], *(f"{100 * d[k]:.3f}" for k in ("value", "low", "high")),
                         f"{d['p_value']:.4f}", f"{r['p_holm']:.4f}", r["verdict"]])  # fmt: skip
    return text.getvalue()


def forest_figures(
    rows: Sequence[Mapping[str, Any]], folder: Path, positives: str = FIRE_IMAGES
) -> list[tuple[Path, str]]:
    """``folder/forest_<mixture>_vs_<baseline>_<test set>.png`` per (comparison, test set) of the slice ``rows``
    (:func:`eval.plots.plot_forest`, one panel per metric; each slice's count named ``positives``,
    :func:`eval.slices.positives_name`), with their captions."""
    from eval.plots import plot_forest

    groups: dict[tuple[str, str, str], dict[str, list[Mapping[str, Any]]]] = {}
    for r in rows:
        groups.setdefault((r["mixture"], r["baseline"], r["test_set"]), {}).setdefault(r["metric"], []).append(r)
    out = []
    for (mixture, baseline, test), panels in groups.items():
        name = "_".join("".join(c if c.isalnum() else "-" for c in p) for p in (mixture, "vs", baseline, test))
        title = f"{mixture} − {baseline} on {test}, by slice ({positives})"
        path = plot_forest(panels, folder / f"forest_{name}.png", title)
        caption = (f"{mixture} minus {baseline} on {test}, slice by slice: 95 % paired bootstrap intervals over "
                   "images and seeds; filled: the interval's p-value holds after Holm's correction")  # fmt: skip
        out.append((path, caption))
    return out

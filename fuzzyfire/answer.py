"""The study's answer in plain sentences, built from its numbers only: which mixture is best on which test set,
what the synthetic images add against the baseline and against the control (with 95 % intervals), the slices
where that difference holds after Holm's correction, and the false-alarm trade-off, with a caveat where the seeds,
the test images or a slice are too few. The report's first screen and ``fuzzyfire experiment``'s last lines."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from collections.abc import Set as AbstractSet
from typing import Any

from eval.errors import ALARMS
from eval.imagelevel import IMAGE_RECALL
from eval.slices import FIRE_IMAGES
from eval.stats import MIN_SEEDS_RESAMPLED, mean_std
from fuzzyfire.first_screen import delta_text, metric_name, seed_counts, seeds_text, unlearned_mixtures
from fuzzyfire.first_screen import verdict as comparison_verdict

SHOWN_SLICES = 4  # slices named per comparison and direction (the largest differences); the rest are counted


def _mean(rows: Sequence[Mapping[str, Any]], mixture: str, test: str, metric: str) -> tuple[float, float | None, int]:
    values = [
        r[metric] for r in rows if r["mixture"] == mixture and r["test_set"] == test and r.get(metric) is not None
    ]
    m = mean_std(values)
    return m.mean, m.std, m.n


def headline_metric(rows: Sequence[Mapping[str, Any]], test: str) -> str | None:
    """The metric a test set is judged by: AP50 when its rows have it, else image recall (too few fire images
    for AP), else None (a set without fire)."""
    mine = [r for r in rows if r["test_set"] == test]
    for metric in ("AP50", IMAGE_RECALL):
        if mine and all(r.get(metric) is not None for r in mine):
            return metric
    return None


def answer(
    rows: Sequence[Mapping[str, Any]],
    comparisons: Sequence[Mapping[str, Any]],
    slices: Sequence[Mapping[str, Any]] = (),
    notes: Sequence[str] = (),
    positives: str = FIRE_IMAGES,
) -> list[str]:
    """The answer's sentences (module docstring). ``rows``: Table 2's rows (:func:`fuzzyfire.aggregate.result_rows`);
    ``comparisons``: :func:`fuzzyfire.aggregate.comparisons`; ``slices``: :func:`fuzzyfire.slicing.study_slices`'s
    comparison rows; ``notes``: caveats known elsewhere (leaked test images dropped), appended as they are;
    ``positives``: what a slice's ``fire_images`` count (:func:`eval.slices.positives_name`)."""
    lines = []
    tests = list(dict.fromkeys(r["test_set"] for r in rows))
    mixtures = list(dict.fromkeys(r["mixture"] for r in rows))
    for test in tests:
        metric = headline_metric(rows, test)
        if metric is None:
            continue
        ranked = sorted(
            (m for m in mixtures if _has(rows, m, test, metric)), key=lambda m: -_mean(rows, m, test, metric)[0]
        )
        shown = "; ".join(_cell(rows, m, test, metric) for m in ranked)
        lines.append(f"Best on {test} by {metric_name(metric)}: {ranked[0]} ({shown}).")
    unlearned = unlearned_mixtures(rows)
    for c in comparisons:
        metric = headline_metric(rows, c["test_set"])
        if c["metric"] != metric:
            continue
        sure = seeds_text(c)
        lines.append(f"On {c['test_set']}, {c['mixture']} against {c['baseline']}: {metric_name(metric)} "
                     f"{delta_text(c['delta'])} points{', ' + sure if sure else ''}, "
                     f"{comparison_verdict(c, bool({c['mixture'], c['baseline']} & unlearned))}.")  # fmt: skip
    lines += _slice_lines(slices, unlearned, positives)
    lines += _alarm_lines(rows, tests, mixtures)
    seeds = max(seed_counts(rows).values(), default=0)
    if 0 < seeds < MIN_SEEDS_RESAMPLED:
        lines.append(f"Caveat: {seeds} seed{'s' * (seeds != 1)} per mixture; the intervals cover the test images and "
                     "the mean of these seeds, not how another training of the same mixture would land.")  # fmt: skip
    return lines + list(notes)


def _has(rows: Sequence[Mapping[str, Any]], mixture: str, test: str, metric: str) -> bool:
    return any(r["mixture"] == mixture and r["test_set"] == test and r.get(metric) is not None for r in rows)


def _cell(rows: Sequence[Mapping[str, Any]], mixture: str, test: str, metric: str) -> str:
    mean, std, n = _mean(rows, mixture, test, metric)
    spread = f" ± {100 * std:.1f}" if std is not None else ""
    return f"{mixture} {100 * mean:.1f}{spread}"


def _slice_lines(slices: Sequence[Mapping[str, Any]], unlearned: AbstractSet[str], positives: str) -> list[str]:
    """Per (comparison, test set): the slices helped and hurt after Holm's correction, or that none is, each slice
    with its count of ``positives``; a comparison with a mixture in ``unlearned`` (a run that did not converge) is
    said not to be read."""
    groups: dict[tuple[str, str, str], list[Mapping[str, Any]]] = {}
    for r in slices:
        groups.setdefault((r["test_set"], r["mixture"], r["baseline"]), []).append(r)
    lines = []
    for (test, mixture, baseline), rows in groups.items():
        found = [r for r in rows if r["verdict"] != "-"]
        names = len({r["slice"] for r in rows})
        if not found:
            lines.append(f"On {test}, no slice separates {mixture} from {baseline} after Holm's correction "
                         f"({names} slices x {len({r['metric'] for r in rows})} metrics).")  # fmt: skip
            continue
        for verdict in ("helps", "hurts"):
            these = _strongest([r for r in found if r["verdict"] == verdict])
            if not these:
                continue
            text = "; ".join(f"{r['slice']} ({r['fire_images']} {positives}) {metric_name(r['metric'])} "
                             f"{delta_text(r['delta'])}" for r in these[:SHOWN_SLICES])  # fmt: skip
            more = len(these) - SHOWN_SLICES
            rest = f"; and {more} more slice{'s' * (more > 1)} (tables/slices.csv)" if more > 0 else ""
            unread = "; not read: a run in it did not converge" if {mixture, baseline} & unlearned else ""
            lines.append(f"On {test}, {mixture} against {baseline} {verdict} on {text}{rest} (Holm-corrected{unread}).")
    return lines


def _strongest(rows: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """One row per slice, its largest difference of any metric, slices by that difference, largest first."""
    best: dict[str, Mapping[str, Any]] = {}
    for r in rows:
        if r["slice"] not in best or abs(r["delta"]["value"]) > abs(best[r["slice"]]["delta"]["value"]):
            best[r["slice"]] = r
    return sorted(best.values(), key=lambda r: -abs(r["delta"]["value"]))


def _alarm_lines(rows: Sequence[Mapping[str, Any]], tests: Sequence[str], mixtures: Sequence[str]) -> list[str]:
    """The false alarms of each mixture on the sets without fire, and the fire images each detects at the alarm
    budget (:mod:`eval.imagelevel`) when the study has such a set."""
    lines = []
    free = any(r.get(ALARMS) is not None for r in rows)
    for test in tests if free else ():
        if not any(r["test_set"] == test and r.get(IMAGE_RECALL) is not None for r in rows):
            continue
        shown = "; ".join(_cell(rows, m, test, IMAGE_RECALL) for m in mixtures if _has(rows, m, test, IMAGE_RECALL))
        lines.append(f"Fire images of {test} detected at 10 false-alarm images per 100 fire-free ones (%): {shown}.")
    for test in tests:
        if not any(r["test_set"] == test and r.get(ALARMS) is not None for r in rows):
            continue
        shown = "; ".join(f"{m} {_mean(rows, m, test, ALARMS)[0]:.1f}" for m in mixtures if _has(rows, m, test, ALARMS))
        lines.append(f"False alarms on {test} (detections at confidence 0.25 per 100 images): {shown}.")
    return lines

"""The answer's first screen: about ten lines that stand alone before any table. What was compared (each pool in
one sentence of what its images are), the headline with its interval and the control's share, how sure (seeds
that agree in sign, what the interval resamples, runs that did not learn) and what the data became (classes,
curation, leakage). Built from the study's numbers and its data's own records (``curation.json``, each pool's
``manifest.json``, :class:`ground.data.load.ClassChanges`, :class:`fuzzyfire.leakage.TestLeaks`)."""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from curate.curation import read_curation
from curate.mix import parse_mixture
from eval.operating import ALARM_BUDGET
from eval.tables import METRIC_LABELS

MIN_FREE_IMAGES = 100  # fewer fire-free test images than this: the alarm budget's steps are coarse, said so


def metric_name(metric: str) -> str:
    """A metric as the tables head it (``image_recall`` -> ``image recall``)."""
    return METRIC_LABELS.get(metric, metric)


def delta_text(d: Mapping[str, float]) -> str:
    """A paired difference in points with its interval: ``+3.0 [+0.5, +5.5]``."""
    return f"{100 * d['value']:+.1f} [{100 * d['low']:+.1f}, {100 * d['high']:+.1f}]"


def per_class_text(comparisons: Sequence[Mapping[str, Any]], c: Mapping[str, Any], against: str = "") -> str:
    """The per-class deltas of comparison ``c`` (same set, mixture, baseline; metric ``"<c's metric> <class>"``,
    :func:`eval.tables.class_metric`): `` Per class: fire +0.4 [-2.0, +2.9], smoke +6.1 [+1.2, +11.0].``, ``against``
    saying what they are measured against when the sentence before names another baseline; empty for a set of one
    class."""
    parts = [f"{x['metric'][len(c['metric']) + 1:]} {delta_text(x['delta'])}" for x in comparisons
             if x["test_set"] == c["test_set"] and x["mixture"] == c["mixture"] and x["baseline"] == c["baseline"]
             and x["metric"].startswith(f"{c['metric']} ")]  # fmt: skip
    return f" Per class{against}: {', '.join(parts)}." if parts else ""


def unlearned_mixtures(rows: Sequence[Mapping[str, Any]]) -> set[str]:
    """The mixtures (table labels) with a run that did not converge (:mod:`fuzzyfire.learning`)."""
    return {r["mixture"] for r in rows if r.get("learning")}


def pool_sentence(manifest: Path, flames: str, size: int | None = None) -> str:
    """What a Method 2 pool's images are, from its ``manifest.json`` (each image's metadata): how many carry
    pasted flames on the user's labelled frames, on fire-free photos or on rendered places, how many are photos
    left as they are (negatives), and whether the flames are simulated or cut out of the real images
    (``flames``: the pool's ``flames.source``), and its plumes of smoke (:mod:`synth.smoke`) when it has any. ``size``: the images a mixture draws of it, when fewer."""
    meta = json.loads(manifest.read_text(encoding="utf-8"))["args"].get("per_image", [])
    kind = "cut-out flames (from the real training images)" if flames == "cutouts" else "simulated flames"
    counts = {"frames": 0, "frames_plain": 0, "photos": 0, "photos_plain": 0, "places": 0, "places_plain": 0}
    for m in meta:
        where = "frames" if "frame_boxes" in m else "photos" if "photo" in m else "places"
        counts[where if m.get("flames") else f"{where}_plain"] += 1
    flames_n = sum(len(m.get("flames", ())) for m in meta)
    parts = []
    if counts["frames"]:
        parts.append(f"{counts['frames']} of the real training frames with pasted flames"
                     + (f" and {counts['frames_plain']} left without" if counts["frames_plain"] else ""))  # fmt: skip
    elif counts["frames_plain"]:
        parts.append(f"{counts['frames_plain']} real training frames")
    if counts["photos"]:
        parts.append(f"{counts['photos']} fire-free photos with pasted flames")
    if counts["photos_plain"]:
        parts.append(f"{counts['photos_plain']} fire-free photos as they are (negatives)")
    if counts["places"] or counts["places_plain"]:
        parts.append(
            f"{counts['places'] + counts['places_plain']} rendered places ({counts['places_plain']} without flames)"
        )
    drawn = f"; a mixture draws {size} of its {len(meta)}" if size is not None and size < len(meta) else ""
    smoke = plume_words([p for m in meta for p in m.get("plumes", ())])
    laid = f"{flames_n} {kind}" if flames_n else "no pasted flames"
    if smoke and not flames_n:  # a pool of plumes: they lead
        return f"{len(meta)} images: {smoke}, on {', '.join(parts) or 'none'}; {laid}{drawn}"
    return f"{len(meta)} images: {', '.join(parts) or 'none'}; {laid}{'; ' + smoke if smoke else ''}{drawn}"


def plume_words(plumes: Sequence[Mapping[str, Any]]) -> str:
    """``206 plumes of smoke (160 on the ground, 46 in the sky; 206 own)`` from a pool's plume records (where each
    was laid, its colour); "" without plumes."""
    if not plumes:
        return ""
    names = {"above": "above flames", "ground": "on the ground", "sky": "in the sky"}
    where = Counter(p["where"] for p in plumes)
    places = ", ".join(f"{where[k]} {v}" for k, v in names.items() if where[k])
    colours = ", ".join(f"{n} {c}" for c, n in Counter(p["colour"] for p in plumes).most_common())
    return f"{len(plumes)} plumes of smoke ({places}; {colours})"


def curation_sentence(folder: Path) -> str | None:
    """What curation made of the real images (``folder/curation.json``): read, duplicates dropped, split sizes;
    None for a folder that was not curated."""
    doc = read_curation(folder)
    if doc is None:
        return None
    c = doc.get("counts", {})
    splits = " / ".join(f"{k} {v:,}" for k, v in doc.get("splits", {}).items())
    return (f"curation read {c.get('images', 0):,} images, dropped {c.get('removed_exact', 0):,} exact and "
            f"{c.get('removed_near', 0):,} near duplicates ({c.get('unreadable', 0)} unreadable), split {splits}")  # fmt: skip


def class_sentence(classes: Sequence[str], given: bool, changes: Mapping[str, Any]) -> str:
    """The classes studied (named by the config, or the real data's) and what the class rules removed from each
    set (``changes``: :class:`ground.data.load.ClassChanges` by set label; sets it left alone are not named)."""
    source = "as the config names them" if given else "every class the real data boxes"
    touched = [f"{name}: {c.text()}" for name, c in changes.items() if c]
    rules = "; ".join(touched) if touched else "No box removed from any set"
    return f"Classes studied: {', '.join(classes)} ({source}). {rules}."


def leak_sentence(leaks: Mapping[str, Any]) -> str | None:
    """How many images of each test set the leakage check found in the training data (dropped before scoring)."""
    if not leaks:
        return None
    parts = [f"{name} {len(t.leaked)} of {t.images}" for name, t in leaks.items()]
    return f"Leakage check: test images found in the training data and dropped: {', '.join(parts)} (leakage.json)."


def free_images_note(free: int) -> str | None:
    """The alarm budget's resolution on ``free`` fire-free test images, a warning under :data:`MIN_FREE_IMAGES`."""
    if not free:
        return None
    step = 100 / free
    coarse = f"; fewer than {MIN_FREE_IMAGES}: image recall moves in coarse steps" if free < MIN_FREE_IMAGES else ""
    return f"the alarm budget on {free} fire-free images allows {int(free * ALARM_BUDGET / 100)} alarm images, one image = {step:.1f} per 100{coarse}"


def seeds_text(row: Mapping[str, Any]) -> str:
    """``seeds agree 2 of 3 (+3.8, +5.1, -2.7)`` from a comparison's per-seed differences ("" with one seed)."""
    deltas = [d["delta"] for d in row.get("seeds", ())]
    if len(deltas) < 2:
        return ""
    point = row["delta"]["value"]
    agree = sum(1 for d in deltas if d * point > 0)
    return f"seeds agree {agree} of {len(deltas)} ({', '.join(f'{100 * d:+.1f}' for d in deltas)})"


def sides_text(row: Mapping[str, Any]) -> str:
    """`` (R200_S200 over seeds 0, 1; R200_S0 over seed 0: each side averaged over its own seeds)`` when the two
    sides of a comparison were trained over other seeds (its interval then resamples the test images only); ""
    when they hold the same seeds (or the row does not say)."""
    mine, theirs = row.get("mixture_seeds"), row.get("baseline_seeds")
    if mine is None or theirs is None or list(mine) == list(theirs):
        return ""

    def over(seeds) -> str:
        return f"seed{'s' if len(seeds) > 1 else ''} {', '.join(str(s) for s in seeds)}"

    return (
        f" ({row['mixture']} over {over(mine)}; {row['baseline']} over {over(theirs)}: each side averaged over its own "
        "seeds)"
    )


def verdict(row: Mapping[str, Any], unlearned: bool) -> str:
    """The verdict on one comparison: it helps (or hurts) only when the interval excludes 0 *and* every seed's
    difference has that sign, and no run of it is flagged as not converged."""
    if unlearned:
        return "not read: a run in it did not converge"
    d = row["delta"]
    deltas = [s["delta"] for s in row.get("seeds", ())]
    if d["low"] <= 0 <= d["high"]:
        return "not distinguishable from 0"
    sign = 1 if d["low"] > 0 else -1
    against = sum(1 for x in deltas if x * sign <= 0)
    if against:
        return f"the interval excludes 0 but {against} of {len(deltas)} seeds disagree: not settled"
    return "it helps" if sign > 0 else "it hurts"


def headline_lines(
    rows: Sequence[Mapping[str, Any]],
    comparisons: Sequence[Mapping[str, Any]],
    metric_of,
    baseline: str | None,
    added: str = "flames",
) -> list[str]:
    """Per test set with a headline metric (``metric_of(test)``): each mixture with synthetic images against the
    baseline, and, where it has a control, the share of what its pool pastes (``added``: ``flames``, or ``flames
    and smoke`` for a pool that lays plumes) beyond that control first."""
    lines = []
    unlearned = unlearned_mixtures(rows)
    for c in comparisons:
        if c["metric"] != metric_of(c["test_set"]) or c["baseline"] != baseline or c["mixture"].endswith(" copies"):
            continue
        control = next((x for x in comparisons if x["test_set"] == c["test_set"] and x["metric"] == c["metric"]
                        and x["mixture"] == c["mixture"] and x["baseline"] == f"{c['mixture']} copies"), None)  # fmt: skip
        bad = bool({c["mixture"], baseline} & unlearned)
        sure = seeds_text(c)
        if control is not None:
            bad_control = bad or f"{c['mixture']} copies" in unlearned
            copies = c["delta"]["value"] - control["delta"]["value"]
            lines.append(
                f"On {c['test_set']}, the {added} of {c['mixture']} add {metric_name(c['metric'])} "
                f"{delta_text(control['delta'])} points beyond copies of the same real images with nothing pasted "
                f"(the control; "
                f"{seeds_text(control) or 'one seed'}){sides_text(control)}: "
                f"{verdict(control, bad_control)}. Against {baseline} the "
                f"mixture reads {delta_text(c['delta'])}{sides_text(c)}; the copies alone (more images and steps) about "
                f"{100 * copies:+.1f}.{per_class_text(comparisons, control, ' beyond the control')}"
            )
            continue
        mix, base = parse_mixture(c["mixture"]), parse_mixture(baseline or c["mixture"])
        synthetic = mix.synth > base.synth
        lines.append(
            f"On {c['test_set']}, {added_text(mix.real - base.real, mix.synth - base.synth, added)} "
            f"({c['mixture']} vs {baseline}): {metric_name(c['metric'])} {delta_text(c['delta'])} points"
            f"{sides_text(c)}"
            f"{'; ' + sure if sure else ''}: {verdict(c, bad)}."
            + per_class_text(comparisons, c)
            + (f" No control was trained, so the share of the {added} is unknown: grid.control=true trains copies with "
               "nothing pasted to separate them." if synthetic else "")
        )  # fmt: skip
    return lines


def pool_words(flames: bool, smoke: bool) -> str:
    """What a pool pastes, as the answer names it: ``flames``, ``flames and smoke``, ``smoke``, or ``images`` for a
    pool that lays neither."""
    return " and ".join(word for word, laid in (("flames", flames), ("smoke", smoke)) if laid) or "images"


def added_text(real: int, synth: int, added: str = "flames") -> str:
    """What a mixture adds to the baseline, ``real`` and ``synth`` images more (or fewer, negative), its pool
    pasting ``added``: ``200 synthetic images (flames and more images together) against none``, ``200 more real
    images``."""
    parts = [f"{synth} synthetic images ({added} and more images together) against none"] if synth > 0 else []
    parts += [f"{abs(synth)} fewer synthetic images"] if synth < 0 else []
    parts += [f"{real} more real images"] if real > 0 else [f"{-real} fewer real images"] if real < 0 else []
    return " and ".join(parts) or "the same images"


def seed_counts(rows: Sequence[Mapping[str, Any]]) -> dict[str, int]:
    """The number of seeds each mixture of ``rows`` was trained on, in the rows' order."""
    return {m: len({r["seed"] for r in rows if r["mixture"] == m}) for m in dict.fromkeys(r["mixture"] for r in rows)}


def how_sure_line(rows: Sequence[Mapping[str, Any]], comparisons: Sequence[Mapping[str, Any]], epochs: int) -> str:
    """Seeds per mixture (a mixture trained on fewer seeds is named with its count), what the intervals resample,
    and the training length."""
    counts = seed_counts(rows)
    seeds = max(counts.values(), default=0)
    fewer = [f"{m} {n}" for m, n in counts.items() if n < seeds]
    two = sorted({metric_name(c["metric"]) for c in comparisons if c["delta"].get("resampled") == "images and seeds"})
    one = sorted({metric_name(c["metric"]) for c in comparisons if c["delta"].get("resampled", "images") == "images"})
    if two:
        resampled = "test images and seeds (a two-level paired bootstrap)"
        resampled += f"; {', '.join(one)}: test images only" if one else ""
    elif one:
        resampled = ("test images only (paired bootstrap): with fewer than 3 seeds they say nothing of how another "
                     "training of the same mixture would land")  # fmt: skip
    else:
        resampled = "nothing (no comparison)"
    per = f" ({', '.join(fewer)} only)" if fewer else ""
    return (f"How sure: {seeds} seed{'s' * (seeds != 1)} per mixture{per}, {epochs} epoch{'s' * (epochs != 1)} each; "
            f"the 95 % intervals resample {resampled}.")  # fmt: skip


def longer(epochs: int) -> int:
    """The training length to suggest after ``epochs`` did not converge: half as long again, in tens (5 -> 10,
    40 -> 60, 100 -> 150)."""
    return max(10, -(-3 * epochs // 20) * 10)


def unlearned_line(rows: Sequence[Mapping[str, Any]], epochs: int) -> str | None:
    """The first caveat when runs did not learn in ``epochs``: which, why, and the key that fixes it."""
    flagged = {(r["mixture"], r["seed"]): r["learning"] for r in rows if r.get("learning")}
    if not flagged:
        return None
    runs = len({(r["mixture"], r["seed"]) for r in rows})
    (mixture, seed), why = next(iter(flagged.items()))
    return (f"Caveat first: {len(flagged)} of {runs} runs did not converge ({mixture} seed {seed} {why}); their "
            "figures are not results and no verdict is drawn from them: train longer (train.epochs, e.g. "
            f"SET=\"train.epochs={longer(epochs)}\").")  # fmt: skip


def silent_line(rows: Sequence[Mapping[str, Any]]) -> str | None:
    """Runs that detect nothing at confidence 0.25: their false alarms are not measured."""
    silent = sorted({(r["mixture"], r["seed"]) for r in rows if r.get("silent")})
    if not silent:
        return None
    named = ", ".join(f"{m} seed {s}" for m, s in silent[:4]) + (" and more" if len(silent) > 4 else "")
    runs = f"{len(silent)} runs detect" if len(silent) > 1 else "1 run detects"
    return (f"{runs} nothing at confidence 0.25 on any test set ({named}): {'their' if len(silent) > 1 else 'its'} "
            "false alarms are shown as not measured (–), not as 0.")  # fmt: skip

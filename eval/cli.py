"""``fuzzyfire score`` and ``compare``: COCO metrics of detector ONNX files on a test set (and the registration of
``predict``, :mod:`eval.cli_predict`). ``cmd_*`` return an exit code."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from curate.core.commands import add_command
from curate.core.formats.images import IMAGE_LABELLED, NEGATIVES_ONLY
from curate.core.formats.registry import FORMATS
from eval.cli_options import add_model_args, build_detector
from eval.errors import ALARM_CONF
from eval.imagelevel import IMAGE_RECALL, IMAGE_RECALL_AT_CONF
from eval.operating import ALARM_BUDGET, RECALL_AT_ALARMS


def _fmt(value: float | None) -> str:
    return "  -  " if value is None else f"{value:.3f}"


def _split_label(test, holdout: float = 0.0) -> str:  # test: eval.score.TestSet
    """How the scored split is named in the output: as the dataset names it, and the held-out share if any."""
    from eval.score import ALL_SPLITS

    if test.split != ALL_SPLITS:
        label = f"split {test.split}"
    else:
        label = "all splits" if any(test.splits) else "every image (no splits)"
    return f"{label}, held out at {holdout:g}" if holdout else label


def _print_text(result, intervals: dict, split: str) -> None:  # result: eval.score.ScoreResult
    m, spec = result.metrics, result.spec
    print(
        f"model  {spec.path} ({spec.format}, {spec.input_width}x{spec.input_height}, classes {list(spec.class_names)})"
    )
    if result.dataset.image_labelled:  # no boxes: no AP table, the image recall follows
        print(f"data   {split}: {m.images} images ({m.images - m.negatives} holding a class, {m.negatives} without), "
              f"labelled per image (no boxes), {m.detections} detections")  # fmt: skip
        return
    print(f"data   {split}: {m.images} images ({m.negatives} negatives), {m.boxes} boxes, {m.detections} detections")
    print("       " + "  ".join(f"{k} {_fmt(v)}" for k, v in m.summary.items()))
    for key, iv in intervals.items():
        print(f"       {key[:-3]} 95% CI [{iv['low']:.3f}, {iv['high']:.3f}] ({iv['samples']} image resamples)")
    print(f"       {'class':<12} {'boxes':>6} {'AP':>6} {'AP50':>6} {'AP25':>6}")
    for name, row in m.per_class.items():
        print(
            f"       {name:<12} {row['boxes']:>6} {_fmt(row['AP']):>6} {_fmt(row['AP50']):>6} {_fmt(row.get('AP25')):>6}"
        )
    skipped = m.extra["classes"]
    if skipped["not_in_model"]:
        print(f"       not scored (the model has no such class): {', '.join(skipped['not_in_model'])}")


def _score_model(model: Path, args: argparse.Namespace, dataset, problems):  # -> eval.score.ScoreResult
    from eval.score import score

    detector, options = build_detector(model, args)
    if not dataset.categories:  # a negatives-only set: the model's classes, none present (every detection false)
        from curate.core.classes import canonical_class

        dataset = dataset.with_categories(list(dict.fromkeys(canonical_class(n) for n in detector.spec.class_names)))
    return score(detector, dataset, options, problems)


def _load(args: argparse.Namespace):  # -> eval.score.TestSet
    """The test set of ``--data`` / ``--split``; says on stderr which split is scored when none was named."""
    from eval.score import ALL_SPLITS, load_test_set

    test = load_test_set(
        args.data, args.data_format, args.split, _aliases(args.alias), args.drop_class, args.holdout, args.label
    )
    for note in (p for p in test.problems if p.code == NEGATIVES_ONLY):
        print(f"{note.path}: {note.reason} (AP has no boxes to find: --errors counts its false alarms; if its "
              "images hold fire: --label fire, or fire/ and normal/ sub-folders)", file=sys.stderr)  # fmt: skip
    for note in (p for p in test.problems if p.code == IMAGE_LABELLED):
        print(f"{note.path}: {note.reason}", file=sys.stderr)
    if args.split is None and test.split != ALL_SPLITS:
        others = [s for s in test.splits if s != test.split]
        print(
            f"scoring split {test.split!r} of {args.data} ({len(test.dataset.images)} images; other splits: "
            f"{', '.join(others) or 'none'}; --split NAME or --split all to choose)",
            file=sys.stderr,
        )
    return test


def _report_problems(result) -> None:
    from curate.core.commands import print_problems

    shown = [p for p in result.problems if p.level != "info"]
    if shown:
        print_problems(shown, sys.stderr, limit=20)


def cmd_score(args: argparse.Namespace) -> int:
    from curate.core.cocoeval import ClassMatchError
    from curate.core.commands import print_problems
    from eval.onnx_model import ModelError
    from eval.score import ScoreError, error_pictures, score_errors, score_found, score_image_level, write_outputs

    try:
        test = _load(args)
        result = _score_model(args.model, args, test.dataset, test.problems)
    except (ModelError, ScoreError, ClassMatchError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    _report_problems(result)
    intervals = _intervals(result, args.ci, args.seed) if args.ci else {}
    held = {"holdout": args.holdout} if args.holdout else {}
    errors = score_errors(result, args.alarm_conf) if args.errors else None
    found = score_found(result, args.alarm_conf) if args.errors else None
    if args.out:
        files = write_outputs(result, args.out, {**intervals, **held})
        if errors is not None and found is not None:
            files["errors"] = errors.write(args.out, {"boxes_found": found.to_dict()})
            files["error_pictures"], not_drawn = error_pictures(result, args.out)
            if not_drawn:
                print_problems(not_drawn, sys.stderr, limit=20)
        print(f"wrote {', '.join(str(p) for p in files.values())}", file=sys.stderr)
    level = score_image_level(result, args.alarm_conf) if test.dataset.image_labelled else None
    if args.json:
        extra = {"errors": errors.to_dict(), "boxes_found": found.to_dict()} if errors and found else {}
        extra |= {"image_level": level.to_dict()} if level else {}
        print(json.dumps({**result.metrics.to_dict(), **held, **intervals, **extra}, indent=1))
    else:
        _print_text(result, intervals, _split_label(test, args.holdout))
        if level is not None:
            _print_image_level(level)
        if errors is not None and found is not None:
            _print_errors(errors)
            _print_found(found)
    return 0


def _print_image_level(level) -> None:  # level: eval.imagelevel.ImageLevel
    """An image-labelled set's result: image recall at the confidence, and at the alarm budget of its own images
    without fire when it has any."""
    found = round(level.recall_at_conf * level.fire_images)
    print(f"image  {found} of {level.fire_images} images holding fire detected at confidence >= {level.conf:g}: "
          f"image recall {level.recall_at_conf:.3f} (no boxes: AP is -)")  # fmt: skip
    if level.free_images:
        print(f"       {round(level.alarm_share_at_conf * level.free_images)} of its {level.free_images} images without "
              f"fire raise an alarm at {level.conf:g}; at most {level.budget:g} false-alarm images per 100 of them "
              f"(threshold {level.budget_threshold:.3f}): image recall {level.budget_recall:.3f}")  # fmt: skip


def _print_errors(errors) -> None:  # errors: eval.errors.ErrorBreakdown
    if errors.ap50 is None:
        print("errors (TIDE): no box to find on these images (AP50 undefined); false alarms only")
    else:
        print("errors (TIDE): AP50 gained when each kind is fixed alone, in points")
        for kind, delta in errors.delta_ap50.items():
            print(f"       {kind:<15} {100 * delta:>5.1f}  ({errors.counts[kind]})")
    if errors.false_alarms_per_100 is not None:
        print(
            f"alarms {errors.false_alarms_per_100:.1f} detections >= {errors.alarm_conf:g} per 100 images without "
            f"fire ({100 * errors.alarm_image_share:.0f}% of the {errors.negatives} such images raise one)"
        )


def _print_found(found) -> None:  # found: eval.found.BoxesFound
    if not found.boxes:
        return
    o = found.outcomes
    poor = o["merged"] + o["split"] + o["too_large"] + o["too_small"]
    print(
        f"boxes  at confidence >= {found.conf:g}: {o['found']} of {found.boxes} found at IoU >= 0.5 "
        f"({100 * o['found'] / found.boxes:.0f}%), {poor} boxed poorly (merged with neighbours {o['merged']}, split "
        f"{o['split']}, too large {o['too_large']}, too small {o['too_small']}), {o['missed']} missed"
    )
    for label, table in (("by size (px)", found.by_size), ("by boxes in image", found.by_crowding)):
        cells = "  ".join(f"{k} {100 * f / n:.0f}% of {n}" for k, (f, n) in table.items() if n)
        print(f"       found {label:<17} {cells}")


def _models(text: str) -> list[Path]:
    """``A.onnx`` or ``A0.onnx,A1.onnx,...`` (one side of ``compare``: several runs, e.g. one per seed)."""
    paths = [Path(part.strip()) for part in text.split(",") if part.strip()]
    if not paths:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a model .onnx or a comma-separated list of them")
    return paths


def _side(models: list[Path], results: list) -> dict:  # results: list[eval.score.ScoreResult]
    """One side of the compare document: its models' AP and AP50 averaged (the bootstrap's point), and each run."""
    runs = [{"model": str(m), **{k: r.metrics.summary[k] for k in ("AP", "AP50")}} for m, r in zip(models, results)]
    mean = {k: None if any(run[k] is None for run in runs) else sum(run[k] for run in runs) / len(runs)
            for k in ("AP", "AP50")}  # fmt: skip
    return {"model": ",".join(str(m) for m in models), **mean, "runs": runs}


def same_content(model_a: list[Path], model_b: list[Path]) -> list[dict]:
    """The models that are one file's content more than once among both sides: per sha256 of the file contents
    (in first-listed order), ``{"sha256", "A": [paths], "B": [paths]}``; only those listed twice or more."""
    from curate.core.manifest import file_sha256

    groups: dict[str, dict] = {}
    for side, models in (("A", model_a), ("B", model_b)):
        for model in models:
            digest = file_sha256(model) if model.is_file() else f"missing:{model}"  # scoring names a missing file
            groups.setdefault(digest, {"sha256": digest, "A": [], "B": []})[side].append(str(model))
    return [g for g in groups.values() if len(g["A"]) + len(g["B"]) > 1 and not g["sha256"].startswith("missing:")]


def same_content_lines(groups: list[dict], runs_a: int, runs_b: int) -> list[str]:
    """What :func:`same_content` found, in words: a model both sides list (when the sides hold the same models
    as often, the difference is 0 by construction), or one a side lists twice."""
    zero = all(len(g["A"]) == len(g["B"]) for g in groups) and sum(len(g["A"]) for g in groups) == runs_a == runs_b
    lines = []
    for g in groups:
        digest = f"same content, sha256 {g['sha256'][:12]}…"
        if g["A"] and g["B"]:
            a, b = ", ".join(g["A"]), ", ".join(g["B"])
            lines.append(f"{a} and {b} are one model ({digest})" if zero and len(groups) == 1 else
                         f"{a} (A) and {b} (B) are one model ({digest})")  # fmt: skip
        else:
            side = "A" if g["A"] else "B"
            lines.append(f"{side} lists one model {len(g[side])} times ({', '.join(g[side])}; {digest}): its mean "
                         f"counts it {len(g[side])} times")  # fmt: skip
    if zero and len(groups) == 1:
        lines[0] += ": the difference is 0 by construction"
    elif zero and groups:
        lines.append(f"A and B are the same {runs_a} models: the difference is 0 by construction")
    return lines


def cmd_compare(args: argparse.Namespace) -> int:
    import numpy as np

    from curate.core.cocoeval import ClassMatchError
    from eval.imagelevel import paired_image_recall
    from eval.onnx_model import ModelError
    from eval.score import ScoreError, score_operating
    from eval.stats import MatchTable, paired_bootstrap

    sides = (args.model_a, args.model_b)
    if args.alarm_budget <= 0 or args.samples < 1:
        raise ValueError(f"--alarm-budget must be > 0 and --samples >= 1, got {args.alarm_budget}, {args.samples}")
    if (args.attributes is not None or args.forest is not None) and not args.slices:
        raise ValueError("--attributes and --forest go with --slices")
    if args.attributes is not None and not args.attributes.is_file():
        raise FileNotFoundError(f"--attributes: {args.attributes}: no such file")
    try:
        test = _load(args)
        results = [[_score_model(m, args, test.dataset, test.problems) for m in side] for side in sides]
    except (ModelError, ScoreError, ClassMatchError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    _report_problems(results[0][0])
    same = same_content(args.model_a, args.model_b)
    tables = [[MatchTable(r.evaluation) for r in side] for side in results]
    if any(not np.array_equal(tables[0][0].image_ids, t.image_ids) for t in tables[0] + tables[1]):
        print("error: the models could not all be scored on the same images", file=sys.stderr)
        return 2
    labelled = test.dataset.image_labelled  # no boxes: image recall only
    deltas = {} if labelled else paired_bootstrap(tables[0], tables[1], np.random.default_rng(args.seed), args.samples)
    doc = {
        "A": _side(args.model_a, results[0]),
        "B": _side(args.model_b, results[1]),
        "images": results[0][0].metrics.images,
        "delta": {k: d.to_dict() for k, d in deltas.items()},
        "samples": args.samples,
        "seed": args.seed,
        "same_content": same,
    }
    free = points = None
    if args.negatives is not None:
        try:
            free = _negatives_scored(args)
        except (ModelError, ScoreError, ClassMatchError, ValueError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        points = [[score_operating(r, n) for r, n in zip(side, neg)] for side, neg in zip(results, free)]
        if (delta := _add_operating(doc, points, args, boxes=not labelled)) is not None:
            deltas[RECALL_AT_ALARMS] = delta
    own = labelled and free is None and test.dataset.num_negatives() > 0  # its own images without fire
    if own:
        doc["own_negatives"] = test.dataset.num_negatives()
    levels = _image_levels(results, points, own)
    deltas[IMAGE_RECALL] = paired_image_recall(levels[0], levels[1], np.random.default_rng(args.seed), args.samples,
                                               args.alarm_budget)  # fmt: skip
    doc["delta"][IMAGE_RECALL] = deltas[IMAGE_RECALL].to_dict()
    for key, side_levels in zip(("A", "B"), levels):  # each run's image recall at ALARM_CONF, and each side's mean
        for run, (hits, _) in zip(doc[key]["runs"], side_levels):
            run[IMAGE_RECALL_AT_CONF] = hits.recall(ALARM_CONF)
        doc[key][IMAGE_RECALL_AT_CONF] = float(np.mean([run[IMAGE_RECALL_AT_CONF] for run in doc[key]["runs"]]))
    if args.slices:
        doc["slices"] = _compare_slices(args, results, levels)
    if args.json:
        print(json.dumps(doc, indent=1))
        return 0
    _print_compare(doc, deltas, args, labelled, free is not None or own)
    return 0


def _print_compare(doc: dict, deltas: dict, args: argparse.Namespace, labelled: bool, at_budget: bool) -> None:
    """``compare``'s text: each side's runs and mean, what the alarms were counted on, and each difference
    (``labelled``: an image-labelled test set, its image recall at the confidence per side; ``at_budget``: image
    recall read at the alarm budget rather than at the confidence)."""
    for line in same_content_lines(doc["same_content"], len(args.model_a), len(args.model_b)):
        print(line)
    for side in ("A", "B"):
        runs = doc[side]["runs"]
        for run in runs if len(runs) > 1 else []:
            print(f"{side}      {run['model']}  AP {_fmt(run['AP'])}  AP50 {_fmt(run['AP50'])}{_at_budget(run)}"
                  f"{_image_recall(run, labelled)}")  # fmt: skip
        name = doc[side]["model"] if len(runs) == 1 else f"mean of {len(runs)} runs"
        print(
            f"{side}      {name}  AP {_fmt(doc[side]['AP'])}  AP50 {_fmt(doc[side]['AP50'])}{_at_budget(runs[0] if len(runs) == 1 else doc[side])}"
            f"{_image_recall(doc[side], labelled)}"
        )
    if "negatives" in doc:
        neg = doc["negatives"]
        held = f", held out at {neg['holdout']:g}" if "holdout" in neg else ""
        print(f"alarms {neg['images']} images without fire ({neg['data']}{held}): each model read at the threshold where it "
              f"raises at most {neg['budget']:g} alarms per 100 of them")  # fmt: skip
    if "own_negatives" in doc:
        print(f"alarms the test set's {doc['own_negatives']} images without fire: each model read at the "
              f"threshold where at most {args.alarm_budget:g} of 100 of them raise an alarm")  # fmt: skip
    for key, d in deltas.items():
        iv, images = d.interval, f"{doc['images']} images"
        name = {RECALL_AT_ALARMS: f"recall at {args.alarm_budget:g} alarms/100",
                IMAGE_RECALL: f"image recall at {args.alarm_budget:g} false-alarm images/100" if at_budget else
                f"image recall at confidence {ALARM_CONF:g}"}.get(key, key)  # fmt: skip
        images += (
            f" and {doc['negatives']['images']} without fire"
            if key != "AP" and key != "AP50" and "negatives" in doc
            else ""
        )
        print(
            f"B - A  {name} {100 * iv.point:+.1f} points, 95% CI [{100 * iv.low:+.1f}, {100 * iv.high:+.1f}], "
            f"p = {d.p_value:.3f} ({args.samples} paired resamples of {images})"
        )


def _negatives_scored(args: argparse.Namespace) -> list[list]:  # per side, per model: eval.score.ScoreResult
    """Every model of both sides scored on ``--negatives`` (raises ValueError when that set has boxes)."""
    from eval.score import ALL_SPLITS, load_test_set

    negatives = load_test_set(args.negatives, "auto", ALL_SPLITS, holdout=args.negatives_holdout)
    if negatives.dataset.annotations or negatives.dataset.image_labelled:
        held = len(negatives.dataset.images) - negatives.dataset.num_negatives()
        raise ValueError(f"{args.negatives}: --negatives takes images without fire; {held} of its images hold a "
                         f"class ({len(negatives.dataset.annotations)} boxes)")  # fmt: skip
    return [[_score_model(m, args, negatives.dataset, negatives.problems) for m in models]
            for models in (args.model_a, args.model_b)]  # fmt: skip


def _image_levels(results: list[list], points: list[list] | None, own: bool = False) -> list[list]:
    """Per side, per model: (its :class:`eval.imagelevel.ImageHits` on the test set, its per-image alarms on
    ``--negatives`` (from its operating data ``points``), with ``own`` on the test set's own images without fire,
    or, without either, the confidence :data:`eval.errors.ALARM_CONF` it is read at)."""
    from eval.imagelevel import free_alarms, image_alarms, image_hits
    from eval.score import scored_images

    out = []
    for k, side in enumerate(results):
        levels = []
        for j, r in enumerate(side):
            ds, cat_ids = scored_images(r)
            hits = image_hits(ds, r.records, cat_ids)
            read_at: Any = ALARM_CONF if points is None else image_alarms(points[k][j][1])
            levels.append((hits, free_alarms(hits, r.records, cat_ids) if own else read_at))
        out.append(levels)
    return out


def _compare_slices(args: argparse.Namespace, results: list[list], levels: list[list]) -> list[dict]:
    """``--slices``: the comparison slice by slice (:func:`eval.slices.compare_slices`) on the test set's
    computed attributes (and ``--attributes``), printed as a table unless ``--json``; ``--forest`` draws them."""
    import numpy as np

    from curate.core.cocoeval import LOOSE_IOU, run_cocoeval
    from eval.attributes import dataset_attributes, merged, read_attributes_csv
    from eval.score import scored_images
    from eval.slices import Side, compare_slices, make_slices
    from eval.stats import MatchTable

    ds, cat_ids = scored_images(results[0][0])
    attrs = dataset_attributes(ds, args.workers)
    if args.attributes is not None:
        attrs = merged(attrs, read_attributes_csv(args.attributes, ds))
    hits = levels[0][0][0]
    slices = make_slices(attrs, hits.image_ids, hits.fire)
    sides = [Side([MatchTable(r.evaluation) for r in side],
                  [MatchTable(run_cocoeval(ds, r.records, cat_ids, [LOOSE_IOU])) for r in side], level)
             for side, level in zip(results, levels)]  # fmt: skip
    rows = compare_slices(sides[0], sides[1], slices, np.random.default_rng(args.seed), args.samples)
    if args.forest is not None:
        from eval.plots import plot_forest

        panels: dict[str, list[dict]] = {}
        for r in rows:
            panels.setdefault(r["metric"], []).append(r)
        plot_forest(panels, args.forest, "B − A by slice (fire images)")
    if not args.json:
        few = [f"{s.name} ({s.fire_images})" for s in slices if s.too_few]
        print("slice                          fire  Δ AP50               Δ AP25               Δ image recall")
        by: dict[str, dict[str, dict]] = {}
        for r in rows:
            by.setdefault(r["slice"], {})[r["metric"]] = r
        for name, metrics in by.items():
            cells = [_slice_cell(metrics.get(m)) for m in ("AP50", "AP25", "image_recall")]
            print(f"{name:<30} {next(iter(metrics.values()))['fire_images']:>4}  {'  '.join(cells)}")
        print("*: the difference holds after Holm's correction over the slices of its metric (5 % family-wise)"
              + (f"; too few fire images to compare: {', '.join(few)}" if few else ""))  # fmt: skip
    return rows


def _slice_cell(r: dict | None) -> str:
    if r is None:
        return f"{'–':<19}"
    d = r["delta"]
    text = f"{100 * d['value']:+.1f} [{100 * d['low']:+.1f},{100 * d['high']:+.1f}]{'*' if r['verdict'] != '-' else ''}"
    return f"{text:<19}"


def _image_recall(side: dict, labelled: bool) -> str:
    """``"  image recall 0.500 at 0.25"`` of a compare side's run (or mean) on an image-labelled set; else empty."""
    return f"  image recall {side[IMAGE_RECALL_AT_CONF]:.3f} at {ALARM_CONF:g}" if labelled else ""


def _at_budget(side: dict) -> str:
    """``"  recall 0.306 at threshold 0.442"`` of a compare side's run read at the alarm budget (a side of several
    runs: their mean recall); empty without ``--negatives``."""
    if RECALL_AT_ALARMS not in side:
        return ""
    return f"  recall {side[RECALL_AT_ALARMS]:.3f}" + (
        f" at threshold {side['threshold']:.3f}" if "threshold" in side else ""
    )


def _add_operating(doc: dict, points: list[list], args: argparse.Namespace, boxes: bool = True):  # -> PairedDelta
    """Read every run at ``--alarm-budget`` into ``doc`` (each run's recall and threshold, each side's mean recall,
    ``negatives``: the set and its size) and return the paired bootstrap of the recall difference B - A; a test
    set without boxes (``boxes`` False: image-labelled) has no box recall: only ``negatives``, and None."""
    import numpy as np

    from eval.operating import operating_point, paired_recall_bootstrap

    images = points[0][0][1].images
    doc["negatives"] = {"data": str(args.negatives), "images": images, "budget": args.alarm_budget}
    if args.negatives_holdout:
        doc["negatives"]["holdout"] = args.negatives_holdout
    if not boxes:
        return None
    for key, side in zip(("A", "B"), points):
        for run, (found, alarms) in zip(doc[key]["runs"], side):
            point = operating_point(found, alarms, args.alarm_budget)
            run.update({RECALL_AT_ALARMS: point.recall, "threshold": point.threshold})
        doc[key][RECALL_AT_ALARMS] = float(np.mean([run[RECALL_AT_ALARMS] for run in doc[key]["runs"]]))
    delta = paired_recall_bootstrap(
        points[0], points[1], np.random.default_rng(args.seed), args.samples, args.alarm_budget
    )
    doc["delta"][RECALL_AT_ALARMS] = delta.to_dict()
    return delta


def _intervals(result, samples: int, seed: int) -> dict[str, dict[str, float]]:
    """``{"AP_ci": {...}, "AP50_ci": {...}}``: 95% image-level bootstrap intervals."""
    import numpy as np

    from eval.stats import MatchTable, bootstrap_ap

    found = bootstrap_ap(MatchTable(result.evaluation), np.random.default_rng(seed), samples)
    return {f"{key}_ci": {**iv.to_dict(), "samples": samples, "seed": seed} for key, iv in found.items()}


def _aliases(items: list[str]) -> dict[str, str]:
    out = {}
    for item in items:
        name, sep, target = item.partition("=")
        if not sep or not name.strip() or not target.strip():
            raise SystemExit(f"--alias {item!r}: expected NAME=CLASS, e.g. Flame=fire")
        out[name.strip()] = target.strip()
    return out


def _add_scoring_args(p: argparse.ArgumentParser) -> None:
    """Test-set and model options shared by ``score`` and ``compare``."""
    p.add_argument(
        "--data", required=True, help="test set: folder, COCO .json or data.yaml, in any format fuzzyfire reads"
    )
    p.add_argument(
        "--split",
        help="split to score (val and valid are one name); default: test, else val/valid, else the whole set "
        "when it has no splits; 'all' = every image",
    )
    p.add_argument(
        "--from",
        dest="data_format",
        default="auto",
        choices=("auto", *FORMATS),
        help="test-set format (default: detect)",
    )
    p.add_argument(
        "--alias", action="append", default=[], metavar="NAME=CLASS", help="map a test-set class, e.g. Flame=fire"
    )
    p.add_argument(
        "--drop-class", action="append", default=[], metavar="NAME", help="ignore a test-set class (repeatable or a,b)"
    )
    p.add_argument(
        "--label",
        metavar="CLASS",
        help="every image of --data (a folder of images without label files) holds CLASS, e.g. fire: an "
        "image-labelled set, judged by image recall (no AP); a classification layout (fire/ and normal/ "
        "sub-folders) is read so without it (default: such a folder is negatives only)",
    )
    p.add_argument(
        "--holdout",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="score only the images held out by content at this share (0..1), the photos a Method 2 pool with "
        "background_holdout SHARE never composites on (default 0: every image)",
    )
    add_model_args(p)
    p.add_argument("--seed", type=int, default=0, help="bootstrap seed (default 0)")


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``score``, ``compare`` and ``predict`` (:mod:`eval.cli_predict`) to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "score",
        help="COCO AP of a detector ONNX (ours, YOLOv5, YOLOv8/11 exports) on a test set",
        description="Run a detector ONNX with onnxruntime on every image of a test set (letterbox, NMS, boxes in\n"
        "original pixels) and report COCO AP, AP50, AP75, small/medium/large and per class (pycocotools;\n"
        "negative images count). Classes are matched by name between the model's metadata and the test set.\n\n"
        "example:\n  fuzzyfire score runs/R500_S500/seed0/best.onnx --data ../shared/data/fire-smoke-608 --split test\n"
        "  fuzzyfire score yolov8n.onnx --data out/test --format yolov8 --names fire --json --out out/score\n"
        "  fuzzyfire score best.onnx --data ds/data.yaml --split val --resize linear --errors\n"
        "  fuzzyfire score best.onnx --data ds --errors --out out/score   # + out/score/errors/*.png\n"
        "  fuzzyfire score best.onnx --data ../shared/data/fire-free --holdout 0.25 --errors   # false alarms on\n"
        "      the fire-free photos that pools with background_holdout 0.25 never composited on",
    )
    p.add_argument("model", type=Path, help="detector .onnx file")
    _add_scoring_args(p)
    p.add_argument(
        "--ci", type=int, default=0, metavar="N", help="95%% bootstrap interval of AP from N image resamples"
    )
    p.add_argument(
        "--errors",
        action="store_true",
        help="TIDE-style breakdown: AP50 lost to classification, localisation, both, duplicate, background and "
        "missed errors, false alarms on images without fire, and which boxes are found at --alarm-conf (merged "
        "with neighbours, split, too large or small, missed; by size and by boxes per image: eval/found.py); "
        "with --out, pictures of the worst false alarms and misses in OUT/errors/",
    )
    p.add_argument(
        "--alarm-conf",
        type=float,
        default=0.25,
        help="confidence of a false alarm and of a found box for --errors (default 0.25)",
    )
    p.add_argument("--json", action="store_true", help='print {"AP", "AP50", "images", "boxes", "per_class", ...}')
    p.add_argument(
        "--out",
        type=Path,
        help="also write predictions.json, metrics.json, pr_curve.png, matches.npz (with --errors: errors.json "
        "and errors/, pictures of the worst false alarms and misses)",
    )
    p.set_defaults(func=cmd_score)

    p = add_command(
        sub,
        "compare",
        help="AP difference of two detectors on the same test images, with a paired bootstrap interval",
        description="Score two detector ONNX files on the same test set and report AP(B) - AP(A) with a 95%\n"
        "interval and p-value from a paired image-level bootstrap (both models scored on each resample).\n"
        "Each side may be several runs, comma-separated (e.g. one per seed): their AP is averaged on each\n"
        "resample, as the experiment's comparisons average seeds.\n\n"
        "example:\n  fuzzyfire compare runs/R1000_S0/seed0/best.onnx runs/R750_S250/seed0/best.onnx \\\n"
        "      --data ../shared/data/fire-smoke-608 --split test --drop-class default\n"
        "  fuzzyfire compare a/seed0/best.onnx,a/seed1/best.onnx b/seed0/best.onnx,b/seed1/best.onnx \\\n"
        "      --data out/study/data/curated-6407ecb64193 --split test\n"
        "  fuzzyfire compare a.onnx b.onnx --data out/study/data/curated-6407ecb64193 --split test \\\n"
        "      --negatives ../shared/data/fire-free   # + recall at 10 false alarms per 100 fire-free photos\n"
        "  fuzzyfire compare a.onnx b.onnx --data out/study/data/curated-6407ecb64193 --split test \\\n"
        "      --negatives ../shared/data/fire-free --negatives-holdout 0.25   # the photos no pool composited on",
    )
    p.add_argument("model_a", type=_models, help="baseline detector .onnx (A), or several: A0.onnx,A1.onnx,...")
    p.add_argument("model_b", type=_models, help="detector compared with it (B), or several: B0.onnx,B1.onnx,...")
    _add_scoring_args(p)
    p.add_argument("--samples", type=int, default=1000, help="bootstrap resamples (default 1000)")
    p.add_argument(
        "--negatives",
        type=Path,
        metavar="DATA",
        help="images without fire (a folder of photos, or any set without boxes; every image): each model is "
        "also scored there and read at the threshold where it raises at most --alarm-budget alarms per 100 of "
        "them; adds the recall of the test set's boxes there and its paired difference (both sets resampled)",
    )
    p.add_argument(
        "--alarm-budget",
        type=float,
        default=ALARM_BUDGET,
        metavar="N",
        help=f"false alarms per 100 images without fire for --negatives (default {ALARM_BUDGET:g})",
    )
    p.add_argument(
        "--negatives-holdout",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="--negatives: only the photos held out by content at this share, those a pool with "
        "background_holdout SHARE never composited on (default 0: every image)",
    )
    p.add_argument(
        "--slices",
        action="store_true",
        help="also compare slice by slice: the test images cut by what they show (fire size, count, night/day, "
        "fire colour, sky, blur, source; docs/scoring.md), AP50, AP25 and image recall per slice with paired "
        "intervals, Holm-corrected",
    )
    p.add_argument(
        "--attributes",
        type=Path,
        metavar="CSV",
        help="--slices: your own attributes of the test images, a CSV with the header image,attribute,value",
    )
    p.add_argument(
        "--forest", type=Path, metavar="PNG", help="--slices: draw the per-slice differences (a forest plot)"
    )
    p.add_argument(
        "--json",
        action="store_true",
        help='print {"A": {"model", "AP", "AP50", "runs"}, "B", "images", "delta": {"AP": ...}, ...}',
    )
    p.set_defaults(func=cmd_compare)

    from eval import cli_predict

    cli_predict.register(sub)

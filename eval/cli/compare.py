"""``fuzzyfire compare``: two detectors (or two sides of several runs each) scored on the same test images, and
the paired bootstrap of their difference: AP (and each class's AP50 on a set of several classes), recall at a
false-alarm budget, image recall, slice by slice.
``cmd_compare`` returns an exit code."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from eval.cli.options import SCORING_ALIASES, fmt, load_test_set, report_problems, score_model
from eval.errors import ALARM_CONF
from eval.imagelevel import IMAGE_RECALL, IMAGE_RECALL_AT_CONF
from eval.operating import RECALL_AT_ALARMS
from ground.cli.commands import add_command
from ground.cli.options import Alias, add_settings, command_config

if TYPE_CHECKING:
    from eval.config import CompareConfig

#: Flags of ``fuzzyfire compare``: aliases of :class:`eval.config.CompareConfig` keys (their defaults are the keys').
ALIASES: tuple[Alias, ...] = (
    *SCORING_ALIASES,
    Alias("--samples", ("samples",), "bootstrap resamples", {"type": int}),
    Alias("--alarm-budget", ("alarm_budget",), "false alarms per 100 images without fire at which each model is "
          "read (--negatives, or the test set's own images without fire)", {"type": float, "metavar": "N"}),
    Alias("--negatives-holdout", ("negatives_holdout",), "--negatives: only the photos held out by content at this "
          "share, those a pool with background_holdout SHARE never composited on (0: every image)",
          {"type": float, "metavar": "SHARE"}),
    Alias("--paired-seeds", ("paired_seeds",), "run i of each side was trained with seed i: the intervals resample "
          "the seeds too, as the study's do (at least 3 runs on each side)", {"action": "store_true"}),
)  # fmt: skip


def _compare_config() -> type:
    from eval.config import CompareConfig

    return CompareConfig


def _models(text: str) -> list[Path]:
    """``A.onnx`` or ``A0.onnx,A1.onnx,...`` (one side of ``compare``: several runs, e.g. one per seed)."""
    paths = [Path(part.strip()) for part in text.split(",") if part.strip()]
    if not paths:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a model .onnx or a comma-separated list of them")
    return paths


def _side(models: list[Path], results: list, classes: list[str]) -> dict:  # results: list[eval.score.ScoreResult]
    """One side of the compare document: its models' AP and AP50 averaged (the bootstrap's point), and each run;
    with several ``classes`` also each class's AP50 (``"AP50 smoke"``, :func:`eval.tables.class_metric`)."""
    from eval.tables import class_metric

    keys = ("AP", "AP50", *(class_metric("AP50", c) for c in classes))
    runs = [{"model": str(m), "AP": r.metrics.summary["AP"], "AP50": r.metrics.summary["AP50"],
             **{class_metric("AP50", c): r.metrics.per_class[c]["AP50"] for c in classes}}
            for m, r in zip(models, results)]  # fmt: skip
    mean = {k: None if any(run[k] is None for run in runs) else sum(run[k] for run in runs) / len(runs)
            for k in keys}  # fmt: skip
    return {"model": ",".join(str(m) for m in models), **mean, "runs": runs}


def same_content(model_a: list[Path], model_b: list[Path]) -> list[dict]:
    """The models that are one file's content more than once among both sides: per sha256 of the file contents
    (in first-listed order), ``{"sha256", "A": [paths], "B": [paths]}``; only those listed twice or more."""
    from ground.data.manifest import file_sha256

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

    from eval.imagelevel import paired_image_recall
    from eval.onnx_model import ModelError
    from eval.score import ScoreError, score_operating
    from eval.stats import MIN_SEEDS_RESAMPLED, MatchTable, paired_bootstrap
    from eval.tables import class_metric
    from ground.detect.cocoeval import ClassMatchError

    cfg = command_config(args, _compare_config(), ALIASES, {"--data": args.data})
    if cfg is None:
        return 0
    sides = (args.model_a, args.model_b)
    if (args.attributes is not None or args.forest is not None) and not args.slices:
        raise ValueError("--attributes and --forest go with --slices")
    if args.attributes is not None and not args.attributes.is_file():
        raise FileNotFoundError(f"--attributes: {args.attributes}: no such file")
    runs = (len(args.model_a), len(args.model_b))
    if cfg.paired_seeds and (runs[0] != runs[1] or runs[0] < MIN_SEEDS_RESAMPLED):
        raise ValueError(f"--paired-seeds needs as many runs on each side, at least {MIN_SEEDS_RESAMPLED} "
                         f"(run i of each trained with seed i); got {runs[0]} and {runs[1]}")  # fmt: skip
    seeds = cfg.paired_seeds
    try:
        test = load_test_set(args.data, cfg.data)
        results = [[score_model(m, cfg, test.dataset, test.problems) for m in side] for side in sides]
    except (ModelError, ScoreError, ClassMatchError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    report_problems(results[0][0])
    same = same_content(args.model_a, args.model_b)
    tables = [[MatchTable(r.evaluation) for r in side] for side in results]
    if any(not np.array_equal(tables[0][0].image_ids, t.image_ids) for t in tables[0] + tables[1]):
        print("error: the models could not all be scored on the same images", file=sys.stderr)
        return 2
    labelled = test.dataset.image_labelled  # no boxes: image recall only
    deltas = {} if labelled else paired_bootstrap(*tables, np.random.default_rng(cfg.seed), cfg.samples, seeds=seeds)
    per_class = results[0][0].metrics.per_class  # the scored classes, in the order of the match tables
    classes = list(per_class) if not labelled and len(per_class) > 1 else []
    for k, name in enumerate(classes):  # each class alone, on the same resampled images as AP's
        if not per_class[name]["boxes"]:
            continue  # a class the test set never boxes has no AP (its AP50 reads '-')
        one = [[t.of_class(k) for t in side] for side in tables]
        alone = paired_bootstrap(*one, np.random.default_rng(cfg.seed), cfg.samples, seeds=seeds)
        deltas[class_metric("AP50", name)] = alone["AP50"]
    doc = {
        "A": _side(args.model_a, results[0], classes),
        "B": _side(args.model_b, results[1], classes),
        "images": results[0][0].metrics.images,
        "classes": classes,
        "delta": {k: d.to_dict() for k, d in deltas.items()},
        "samples": cfg.samples,
        "seed": cfg.seed,
        "same_content": same,
    }
    free = points = None
    if args.negatives is not None:
        try:
            free = _negatives_scored(args, cfg)
        except (ModelError, ScoreError, ClassMatchError, ValueError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        points = [[score_operating(r, n) for r, n in zip(side, neg)] for side, neg in zip(results, free)]
        if (delta := _add_operating(doc, points, args.negatives, cfg, boxes=not labelled)) is not None:
            deltas[RECALL_AT_ALARMS] = delta
    own = labelled and free is None and test.dataset.num_negatives() > 0  # its own images without fire
    if own:
        doc["own_negatives"] = test.dataset.num_negatives()
    levels = _image_levels(results, points, own)
    deltas[IMAGE_RECALL] = paired_image_recall(levels[0], levels[1], np.random.default_rng(cfg.seed), cfg.samples,
                                               cfg.alarm_budget, seeds=seeds)  # fmt: skip
    doc["delta"][IMAGE_RECALL] = deltas[IMAGE_RECALL].to_dict()
    for key, side_levels in zip(("A", "B"), levels):  # each run's image recall at ALARM_CONF, and each side's mean
        for run, (hits, _) in zip(doc[key]["runs"], side_levels):
            run[IMAGE_RECALL_AT_CONF] = hits.recall(ALARM_CONF)
        doc[key][IMAGE_RECALL_AT_CONF] = float(np.mean([run[IMAGE_RECALL_AT_CONF] for run in doc[key]["runs"]]))
    if args.slices:
        doc["slices"] = _compare_slices(args, cfg, results, levels)
    if args.json:
        print(json.dumps(doc, indent=1))
        return 0
    _print_compare(doc, deltas, cfg, labelled, free is not None or own)
    return 0


def _print_compare(doc: dict, deltas: dict, cfg: CompareConfig, labelled: bool, at_budget: bool) -> None:
    """``compare``'s text: each side's runs and mean, what the alarms were counted on, and each difference
    (``labelled``: an image-labelled test set, its image recall at the confidence per side; ``at_budget``: image
    recall read at the alarm budget rather than at the confidence)."""
    for line in same_content_lines(doc["same_content"], len(doc["A"]["runs"]), len(doc["B"]["runs"])):
        print(line)
    for side in ("A", "B"):
        runs = doc[side]["runs"]
        for run in runs if len(runs) > 1 else []:
            print(f"{side}      {run['model']}  AP {fmt(run['AP'])}  AP50 {fmt(run['AP50'])}"
                  f"{_class_ap50(run, doc['classes'])}{_at_budget(run)}{_image_recall(run, labelled)}")  # fmt: skip
        name = doc[side]["model"] if len(runs) == 1 else f"mean of {len(runs)} runs"
        print(
            f"{side}      {name}  AP {fmt(doc[side]['AP'])}  AP50 {fmt(doc[side]['AP50'])}"
            f"{_class_ap50(doc[side], doc['classes'])}{_at_budget(runs[0] if len(runs) == 1 else doc[side])}"
            f"{_image_recall(doc[side], labelled)}"
        )
    if "negatives" in doc:
        neg = doc["negatives"]
        held = f", held out at {neg['holdout']:g}" if "holdout" in neg else ""
        print(f"alarms {neg['images']} images without fire ({neg['data']}{held}): each model read at the threshold where it "
              f"raises at most {neg['budget']:g} alarms per 100 of them")  # fmt: skip
    if "own_negatives" in doc:
        print(f"alarms the test set's {doc['own_negatives']} images without fire: each model read at the "
              f"threshold where at most {cfg.alarm_budget:g} of 100 of them raise an alarm")  # fmt: skip
    for key, d in deltas.items():
        iv, images = d.interval, f"{doc['images']} images"
        name = {RECALL_AT_ALARMS: f"recall at {cfg.alarm_budget:g} alarms/100",
                IMAGE_RECALL: f"image recall at {cfg.alarm_budget:g} false-alarm images/100" if at_budget else
                f"image recall at confidence {ALARM_CONF:g}"}.get(key, key)  # fmt: skip
        images += (
            f" and {doc['negatives']['images']} without fire"
            if key != "AP" and key != "AP50" and "negatives" in doc
            else ""
        )
        if d.resampled != "images":
            images += f" and {len(doc['A']['runs'])} seeds"
        print(
            f"B - A  {name} {100 * iv.point:+.1f} points, 95% CI [{100 * iv.low:+.1f}, {100 * iv.high:+.1f}], "
            f"p = {d.p_value:.3f} ({cfg.samples} paired resamples of {images})"
        )


def _negatives_scored(args: argparse.Namespace, cfg: CompareConfig) -> list[list]:
    """Every model of both sides scored on ``--negatives`` (every image; held out at ``cfg.negatives_holdout``),
    as ``cfg`` scores: per side, per model, its :class:`eval.score.ScoreResult`; raises ValueError when that
    set has boxes."""
    from eval.config import TestSetConfig
    from eval.score import ALL_SPLITS
    from eval.score import load_test_set as load

    negatives = load(args.negatives, TestSetConfig(split=ALL_SPLITS, holdout=cfg.negatives_holdout))
    if negatives.dataset.annotations or negatives.dataset.image_labelled:
        held = len(negatives.dataset.images) - negatives.dataset.num_negatives()
        raise ValueError(f"{args.negatives}: --negatives takes images without fire; {held} of its images hold a "
                         f"class ({len(negatives.dataset.annotations)} boxes)")  # fmt: skip
    return [[score_model(m, cfg, negatives.dataset, negatives.problems) for m in models]
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


def _compare_slices(
    args: argparse.Namespace, cfg: CompareConfig, results: list[list], levels: list[list]
) -> list[dict]:
    """``--slices``: the comparison slice by slice (:func:`eval.slices.compare_slices`) on the test set's
    computed attributes (and ``--attributes``), printed as a table unless ``--json``; ``--forest`` draws them."""
    import numpy as np

    from eval.attributes import dataset_attributes, merged, read_attributes_csv
    from eval.score import scored_images
    from eval.slices import Side, compare_slices, make_slices, positives_name
    from eval.stats import MatchTable
    from ground.detect.cocoeval import LOOSE_IOU, run_cocoeval

    ds, cat_ids = scored_images(results[0][0])
    attrs = dataset_attributes(ds, cfg.inference.workers)
    if args.attributes is not None:
        attrs = merged(attrs, read_attributes_csv(args.attributes, ds))
    hits = levels[0][0][0]
    slices = make_slices(attrs, hits.image_ids, hits.fire)
    sides = [Side([MatchTable(r.evaluation) for r in side],
                  [MatchTable(run_cocoeval(ds, r.records, cat_ids, [LOOSE_IOU])) for r in side], level)
             for side, level in zip(results, levels)]  # fmt: skip
    rows = compare_slices(sides[0], sides[1], slices, np.random.default_rng(cfg.seed), cfg.samples)
    if args.forest is not None:
        from eval.plots import plot_forest

        panels: dict[str, list[dict]] = {}
        for r in rows:
            panels.setdefault(r["metric"], []).append(r)
        positives = positives_name([c.name for c in ds.categories if c.id in cat_ids])
        plot_forest(panels, args.forest, f"B − A by slice ({positives})")
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


def _class_ap50(side: dict, classes: list[str]) -> str:
    """``" (fire 0.125, smoke 0.601)"``: each class's AP50 of a compare side's run (or mean) on a set of several
    classes; else empty."""
    from eval.tables import class_metric

    cells = [f"{c} {fmt(side[class_metric('AP50', c)])}" for c in classes]
    return f" ({', '.join(cells)})" if cells else ""


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


def _add_operating(
    doc: dict, points: list[list], negatives: Path, cfg: CompareConfig, boxes: bool = True
):  # -> PairedDelta
    """Read every run at ``cfg.alarm_budget`` into ``doc`` (each run's recall and threshold, each side's mean recall,
    ``negatives``: the set and its size) and return the paired bootstrap of the recall difference B - A; a test
    set without boxes (``boxes`` False: image-labelled) has no box recall: only ``negatives``, and None."""
    import numpy as np

    from eval.operating import operating_point, paired_recall_bootstrap

    images = points[0][0][1].images
    doc["negatives"] = {"data": str(negatives), "images": images, "budget": cfg.alarm_budget}
    if cfg.negatives_holdout:
        doc["negatives"]["holdout"] = cfg.negatives_holdout
    if not boxes:
        return None
    for key, side in zip(("A", "B"), points):
        for run, (found, alarms) in zip(doc[key]["runs"], side):
            point = operating_point(found, alarms, cfg.alarm_budget)
            run.update({RECALL_AT_ALARMS: point.recall, "threshold": point.threshold})
        doc[key][RECALL_AT_ALARMS] = float(np.mean([run[RECALL_AT_ALARMS] for run in doc[key]["runs"]]))
    delta = paired_recall_bootstrap(
        points[0], points[1], np.random.default_rng(cfg.seed), cfg.samples, cfg.alarm_budget, seeds=cfg.paired_seeds
    )
    doc["delta"][RECALL_AT_ALARMS] = delta.to_dict()
    return delta


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``compare`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "compare",
        help="AP difference of two detectors on the same test images, with a paired bootstrap interval",
        description="Score two detector ONNX files on the same test set and report AP(B) - AP(A) with a 95%\n"
        "interval and p-value from a paired image-level bootstrap (both models scored on each resample).\n"
        "Each side may be several runs, comma-separated (e.g. one per seed): their AP is averaged on each\n"
        "resample, as the experiment's comparisons average seeds. Settings: --config CONFIG.yaml\n"
        "(docs/config.md#compare), the options below, then --set KEY=VALUE.\n\n"
        "example:\n  fuzzyfire compare runs/R1000_S0/seed0/best.onnx runs/R750_S250/seed0/best.onnx \\\n"
        "      --data ../shared/data/fire-smoke-608 --split test --drop-class default\n"
        "  fuzzyfire compare a/seed0/best.onnx,a/seed1/best.onnx b/seed0/best.onnx,b/seed1/best.onnx \\\n"
        "      --data out/study/data/curated-6407ecb64193 --split test\n"
        "  fuzzyfire compare a.onnx b.onnx --data out/study/data/curated-6407ecb64193 --split test \\\n"
        "      --negatives ../shared/data/fire-free   # + recall at 10 false alarms per 100 fire-free photos\n"
        "  fuzzyfire compare a.onnx b.onnx --data out/study/data/curated-6407ecb64193 --split test \\\n"
        "      --negatives ../shared/data/fire-free --negatives-holdout 0.25   # the photos no pool composited on",
    )
    p.add_argument(
        "model_a", type=_models, metavar="A.onnx", help="baseline detector .onnx (A), or several: A0.onnx,A1.onnx,..."
    )
    p.add_argument(
        "model_b", type=_models, metavar="B.onnx", help="detector compared with it (B), or several: B0.onnx,B1.onnx,..."
    )
    p.add_argument("--data", help="test set: folder, COCO .json or data.yaml, in any format fuzzyfire reads (required)")
    p.add_argument(
        "--negatives",
        type=Path,
        metavar="DATA",
        help="images without fire (a folder of photos, or any set without boxes; every image): each model is "
        "also scored there and read at the threshold where it raises at most --alarm-budget alarms per 100 of "
        "them; adds the recall of the test set's boxes there and its paired difference (both sets resampled)",
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
        help='print {"A": {"model", "AP", "AP50", "runs"}, "B", "images", "classes", "delta": {"AP": ...}, ...} '
        '(a set of several classes: also "AP50 <class>" per side, run and delta)',
    )
    add_settings(p, _compare_config, ALIASES, cmd_compare, flag="--config")

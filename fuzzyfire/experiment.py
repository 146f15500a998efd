"""``fuzzyfire experiment``: the study in one call. Wiring only; the work lives in the stages, runs and eval.

curate (optional) -> synth Method 1 and Method 2 -> mix -> train each mixture x seed -> score every run on
every test set -> aggregate -> report. Output folder::

    OUT/experiment.json            resolved config, versions, git commit, stages, runs and their status
    OUT/data/<stage>-<hash>/       real / rare / method1 / method2 datasets (cached by config hash)
    OUT/mixtures/<pool>-<hash>/seed<S>/R<m>_S<n>/   training mixtures (images symlinked)
    OUT/runs/<mixture>[-<method>]/seed<S>-<hash>/  one run: train/, scores/, results.json (written last)
    OUT/results.jsonl              one line per (run, test set)
    OUT/tables/, OUT/figures/, OUT/report.html
"""

from __future__ import annotations

import functools
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from curate.core.dataset import Dataset, DatasetBuilder
from curate.core.formats.registry import read_dataset
from curate.core.formats.yolo import ultralytics_val_folders
from curate.mix import mixture_dir, parse_mixture, write_mixture
from fuzzyfire.aggregate import STANDIN_NOTICE, result_rows, write_report, write_summary
from fuzzyfire.executors import Outcome
from fuzzyfire.experiment_config import METHODS, ExperimentConfig
from fuzzyfire.runs import EvalSet, RunSpec, execute_run, finished
from fuzzyfire.stages import (
    DataRef,
    Prepared,
    curate_stage,
    digest,
    folder_ref,
    label,
    load_data,
    standin_stage,
    synth_stage,
)


def _say(message: str) -> None:
    print(message, flush=True)


def prepare_data(cfg: ExperimentConfig, base: Path, out: Path) -> Prepared:
    """Build (or reuse) every data stage."""
    root = out / "data"
    real, rare = cfg.real, cfg.rare
    kind = real.source()
    if kind == "path":
        real_ref = folder_ref(real.path, base, real.format, real.aliases, real.drop_classes)
    elif kind == "curate":
        real_ref = _stage("real (curated)", curate_stage, root, real.curate_config(), base)
    else:
        real_ref = _stage("real (stand-in)", standin_stage, root, "real-standin", real.standin)
    rare_ref = None
    if rare is not None and rare.source() == "path":
        rare_ref = folder_ref(rare.path, base, rare.format, rare.aliases, rare.drop_classes, rare.split)
    elif rare is not None:
        rare_ref = _stage("rare (stand-in)", standin_stage, root, "rare-standin", rare.standin)
    pools = {}
    for method in needed_methods(cfg):
        pools[method] = _stage(method, synth_stage, root, method, getattr(cfg.synth, method), base)
    return Prepared(real_ref, rare_ref, pools)


def _stage(what: str, make, *args) -> DataRef:
    """``make(*args)`` -> (Stage, DataRef), announced before (it may take minutes) and after."""
    _say(f"data   {what:<16} ...")
    stage, ref = make(*args)
    _say(f"data   {what:<16} {stage.folder}{'  (cached)' if stage.cached else ''}")
    return ref


def grid_entries(cfg: ExperimentConfig) -> list[tuple[str, str | None]]:
    """(mixture, synthetic method or None) of every distinct run, Table 2 first, then Table 1."""
    entries = []
    for name in cfg.grid.mixtures:
        entries.append((name, None if parse_mixture(name).synth == 0 else cfg.grid.synthetic))
    for name in cfg.grid.table1:
        if parse_mixture(name).real:
            raise ValueError(f"grid.table1: {name} has real images; Table 1 compares synthetic-only training")
        entries += [(name, m) for m in METHODS if getattr(cfg.synth, m) is not None]
    return list(dict.fromkeys(entries))


def needed_methods(cfg: ExperimentConfig) -> list[str]:
    return [m for m in METHODS if any(method == m for _, method in grid_entries(cfg))]


def _empty(root: Path, classes: Sequence[str]) -> Dataset:
    return DatasetBuilder(root, list(classes)).build()


def write_mixtures(cfg: ExperimentConfig, data: Prepared, out: Path) -> dict[tuple[str, str | None, int], DataRef]:
    """Write every (mixture, method, seed) training set; returns their references."""
    real_train = data.real.with_split(cfg.real.train_split)
    real_pool = load_data(real_train, cfg.classes)
    val_ref = data.real.with_split(cfg.real.val_split)
    val = functools.cache(lambda: _yolo_validation(val_ref, cfg.classes))  # read only if a mixture is written
    refs = {}
    for method in dict.fromkeys(m for _, m in grid_entries(cfg)):
        synth = data.pools[method].with_split(None) if method else None
        pool = load_data(synth, cfg.classes) if synth else _empty(real_pool.root, cfg.classes)
        key = {"real": real_train.key(), "synth": synth.key() if synth else None, "classes": list(cfg.classes)}
        root = out / "mixtures" / f"{method or 'real'}-{digest(key)}"
        for seed in cfg.grid.seeds:
            for name, m in grid_entries(cfg):
                if m != method:
                    continue
                folder = _write_mixture(cfg, real_pool, pool, name, seed, root, val)
                identity = {"kind": "mixture", "mixture": name, "seed": seed, **key}
                refs[(name, method, seed)] = DataRef(folder, identity, "coco")
    _say(f"mix    {len(refs)} training sets in {out / 'mixtures'}")
    return refs


def _yolo_validation(ref: DataRef, classes: Sequence[str]) -> Dataset | None:
    """The real validation split as read, when ultralytics can validate on it (the mixtures' ``data.yaml``
    then names it); else None and a line saying why (``data.yaml``'s val stays the training images)."""
    ds = read_dataset(ref.path, ref.format, aliases=dict(ref.aliases) or None).dataset.select_split(ref.split)
    try:
        ultralytics_val_folders(ds, classes)
    except ValueError as exc:
        _say(f"mix    data.yaml val = training images ({exc})")
        return None
    return ds


def _write_mixture(
    cfg: ExperimentConfig,
    real: Dataset,
    synth: Dataset,
    name: str,
    seed: int,
    root: Path,
    val: Callable[[], Dataset | None],
) -> Path:
    mix = parse_mixture(name)
    folder = mixture_dir(root, mix, seed)
    if (folder / "mixture.json").is_file():
        return folder
    if folder.exists():
        shutil.rmtree(folder)  # our own interrupted mixture
    return write_mixture(real, synth, mix, seed, root, cfg.images, cfg.classes, val=val())


def plan_runs(
    cfg: ExperimentConfig, data: Prepared, mixtures: dict[tuple[str, str | None, int], DataRef], out: Path
) -> list[RunSpec]:
    """One spec per (seed, mixture, method): seed-major, so a partial grid has whole tables for early seeds."""
    tests = [EvalSet(label(cfg.real.name, data.real.standin), data.real.with_split(cfg.real.test_split))]
    if data.rare is not None:
        tests.append(EvalSet(label(cfg.rare.name, data.rare.standin), data.rare))
    threads = max(1, int(cfg.executor.num_cpus))
    train = cfg.train if cfg.train.threads else replace(cfg.train, threads=threads)
    score = cfg.score if cfg.score.threads else replace(cfg.score, threads=threads)
    val = data.real.with_split(cfg.real.val_split)
    engine = cfg.engine if cfg.engine.name == "command" else None
    specs = []
    for seed in cfg.grid.seeds:
        for name, method in grid_entries(cfg):
            spec = RunSpec(name, method, seed, mixtures[(name, method, seed)], val, tuple(tests), cfg.classes,
                           train, score, out, engine)  # fmt: skip
            specs.append(replace(spec, out=out / "runs" / spec.label / f"seed{seed}-{spec.hash()[:8]}"))
    return specs


def run_grid(specs: Sequence[RunSpec], executor) -> list[dict[str, Any] | None]:
    """Execute every spec; print one line per finished run; returns results aligned with ``specs``."""
    results: list[dict[str, Any] | None] = [None] * len(specs)
    _say(f"runs   {len(specs)} runs with the {executor.name} executor")
    for count, outcome in enumerate(executor.map(execute_run, specs), start=1):
        spec = specs[outcome.index]
        results[outcome.index] = outcome.result
        _say(f"run    {count}/{len(specs)} {spec.label} seed {spec.seed}: {_outcome_text(outcome)}")
    return results


def _outcome_text(outcome: Outcome) -> str:
    if outcome.error:
        return f"FAILED {outcome.error}"
    res = outcome.result
    scores = "  ".join(f"{name} AP {_pct(m['AP'])} AP50 {_pct(m['AP50'])}" for name, m in res["tests"].items())
    return f"{scores}{'  (done before)' if res.get('skipped') else ''}"


def _pct(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f}"


@dataclass(frozen=True)
class ExperimentResult:
    report: Path
    rows: list[dict]
    failed: list[RunSpec]
    standin: bool


def finished_runs(specs: Sequence[RunSpec]) -> list[dict[str, Any] | None]:
    """The results of the specs that already finished (None for the others); trains nothing."""
    results = [finished(spec) for spec in specs]
    _say(f"runs   {sum(r is not None for r in results)} of {len(specs)} runs finished (report only)")
    return results


def run_experiment(cfg: ExperimentConfig, base: Path, out: Path, executor=None) -> ExperimentResult:
    """The whole study (module docstring); ``base`` resolves relative paths of the config. Without an
    ``executor`` nothing is trained: the report covers the runs finished so far (``failed`` lists the others)."""
    cfg.check()
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    data = prepare_data(cfg, base, out)
    if data.standin:
        _say(STANDIN_NOTICE)
    for split in (cfg.real.val_split, cfg.real.test_split):  # fail now, not after the first training
        load_data(data.real.with_split(split), cfg.classes)
    specs = plan_runs(cfg, data, write_mixtures(cfg, data, out), out)
    results = run_grid(specs, executor) if executor is not None else finished_runs(specs)
    rows = result_rows(cfg, specs, results, out)
    write_summary(cfg, specs, results, rows, out, data.standin)
    report = write_report(cfg, data, rows, out, specs, results)
    failed = [s for s, r in zip(specs, results) if r is None]
    return ExperimentResult(report, rows, failed, data.standin)

"""``fuzzyfire experiment``: the study in one call. Wiring only; the work lives in the stages, runs and eval.

curate (optional) -> synth Method 1 and Method 2 -> mix -> train each mixture x seed -> score every run on
every test set (common, rare and the named ``tests:``; each checked first against the training data, its
leaked images dropped, and refused when it holds a pool's background photo, :mod:`fuzzyfire.leakage`) -> aggregate -> report. Output folder::

    OUT/experiment.json            resolved config, versions, git commit, stages, runs and their status
    OUT/leakage.json               every test set's images found in the training data (dropped from it)
    OUT/data/<stage>-<hash>/       real / rare / method1 / method2 datasets (cached by config hash)
    OUT/mixtures/<pool>-<hash>/seed<S>/R<m>_S<n>/   training mixtures (images symlinked)
    OUT/runs/<mixture>[-<method>]/seed<S>-<hash>/  one run: train/, scores/, results.json (written last)
    OUT/results.jsonl              one line per (run, test set)
    OUT/tables/, OUT/figures/, OUT/report.html
"""

from __future__ import annotations

import functools
import shutil
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from curate.curation import read_curation
from curate.mix import mixture_dir, parse_mixture, write_mixture
from eval.errors import ALARMS
from eval.imagelevel import IMAGE_LABELLED
from fuzzyfire.aggregate import STANDIN_NOTICE, result_rows, write_report, write_summary
from fuzzyfire.controls import CONTROL, CONTROL_TABLE, control_pools, has_control
from fuzzyfire.cutout_pools import cutout_pools, is_own, simulated
from fuzzyfire.datasets import DataRef, Datasets
from fuzzyfire.executors import Outcome
from fuzzyfire.experiment_config import METHODS, EvalSetConfig, ExperimentConfig, ExperimentConfigError
from fuzzyfire.leakage import (
    LEAKS_FILE,
    LeakageError,
    TestLeaks,
    check_leakage,
    find_test_leaks,
    pool_photos,
    reference_images,
    write_leaks,
)
from fuzzyfire.runs import EvalSet, RunSpec, RunTask, execute_task, finished, missing_evals, run_data
from fuzzyfire.stages import (
    Prepared,
    curate_stage,
    digest,
    folder_ref,
    label,
    standin_stage,
    synth_stage,
    with_class_rules,
)
from ground.data.dataset import Dataset, DatasetBuilder
from ground.data.formats.yolo import ultralytics_val_folders
from ground.data.load import SplitError
from ground.run.lock import lock_status, lock_summary
from synth.method2 import Method2Config
from train.config import TrainConfig


def _say(message: str) -> None:
    print(message, flush=True)


def prepare_data(cfg: ExperimentConfig, base: Path, out: Path, methods: Sequence[str]) -> Prepared:
    """Build (or reuse) every data stage: the real set, the rare set, the named test sets and the pools of
    ``methods``."""
    root = out / "data"
    real = cfg.real
    kind = real.source()
    if kind == "path":
        real_ref = folder_ref(
            real.path, base, real.format, real.aliases, real.drop_classes, negatives=real.negative_classes,
            key="real.path",
        )  # fmt: skip
    elif kind == "curate":
        curated = _stage("real (curated)", curate_stage, root, real.curate_config(), base)
        real_ref = with_class_rules(curated, real.drop_classes, real.negative_classes)
    else:
        real_ref = _stage("real (stand-in)", standin_stage, root, "real-standin", real.standin)
    rare_ref = _test_ref(cfg.rare, "rare", "rare-standin", base, root, "rare") if cfg.rare is not None else None
    tests = {}
    for key, name in cfg.test_names().items():
        ref = _test_ref(cfg.tests[key], f"test {key}", "test-standin", base, root, f"tests.{key}")
        tests[label(name, ref.standin)] = ref
    return Prepared(real_ref, rare_ref, prepare_pools(cfg, base, out, methods), tests)


def prepare_pools(cfg: ExperimentConfig, base: Path, out: Path, methods: Sequence[str]) -> dict[str, DataRef]:
    """Build (or reuse) the synthetic pools of ``methods``."""
    pools = {}
    for method in methods:
        synth = cfg.synth.section(method)
        if synth is None:
            raise ExperimentConfigError(f"synth.{method} is null: no {method} pool to build")
        synth = simulated(synth) if isinstance(synth, Method2Config) else synth  # own pools: fuzzyfire.cutout_pools
        pools[method] = _stage(method, synth_stage, out / "data", synth, base)
    return pools


def _test_ref(t: EvalSetConfig, what: str, stage: str, base: Path, root: Path, key: str) -> DataRef:
    """A test set's data (config key ``key``): its folder read in place, or its stand-in built as stage ``stage``."""
    if t.source() == "path":
        return folder_ref(
            t.path, base, t.format, t.aliases, t.drop_classes, t.split, t.holdout, t.negative_classes, f"{key}.path",
            t.label,
        )  # fmt: skip
    ref = _stage(f"{what} (stand-in)", standin_stage, root, stage, t.standin)
    return replace(ref, identity={**ref.identity, "label": t.label}, label=t.label) if t.label else ref


def _stage(what: str, make, *args) -> DataRef:
    """``make(*args)`` -> (Stage, DataRef), announced before (it may take minutes) and after."""
    _say(f"data   {what:<16} ...")
    stage, ref = make(*args)
    _say(f"data   {what:<16} {stage.folder}{'  (cached)' if stage.cached else ''}")
    if stage.note:
        _say(f"data   {what:<16} {stage.note}")
    return ref


@dataclass(frozen=True)
class GridEntry:
    """One run of every seed: a mixture, its synthetic pool (None for real-only) and the tables it is in."""

    mixture: str
    method: str | None
    tables: tuple[str, ...]


def grid_entries(cfg: ExperimentConfig) -> list[GridEntry]:
    """The distinct runs of one seed, Table 2 first, then the controls (``grid.control``: method
    :data:`fuzzyfire.controls.CONTROL`), then Table 1 (a run in two tables is one run). This is the one place
    that decides which runs exist and which tables they fill."""
    tables: dict[tuple[str, str | None], list[str]] = {}
    for name in cfg.grid.mixtures:
        method = None if parse_mixture(name).synth == 0 else cfg.grid.synthetic
        tables.setdefault((name, method), []).append("table2")
    for name in cfg.grid.mixtures if cfg.grid.control else ():
        if has_control(name):
            tables.setdefault((name, CONTROL), []).append(CONTROL_TABLE)
    for name in cfg.grid.table1:
        if parse_mixture(name).real:
            raise ValueError(f"grid.table1: {name} has real images; Table 1 compares synthetic-only training")
        for method in (m for m in METHODS if cfg.synth.section(m) is not None):
            tables.setdefault((name, method), []).append("table1")
    return [GridEntry(name, method, tuple(dict.fromkeys(t))) for (name, method), t in tables.items()]


def needed_methods(grid: Sequence[GridEntry]) -> list[str]:
    """The synthetic pools the runs of ``grid`` draw from, in :data:`METHODS` order."""
    return [m for m in METHODS if any(e.method == m for e in grid)]


def shared_methods(cfg: ExperimentConfig, grid: Sequence[GridEntry]) -> list[str]:
    """The methods of :func:`needed_methods` whose *shared* pool some run of ``grid`` draws: Method 2's is left
    out when every Method 2 run has real images and own pools (:func:`fuzzyfire.cutout_pools.is_own`) take its
    place, so a study of own pools does not build a simulated pool nothing trains on."""
    own = is_own(cfg.synth.method2)
    return [
        m
        for m in needed_methods(grid)
        if not (m == "method2" and own and all(parse_mixture(e.mixture).real for e in grid if e.method == m))
    ]


def _empty(root: Path, classes: Sequence[str]) -> Dataset:
    return DatasetBuilder(root, list(classes)).build()


def write_mixtures(
    cfg: ExperimentConfig,
    grid: Sequence[GridEntry],
    data: Prepared,
    datasets: Datasets,
    out: Path,
    own: Mapping[tuple[str, str, int], DataRef] | None = None,
) -> dict[tuple[str, str | None, int], DataRef]:
    """Write every (mixture, method, seed) training set of ``grid``; returns their references. ``own``: the
    pool of a (mixture, method, seed) that has its own (:func:`fuzzyfire.cutout_pools.cutout_pools`,
    :func:`fuzzyfire.controls.control_pools`) instead of the method's shared one."""
    real_train = data.real.with_split(cfg.real.train_split)
    real_pool = datasets.get(real_train)
    val_ref = data.real.with_split(cfg.real.val_split)
    val = functools.cache(lambda: _yolo_validation(datasets, val_ref, cfg.classes))  # only if a mixture is written
    refs = {}
    for method in dict.fromkeys(e.method for e in grid):
        shared = data.pools[method].with_split(None) if method in data.pools else None
        for seed in cfg.grid.seeds:
            for name in (e.mixture for e in grid if e.method == method):
                synth = (own or {}).get((name, method, seed), shared) if method else None
                if method and synth is None:
                    raise KeyError(f"no {method} pool for {name} seed {seed}")  # a control without its pool
                pool = datasets.get(synth) if synth else _empty(real_pool.root, cfg.classes)
                key = {"real": real_train.key(), "synth": synth.key() if synth else None, "classes": list(cfg.classes)}
                root = out / "mixtures" / f"{method or 'real'}-{digest(key)}"
                folder = _write_mixture(cfg, real_pool, pool, name, seed, root, val)
                identity = {"kind": "mixture", "mixture": name, "seed": seed, **key}
                refs[(name, method, seed)] = DataRef(folder, identity, "coco")
    _say(f"mix    {len(refs)} training sets in {out / 'mixtures'}")
    return refs


def _yolo_validation(datasets: Datasets, ref: DataRef, classes: Sequence[str]) -> Dataset | None:
    """The real validation split as read, when ultralytics can validate on it (the mixtures' ``data.yaml``
    then names it); else None and a line saying why (``data.yaml``'s val stays the training images)."""
    ds = datasets.read(ref).select_split(ref.split)
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
    cfg: ExperimentConfig,
    grid: Sequence[GridEntry],
    data: Prepared,
    mixtures: dict[tuple[str, str | None, int], DataRef],
    out: Path,
) -> list[RunSpec]:
    """One fully resolved spec per (seed, grid entry): seed-major, so a partial grid has whole tables for early
    seeds. Each run's train config carries its seed and threads, its score config its threads (``0`` in the
    config = the executor's CPUs per run)."""
    tests, evals = test_sets(cfg, data)
    threads = max(1, int(cfg.executor.num_cpus))
    train = replace(cfg.train, threads=cfg.train.threads or threads)
    score = replace(cfg.score, threads=cfg.score.threads or threads)
    val = data.real.with_split(cfg.real.val_split)
    engine = cfg.engine if cfg.engine.name == "command" else None
    return [
        RunSpec(
            e.mixture,
            e.method,
            mixtures[(e.mixture, e.method, seed)],
            val,
            tests,
            cfg.classes,
            _train_for(replace(train, seed=seed), e.mixture),
            score,
            out,
            engine,
            e.tables,
            evals,
        )  # fmt: skip
        for seed in cfg.grid.seeds
        for e in grid
    ]


def _train_for(train: TrainConfig, mixture: str) -> TrainConfig:
    """``train`` for one mixture: ``real_finetune`` only where the mixture has real *and* synthetic images (else it
    changes nothing, and a real-only or synthetic-only run stays the run it was: same identity, not trained again)."""
    mix = parse_mixture(mixture)
    return train if mix.real and mix.synth else replace(train, real_finetune=0)


def test_sets(cfg: ExperimentConfig, data: Prepared) -> tuple[tuple[EvalSet, ...], tuple[EvalSet, ...]]:
    """The test sets of every run: the common and rare sets, and the named sets of ``tests:`` (adding one scores
    the finished runs, it trains nothing), each without the images that leak from the training data when
    ``leakage.action`` is drop (``data.leaks``)."""
    tests = {label(cfg.real.name, data.real.standin): data.real.with_split(cfg.real.test_split)}
    if data.rare is not None:
        tests[label(cfg.rare.name, data.rare.standin)] = data.rare
    drop = cfg.leakage.action == "drop"

    def clean(name: str, ref: DataRef) -> EvalSet:
        leaks = data.leaks.get(name)
        return EvalSet(name, replace(ref, exclude=leaks.leaked) if drop and leaks and leaks.leaked else ref)

    return tuple(clean(n, r) for n, r in tests.items()), tuple(clean(n, r) for n, r in data.tests.items())


def check_test_leaks(cfg: ExperimentConfig, data: Prepared, datasets: Datasets, base: Path) -> dict[str, TestLeaks]:
    """Every test set against the real training data (:func:`fuzzyfire.leakage.find_test_leaks`), one line per
    set; raises :class:`fuzzyfire.leakage.LeakageError` when one leaks and ``leakage.action`` is refuse."""
    from curate.embed import embedding_cache_path, load_embedder
    from curate.embedcache import EmbeddingCache
    from curate.scan import scan_images

    trained = [datasets.get(data.real.with_split(s)) for s in (cfg.real.train_split, cfg.real.val_split)]
    sources = [s.path if s.path.is_absolute() else base / s.path for s in cfg.real.curate_config().sources] \
        if cfg.real.source() == "curate" else []  # fmt: skip
    common, named = test_sets(cfg, replace(data, leaks={}))
    own = common[0].name  # the real set's own test split: its images are among the curated sources
    tests = {t.name: (datasets.get(t.data), reference_images(trained, [] if t.name == own else sources))
             for t in (*common, *named)}  # fmt: skip
    _say(f"leak   checking {len(tests)} test sets against the training data ...")
    embedder = load_embedder()
    with EmbeddingCache(embedding_cache_path()) as cache:
        leaks = find_test_leaks(tests, cfg.leakage.threshold, lambda paths: scan_images(paths, embedder, cache))
    for t in leaks.values():
        _say(f"leak   {t.line(cfg.leakage.action)}")
    if cfg.leakage.action == "refuse" and any(t.leaked for t in leaks.values()):
        worst = max(leaks.values(), key=lambda t: len(t.leaked))
        raise LeakageError(f"leakage: {worst.line('refuse')}; set leakage.action: drop to test without them")
    return leaks


def run_grid(specs: Sequence[RunSpec], datasets: Datasets, executor) -> list[dict[str, Any] | None]:
    """Execute every spec, handing it its shared datasets from ``datasets``; print one line per finished run;
    returns results aligned with ``specs``."""
    results: list[dict[str, Any] | None] = [None] * len(specs)
    _say(f"runs   {len(specs)} runs with the {executor.name} executor")
    tasks = [RunTask(s, run_data(s, datasets.get)) for s in specs]
    for count, outcome in enumerate(executor.map(execute_task, tasks), start=1):
        spec = specs[outcome.index]
        results[outcome.index] = outcome.result
        _say(f"run    {count}/{len(specs)} {spec.label} seed {spec.seed}: {_outcome_text(outcome)}")
    return results


def _outcome_text(outcome: Outcome) -> str:
    if outcome.error:
        return f"FAILED {outcome.error}"
    res = outcome.result
    scores = "  ".join(_scores_text(name, m) for name, m in res["tests"].items())
    if res.get("scored"):
        return f"{scores}  (trained before; scored now on {', '.join(res['scored'])})"
    return f"{scores}{'  (done before)' if res.get('skipped') else ''}"


def _scores_text(name: str, m: dict[str, Any]) -> str:
    if m.get(ALARMS) is not None:
        return f"{name} alarms/100 {m[ALARMS]:.1f}"
    if m.get(IMAGE_LABELLED):
        return f"{name} per image (image recall in the report)"
    return f"{name} AP {_pct(m['AP'])} AP50 {_pct(m['AP50'])}"


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
    missing = Counter(t.name for s, r in zip(specs, results) if r is not None for t in missing_evals(s, r))
    for name, count in missing.items():
        _say(f"runs   {name}: {count} finished runs not scored on it yet (run without --report-only: no training)")
    return results


def check_data(cfg: ExperimentConfig, data: Prepared, datasets: Datasets, photos: dict[str, list[Path]]) -> None:
    """Fail now, not after the first training: the real set must have its validation and test splits, and no
    test set may hold a background photo of a pool (``photos``: :func:`fuzzyfire.leakage.pool_photos`). An
    image-labelled real set (no boxes to train on) is refused: such a set is a test set."""
    if datasets.read(data.real).image_labelled:
        raise ExperimentConfigError(f"real: {data.real.path} is labelled per image (class folders), not boxed: a "
                                    "detector trains on boxes; give it as a test set under tests: instead")  # fmt: skip
    for split in (cfg.real.val_split, cfg.real.test_split):
        try:
            datasets.get(data.real.with_split(split))
        except SplitError as exc:
            raise SplitError(f"{exc}: curate the real set (real.curate) or name its splits (real.*_split)") from None
    every = [t for group in test_sets(cfg, data) for t in group]
    for name, path in cfg.report.attributes.items():
        if name not in {t.name for t in every}:
            raise ExperimentConfigError(f"report.attributes: no test set {name!r} (test sets: "
                                        f"{', '.join(t.name for t in every)})")  # fmt: skip
        if not Path(path).is_file():
            raise FileNotFoundError(f"report.attributes.{name}: {path}: no such file")
    check_leakage(photos, {t.name: datasets.get(t.data) for t in every} if photos else {})


def check_real_count(cfg: ExperimentConfig, data: Prepared, datasets: Datasets, grid: Sequence[GridEntry]) -> None:
    """Fail before any pool is built when a mixture of ``grid`` asks for more real images than the real set's
    training split holds, saying what curation dropped and how to ask for fewer."""
    train = datasets.get(data.real.with_split(cfg.real.train_split))
    want = max((parse_mixture(e.mixture) for e in grid), key=lambda m: m.real, default=None)
    if want is None or want.real <= len(train.images):
        return
    dropped = (read_curation(data.real.path) or {}).get("counts", {}).get("removed_near", 0)
    why = (f" (curation dropped {dropped} near-duplicate images: a video's frames are near duplicates; a lower "
           "real.curate.dedup.threshold keeps more of them)" if dropped else "")  # fmt: skip
    fewer = max(len(train.images) // 50 * 50, 1)
    raise ExperimentConfigError(
        f"real: {want.name} asks for {want.real} real training images but {data.real.path} holds "
        f"{len(train.images)} in its {cfg.real.train_split!r} split{why}; ask for fewer, e.g. "
        f"--set 'grid.mixtures=[R{fewer}_S0,R{fewer}_S{fewer}]', or give more labelled images"
    )


def studied_classes(cfg: ExperimentConfig, data: Prepared, datasets: Datasets) -> tuple[ExperimentConfig, Datasets]:
    """``cfg`` with its classes resolved (``classes: null`` = the classes the real data boxes, less
    ``real.drop_classes`` and ``real.negative_classes``: :func:`ground.data.load.data_classes`) and ``datasets`` prepared with them; says which
    classes are studied and what the class rules removed from each set (:class:`ground.data.load.ClassChanges`)."""
    from ground.data.load import data_classes

    classes, given = cfg.classes, cfg.classes is not None
    if classes is None:
        classes = data_classes(datasets.read(data.real), drop=(*cfg.real.drop_classes, *cfg.real.negative_classes))
        if not classes:
            raise ExperimentConfigError(f"{data.real.path}: the real data has no boxes of any class: nothing to study")
        cfg = replace(cfg, classes=classes)
        datasets = datasets.for_classes(classes)
    _say(f"data   classes studied: {', '.join(classes)} ({'config' if given else 'the classes the real data boxes'})")
    for line in reading_lines(cfg, data, datasets):
        _say(line)
    return pools_box_classes(cfg), datasets


def pools_box_classes(cfg: ExperimentConfig) -> ExperimentConfig:
    """``cfg`` whose synthetic pools box smoke exactly when smoke is a studied class (``smoke_class`` of each
    method follows ``classes``: a pool of a fire + smoke study labels its plumes and its frames' smoke, a fire-only
    one neither); ExperimentConfigError when a method sets ``smoke_class: true`` in a study without smoke."""
    smoke = "smoke" in (cfg.classes or ())
    sections = {}
    for method in METHODS:
        section = cfg.synth.section(method)
        if section is None or section.smoke_class == smoke:
            continue
        if section.smoke_class:
            raise ExperimentConfigError(
                f"synth.{method}.smoke_class is true but smoke is not a studied class ({', '.join(cfg.classes or ())}):"
                " a pool boxes the classes the study has; add smoke to classes or drop the key"
            )
        sections[method] = replace(section, smoke_class=True)
    return replace(cfg, synth=replace(cfg.synth, **sections)) if sections else cfg


def reading_lines(cfg: ExperimentConfig, data: Prepared, datasets: Datasets) -> list[str]:
    """What each test set without boxes was read as, one line each: a negatives-only set (with how to declare
    it image-labelled instead) or an image-labelled one (:meth:`fuzzyfire.datasets.Datasets.reading`)."""
    sets = {**({cfg.rare.name: data.rare} if cfg.rare is not None and data.rare is not None else {}), **data.tests}
    lines = []
    for name, ref in sets.items():
        said = datasets.reading(ref)
        if said and datasets.read(ref).image_labelled:
            lines.append(f"data   test {name}: {said}")
        elif said:
            lines.append(f"data   test {name}: {said} (its false alarms are counted; if its images hold fire, "
                         f"declare it: label: fire, or fire/ and normal/ sub-folders)")  # fmt: skip
    return lines


def run_experiment(cfg: ExperimentConfig, base: Path, out: Path, executor=None) -> ExperimentResult:
    """The whole study (module docstring); ``base`` resolves relative paths of the config. Without an
    ``executor`` nothing is trained: the report covers the runs finished so far (``failed`` lists the others)."""
    cfg = cfg.resolved(base)
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    _say(f"env    {lock_summary(lock_status())}")
    grid = grid_entries(cfg)
    data = prepare_data(cfg, base, out, ())  # the real and test sets, checked before any pool is built
    from_data = cfg.classes is None
    cfg, datasets = studied_classes(cfg, data, Datasets(cfg.classes or ()))
    check_data(cfg, data, datasets, pool_photos(cfg.synth, needed_methods(grid), base))
    check_real_count(cfg, data, datasets, grid)
    data = replace(data, leaks=check_test_leaks(cfg, data, datasets, base))
    write_leaks(out / LEAKS_FILE, data.leaks, cfg.leakage.threshold, cfg.leakage.action)
    data = replace(data, pools=prepare_pools(cfg, base, out, shared_methods(cfg, grid)))
    if data.standin:
        _say(STANDIN_NOTICE)
    drawn = [e.mixture for e in grid if e.method == "method2"]
    real_train = data.real.with_split(cfg.real.train_split)
    own = cutout_pools(cfg, drawn, real_train, datasets, base, out)
    controlled = [e.mixture for e in grid if e.method == CONTROL]
    own = {**own, **control_pools(cfg, controlled, real_train, datasets, base, out)}
    specs = plan_runs(cfg, grid, data, write_mixtures(cfg, grid, data, datasets, out, own), out)
    results = run_grid(specs, datasets, executor) if executor is not None else finished_runs(specs)
    rows = result_rows(specs, results, out, datasets, cfg.report.min_fire_images)
    write_summary(cfg, specs, results, rows, out, data.standin)
    report = write_report(cfg, data, datasets, rows, out, specs, results, own, from_data)
    failed = [s for s, r in zip(specs, results) if r is None]
    return ExperimentResult(report, rows, failed, data.standin)

"""One run of the grid: train on a mixture with a seed, then score ``best.onnx`` on every test set.

A run is a pure function of its :class:`RunSpec` (config, mixture, seed and the identities of its data). It
writes into ``spec.out``: ``run.json`` (the spec) first, ``train/`` (the training run folder, resumable from
its ``last.pt``), ``scores/<test set>/`` (metrics.json, predictions.json, matches.npz, pr_curve.png,
errors.json), ``timing.json``
and, last, ``results.json``. A run whose ``results.json`` carries the same identity hash is not trained again,
so a rerun does nothing and an interrupted grid resumes. No test set is part of that identity (a test set does
not change the model): one added later, or redefined (e.g. leaked images dropped, :mod:`fuzzyfire.leakage`), is
scored with the finished run's model and its entry in ``results.json`` replaced. ``results.json`` holds no timings or absolute paths: the same spec gives byte-identical files.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from eval.errors import ALARMS
from eval.imagelevel import IMAGE_LABELLED
from fuzzyfire.datasets import DataRef, load_data
from fuzzyfire.engine import CommandJob, command_train
from fuzzyfire.stages import digest
from ground.config.loader import to_dict

if TYPE_CHECKING:
    from eval.config import InferenceConfig
    from eval.errors import ErrorBreakdown
    from fuzzyfire.engine import EngineConfig
    from ground.data.dataset import Dataset
    from ground.detect.cocoeval import CocoMetrics
    from train.config import TrainConfig

RESULTS_FILE = "results.json"
METRICS = ("AP", "AP50", "AP25", "AP75", "AP_small", "AP_medium", "AP_large")  # as eval.score reports them


class RunError(RuntimeError):
    """A run that could not finish (its folder and the cause in the message)."""


def train_identity(train: TrainConfig) -> dict[str, Any]:
    """``train`` as a run's identity holds it: every key (the identity's version, :data:`fuzzyfire.stages.IDENTITY`,
    is bumped when a key's meaning changes)."""
    return to_dict(train)


@dataclass(frozen=True)
class EvalSet:
    name: str  # label in the tables, e.g. "common (stand-in)"
    data: DataRef


@dataclass(frozen=True)
class RunSpec:
    """Everything a run needs, resolved once by :func:`fuzzyfire.experiment.plan_runs` and never patched after.

    ``method`` is the synthetic pool (None for real-only mixtures); ``train`` the final train config (its
    ``seed`` is the run's seed, its ``threads`` resolved); ``score`` eval's own scoring options; ``engine`` an
    external trainer (:mod:`fuzzyfire.engine`; None = our detector); ``tables`` the study tables the run's rows
    belong to (``table1``, ``table2``); ``root`` the experiment folder (the run's own folder, :attr:`out`,
    follows from its label, seed and identity hash); ``tests`` the common and rare sets, ``evals`` the named
    test sets (no test set is in the identity: module docstring)."""

    mixture: str
    method: str | None
    train_data: DataRef  # the mixture folder
    val_data: DataRef
    tests: tuple[EvalSet, ...]
    classes: tuple[str, ...]
    train: TrainConfig
    score: InferenceConfig
    root: Path
    engine: EngineConfig | None = None
    tables: tuple[str, ...] = ()
    evals: tuple[EvalSet, ...] = ()  # named test sets

    @property
    def seed(self) -> int:
        return self.train.seed

    @property
    def label(self) -> str:
        return self.mixture if self.method is None else f"{self.mixture}-{self.method}"

    @property
    def out(self) -> Path:
        """``root/runs/<label>/seed<S>-<first 8 hex digits of the hash>``."""
        return self.root / "runs" / self.label / f"seed{self.seed}-{self.hash()[:8]}"

    def identity(self) -> dict[str, Any]:
        """What makes the run's model and its scoring (no test set, no paths of ours, no table membership): equal
        identities give equal results on equal test sets."""
        engine = {"engine": to_dict(self.engine)} if self.engine is not None else {}
        return {
            **engine,
            "mixture": self.mixture,
            "method": self.method,
            "seed": self.seed,
            "train_data": self.train_data.key(),
            "val_data": self.val_data.key(),
            "classes": list(self.classes),
            "train": train_identity(self.train),
            "score": to_dict(self.score),
        }

    def hash(self) -> str:
        return digest(self.identity())

    @property
    def test_sets(self) -> tuple[EvalSet, ...]:
        """Every test set the run is scored on: :attr:`tests`, then :attr:`evals`."""
        return (*self.tests, *self.evals)

    def record(self) -> dict[str, Any]:
        """The resolved spec as ``run.json`` and ``results.json`` keep it: identity, hash and tables."""
        return {"hash": self.hash(), "identity": self.identity(), "tables": list(self.tables)}


class RunData(NamedTuple):
    """The shared datasets a run reads, prepared by the experiment (each read once for the whole grid): ``val``
    and the test sets by name. The mixture a run trains on is its own; the run reads it."""

    val: Dataset
    tests: dict[str, Dataset]


class RunTask(NamedTuple):
    """A run as the grid hands it to an executor: its spec and its shared datasets."""

    spec: RunSpec
    data: RunData


def execute_task(task: RunTask) -> dict[str, Any]:
    """:func:`execute_run` of a task (what executors map over)."""
    return execute_run(task.spec, task.data)


def finished(spec: RunSpec) -> dict[str, Any] | None:
    """The run's results when it already finished with this very spec, else None."""
    path = spec.out / RESULTS_FILE
    if not path.is_file():
        return None
    doc = json.loads(path.read_text(encoding="utf-8"))
    return doc if doc.get("hash") == spec.hash() else None


def _write_json(path: Path, doc: Any) -> None:
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def run_data(spec: RunSpec, load: Callable[[DataRef], Dataset] | None = None) -> RunData:
    """The shared datasets of ``spec``, each from ``load`` (the experiment's :meth:`fuzzyfire.datasets.Datasets.get`);
    without it read from disk now (a run outside an experiment)."""
    load = load or (lambda ref: load_data(ref, spec.classes))
    return RunData(load(spec.val_data), {t.name: load(t.data) for t in spec.test_sets})


def train_run(spec: RunSpec, val: Dataset) -> dict[str, Any]:
    """Train (or resume) into ``spec.out/train``, selecting the epoch by ``spec.train.select`` (validation on
    ``val``); returns train's results (best and selected epoch and their metrics). A run that differs from a
    trained one only in ``select`` starts from its training (:func:`adopt_training`): nothing is trained again."""
    from train.loop import fit

    adopt_training(spec)
    return fit(spec.train, load_data(spec.train_data, spec.classes), val, spec.out / "train")


def adopt_training(spec: RunSpec) -> Path | None:
    """Copy the training of ``spec``'s twin with the other ``train.select`` (its ``train/`` without the exported
    model and results) into ``spec.out/train`` when that twin finished training and ``spec`` has not begun;
    returns the folder copied from. The twin's weights are the same (``select`` only chooses what is exported),
    so resuming there trains nothing."""
    import shutil

    here = spec.out / "train"
    if (here / "last.pt").is_file():
        return None
    for other in ("best", "last"):
        twin = replace(spec, train=replace(spec.train, select=other)).out / "train"
        if other != spec.train.select and (twin / "results.json").is_file() and (twin / "last.pt").is_file():
            shutil.copytree(twin, here, ignore=shutil.ignore_patterns("*.onnx", "results.json"), dirs_exist_ok=True)
            print(f"train  {spec.label} seed {spec.seed}: the training of {twin.parent} (select: {other}) reused")
            return twin
    return None


def score_run(
    spec: RunSpec, model: Path, tests: dict[str, Dataset], which: Sequence[EvalSet] | None = None
) -> dict[str, dict[str, Any]]:
    """Score ``model`` on the test sets ``which`` (None = every one of ``spec``; ``tests``: their datasets by
    name); writes ``scores/<name>/``; returns headline metrics per test set (:func:`headline`). Each entry
    carries its data's digest (:func:`eval_key`): a redefined set is scored again."""
    from eval.score import score, score_errors, write_outputs

    detector = spec.score.detector(model)
    if detector.device_notice:
        print(detector.device_notice, flush=True)
    out = {}
    for test in spec.test_sets if which is None else which:
        result = score(detector, tests[test.name], spec.score)
        folder = spec.out / "scores" / slug(test.name)
        write_outputs(result, folder)
        errors = score_errors(result)
        errors.write(folder)
        out[test.name] = {**headline(result.metrics, errors, f"scores/{slug(test.name)}"), "data": eval_key(test)}
    return out


def headline(m: CocoMetrics, errors: ErrorBreakdown, folder: str) -> dict[str, Any]:
    """What ``results.json`` keeps of one scoring: :data:`METRICS` (0..1, None when undefined), counts, per-class
    metrics and the scores folder; for a set without boxes (negatives only: AP undefined) also :data:`ALARMS`,
    the breakdown's detections at ``errors.alarm_conf`` per 100 images (:mod:`eval.errors`); for an
    image-labelled set (no boxes, images holding a class: AP undefined, judged by image recall)
    :data:`eval.imagelevel.IMAGE_LABELLED` True."""
    doc = {
        **{k: m.summary.get(k) for k in METRICS},
        "images": m.images,
        "boxes": m.boxes,
        "detections": m.detections,
        "per_class": m.per_class,
        "scores": folder,
    }
    if m.boxes == 0 and m.negatives == m.images:
        doc[ALARMS] = errors.false_alarms_per_100
    elif m.boxes == 0:
        doc[IMAGE_LABELLED] = True
    return doc


def eval_key(test: EvalSet) -> str:
    """The digest of a test set's data (its identity, split and dropped images) as its results entry records it."""
    return digest(test.data.key())


def missing_evals(spec: RunSpec, results: dict[str, Any]) -> list[EvalSet]:
    """The test sets of ``spec`` that its finished ``results`` were not scored on (or on other data)."""
    return [t for t in spec.test_sets if results["tests"].get(t.name, {}).get("data") != eval_key(t)]


def exported_model(spec: RunSpec) -> Path:
    """The ONNX a finished run exported; trains nothing (a command engine's finished commands are not rerun,
    :func:`fuzzyfire.engine.command_train`). Raises :class:`RunError` when it is gone."""
    if spec.engine is not None:
        return command_train(CommandJob(spec.train, Path(spec.train_data.path), spec.out, spec.hash()), spec.engine)
    path = spec.out / "train" / RESULTS_FILE
    name = json.loads(path.read_text(encoding="utf-8")).get("onnx") if path.is_file() else None
    if not name or not (spec.out / "train" / name).is_file():
        raise RunError(f"{spec.out}: its exported model (train/{spec.train.select}.onnx) is gone: nothing to score new "
                       "test sets on")  # fmt: skip
    return spec.out / "train" / name


def score_finished(spec: RunSpec, done: dict[str, Any], which: Sequence[EvalSet], data: RunData | None) -> dict:
    """Score a finished run's model on the test sets ``which`` and add them to its ``results.json``; returns
    the new results (``skipped``: not trained, ``scored``: the names of the sets scored now)."""
    data = run_data(spec) if data is None else data
    tests = score_run(spec, exported_model(spec), data.tests, which)
    results = {**done, "tests": {**done["tests"], **tests}}
    _write_json(spec.out / RESULTS_FILE, results)
    return {**results, "skipped": True, "scored": [t.name for t in which]}


def slug(name: str) -> str:
    """A folder name for a test-set label (``"common (stand-in)"`` -> ``"common_stand-in"``)."""
    kept = "".join(ch if ch.isalnum() or ch in "-." else "_" for ch in name)
    return "_".join(part for part in kept.split("_") if part) or "test"


def execute_run(spec: RunSpec, data: RunData | None = None) -> dict[str, Any]:
    """Run ``spec`` (module docstring) unless it already finished (then only score it on the test sets its
    results lack); returns its ``results.json`` content.
    ``data``: its shared datasets as the experiment prepared them (None: read here)."""
    done = finished(spec)
    if done is not None:
        missing = missing_evals(spec, done)
        return score_finished(spec, done, missing, data) if missing else {**done, "skipped": True}
    data = run_data(spec) if data is None else data
    spec.out.mkdir(parents=True, exist_ok=True)
    _write_json(spec.out / "run.json", spec.record())
    start = time.perf_counter()
    if spec.engine is not None:
        job = CommandJob(spec.train, Path(spec.train_data.path), spec.out, spec.hash())
        model, best = command_train(job, spec.engine), {"engine": spec.engine.name}
    else:
        trained = train_run(spec, data.val)
        if not trained.get("onnx"):
            raise RunError(f"{spec.out}: training produced no {spec.train.select}.onnx (no epoch finished)")
        model, best = spec.out / "train" / trained["onnx"], trained.get("selected", trained["best"])
    trained_at = time.perf_counter()
    tests = score_run(spec, model, data.tests)
    _write_json(spec.out / "timing.json", {"train_s": trained_at - start, "score_s": time.perf_counter() - trained_at})
    results = {
        "hash": spec.hash(),
        "label": spec.label,
        "mixture": spec.mixture,
        "method": spec.method,
        "seed": spec.seed,
        "best": best,
        "tests": tests,
        "spec": spec.record(),
    }
    _write_json(spec.out / RESULTS_FILE, results)
    return {**results, "skipped": False}

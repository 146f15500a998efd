"""One run of the grid: train on a mixture with a seed, then score ``best.onnx`` on every test set.

A run is a pure function of its :class:`RunSpec` (config, mixture, seed and the identities of its data). It
writes into ``spec.out``: ``run.json`` (the spec) first, ``train/`` (the training run folder, resumable from
its ``last.pt``), ``scores/<test set>/`` (metrics.json, predictions.json, matches.npz, pr_curve.png,
errors.json), ``timing.json``
and, last, ``results.json``. A run whose ``results.json`` carries the same identity hash is skipped, so a
rerun does nothing and an interrupted grid resumes. ``results.json`` holds no timings or absolute paths: the
same spec gives byte-identical files.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from curate.core.config import to_dict
from fuzzyfire.engine import command_train
from fuzzyfire.stages import DataRef, digest, load_data

if TYPE_CHECKING:
    from fuzzyfire.engine import EngineConfig
    from fuzzyfire.experiment_config import ScoreConfig
    from train.config import TrainConfig

RESULTS_FILE = "results.json"
METRICS = ("AP", "AP50", "APs", "APm", "APl")


class RunError(RuntimeError):
    """A run that could not finish (its folder and the cause in the message)."""


@dataclass(frozen=True)
class EvalSet:
    name: str  # label in the tables, e.g. "common (stand-in)"
    data: DataRef


@dataclass(frozen=True)
class RunSpec:
    """Everything a run needs. ``method`` is the synthetic pool (None for real-only mixtures); ``engine`` an
    external trainer (:mod:`fuzzyfire.engine`; None = our detector, trained with ``train``)."""

    mixture: str
    method: str | None
    seed: int
    train_data: DataRef  # the mixture folder
    val_data: DataRef
    tests: tuple[EvalSet, ...]
    classes: tuple[str, ...]
    train: TrainConfig  # its seed is replaced by ``seed``
    score: ScoreConfig
    out: Path
    engine: EngineConfig | None = None

    @property
    def label(self) -> str:
        return self.mixture if self.method is None else f"{self.mixture}-{self.method}"

    def identity(self) -> dict[str, Any]:
        engine = {"engine": to_dict(self.engine)} if self.engine is not None else {}
        return {
            **engine,
            "mixture": self.mixture,
            "method": self.method,
            "seed": self.seed,
            "train_data": self.train_data.key(),
            "val_data": self.val_data.key(),
            "tests": {t.name: t.data.key() for t in self.tests},
            "classes": list(self.classes),
            "train": to_dict(replace(self.train, seed=self.seed)),
            "score": to_dict(self.score),
        }

    def hash(self) -> str:
        return digest(self.identity())


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


def train_run(spec: RunSpec) -> dict[str, Any]:
    """Train (or resume) into ``spec.out/train``; returns train's results (best epoch and its metrics)."""
    from train.loop import fit

    train_ds = load_data(spec.train_data, spec.classes)
    val_ds = load_data(spec.val_data, spec.classes)
    return fit(replace(spec.train, seed=spec.seed), train_ds, val_ds, spec.out / "train")


def score_run(spec: RunSpec, model: Path) -> dict[str, dict[str, Any]]:
    """Score ``model`` on every test set; writes ``scores/<name>/``; returns headline metrics per test set."""
    from eval.onnx_model import OnnxDetector
    from eval.predict import PredictOptions
    from eval.score import score, score_errors, write_outputs

    s = spec.score
    detector = OnnxDetector(model, threads=s.threads, device=s.device)
    if detector.device_notice:
        print(detector.device_notice, flush=True)
    options = PredictOptions(s.conf, s.iou, s.max_det, s.batch, s.workers)
    out = {}
    for test in spec.tests:
        result = score(detector, load_data(test.data, spec.classes), options)
        folder = spec.out / "scores" / slug(test.name)
        write_outputs(result, folder)
        score_errors(result).write(folder)
        m = result.metrics
        out[test.name] = {
            **{k: m.summary.get(k) for k in METRICS},
            "images": m.images,
            "boxes": m.boxes,
            "detections": m.detections,
            "per_class": m.per_class,
            "scores": f"scores/{slug(test.name)}",
        }
    return out


def slug(name: str) -> str:
    """A folder name for a test-set label (``"common (stand-in)"`` -> ``"common_stand-in"``)."""
    kept = "".join(ch if ch.isalnum() or ch in "-." else "_" for ch in name)
    return "_".join(part for part in kept.split("_") if part) or "test"


def execute_run(spec: RunSpec) -> dict[str, Any]:
    """Run ``spec`` (module docstring) unless it already finished; returns its ``results.json`` content."""
    done = finished(spec)
    if done is not None:
        return {**done, "skipped": True}
    spec.out.mkdir(parents=True, exist_ok=True)
    _write_json(spec.out / "run.json", {"hash": spec.hash(), "identity": spec.identity()})
    start = time.perf_counter()
    if spec.engine is not None:
        model, best = command_train(spec, spec.engine), {"engine": spec.engine.name}
    else:
        trained = train_run(spec)
        if not trained.get("onnx"):
            raise RunError(f"{spec.out}: training produced no best.onnx (no epoch finished)")
        model, best = spec.out / "train" / trained["onnx"], trained["best"]
    trained_at = time.perf_counter()
    tests = score_run(spec, model)
    _write_json(spec.out / "timing.json", {"train_s": trained_at - start, "score_s": time.perf_counter() - trained_at})
    results = {
        "hash": spec.hash(),
        "label": spec.label,
        "mixture": spec.mixture,
        "method": spec.method,
        "seed": spec.seed,
        "best": best,
        "tests": tests,
    }
    _write_json(spec.out / RESULTS_FILE, results)
    return {**results, "skipped": False}

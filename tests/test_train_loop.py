"""Training loop: run folder contents, determinism for a seed, resume equals an uninterrupted run."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import torch
from factories_train import painted_dataset

import train.loop as loop
from train.config import OptimConfig, TrainConfig

TIMING = ("train_images_per_s", "val_seconds")
CFG = TrainConfig(epochs=2, imgsz=64, batch=8, seed=5, optim=OptimConfig(warmup_min_iters=2, nominal_batch=16))


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory):
    root = tmp_path_factory.mktemp("painted")
    return painted_dataset(root / "train", 16, seed=0), painted_dataset(root / "val", 6, seed=1)


@pytest.fixture(scope="module")
def reference_run(data, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs") / "ref"
    loop.fit(CFG, *data, out)
    return out


def _metrics(run: Path) -> list[dict]:
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    return [{k: v for k, v in r.items() if k not in TIMING} for r in rows]


def _weights(run: Path, name: str = "last.pt") -> dict[str, torch.Tensor]:
    state = torch.load(run / name, map_location="cpu", weights_only=False)
    return {**state["model"], **{f"ema.{k}": v for k, v in state["ema"]["weights"].items()}}


def test_run_folder_is_complete(reference_run: Path) -> None:
    assert {p.name for p in reference_run.iterdir()} >= {
        "last.pt",
        "best.pt",
        "best.onnx",
        "metrics.jsonl",
        "results.json",
    }
    rows = _metrics(reference_run)
    assert [r["epoch"] for r in rows] == [0, 1]
    for r in rows:
        assert {"loss_box", "loss_obj", "loss_cls", "AP", "AP50", "fitness", "lr"} <= set(r)
        assert r["fitness"] == pytest.approx(0.1 * r["AP50"] + 0.9 * r["AP"])
    results = json.loads((reference_run / "results.json").read_text())
    best = max(rows, key=lambda r: r["fitness"])
    assert results["best"]["epoch"] == best["epoch"] and results["class_names"] == ["fire", "smoke"]
    assert results["config"]["seed"] == 5 and results["onnx"] == "best.onnx"


def test_same_seed_same_run(data, reference_run: Path, tmp_path: Path) -> None:
    loop.fit(CFG, *data, tmp_path / "again")
    a, b = _weights(reference_run), _weights(tmp_path / "again")
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    assert _metrics(reference_run) == _metrics(tmp_path / "again")


def test_resume_equals_uninterrupted(data, reference_run: Path, tmp_path: Path, monkeypatch) -> None:
    real_evaluate = loop.evaluate
    calls = {"n": 0}

    def crash_in_second_epoch(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return real_evaluate(*args, **kwargs)

    monkeypatch.setattr(loop, "evaluate", crash_in_second_epoch)
    with pytest.raises(KeyboardInterrupt):
        loop.fit(CFG, *data, tmp_path / "run")
    assert [r["epoch"] for r in _metrics(tmp_path / "run")] == [0]
    monkeypatch.setattr(loop, "evaluate", real_evaluate)
    loop.fit(CFG, *data, tmp_path / "run")
    a, b = _weights(reference_run), _weights(tmp_path / "run")
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert _metrics(reference_run) == _metrics(tmp_path / "run")


def test_resume_refuses_another_config(data, reference_run: Path, tmp_path: Path) -> None:
    shutil.copytree(reference_run, tmp_path / "copy")
    other = TrainConfig(epochs=2, imgsz=64, batch=8, seed=6)
    with pytest.raises(loop.ResumeError, match="another config"):
        loop.fit(other, *data, tmp_path / "copy")

"""Training loop: run folder contents, determinism for a seed, resume equals an uninterrupted run."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import pytest
import torch
from factories_train import painted_dataset

import train.loop as loop
from train.config import DetectorConfig, OptimConfig, TrainConfig

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
    assert [r["epoch"] for r in rows] == [1, 2]  # counted from 1, as the console counts them
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


def _interrupted_then_resumed(cfg: TrainConfig, data, out: Path, monkeypatch, crash_at: int) -> None:
    """``fit`` stopped in validation number ``crash_at`` (1-based), then run again to the end."""
    real_evaluate, calls = loop.evaluate, {"n": 0}

    def crash(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == crash_at:
            raise KeyboardInterrupt
        return real_evaluate(*args, **kwargs)

    monkeypatch.setattr(loop, "evaluate", crash)
    with pytest.raises(KeyboardInterrupt):
        loop.fit(cfg, *data, out)
    assert [r["epoch"] for r in _metrics(out)] == list(range(1, crash_at))
    monkeypatch.setattr(loop, "evaluate", real_evaluate)
    loop.fit(cfg, *data, out)


def test_resume_equals_uninterrupted(data, reference_run: Path, tmp_path: Path, monkeypatch) -> None:
    _interrupted_then_resumed(CFG, data, tmp_path / "run", monkeypatch, crash_at=2)
    a, b = _weights(reference_run), _weights(tmp_path / "run")
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert _metrics(reference_run) == _metrics(tmp_path / "run")


def test_a_run_begun_with_epochs_counted_from_0_resumes_counted_from_1(
    data, reference_run: Path, tmp_path: Path, monkeypatch
) -> None:
    out = tmp_path / "old"
    real_evaluate, calls = loop.evaluate, {"n": 0}

    def crash(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return real_evaluate(*args, **kwargs)

    monkeypatch.setattr(loop, "evaluate", crash)
    with pytest.raises(KeyboardInterrupt):
        loop.fit(CFG, *data, out)
    state = torch.load(out / "last.pt", map_location="cpu", weights_only=False)  # as an older version wrote it
    del state[loop.EPOCHS_FROM]
    state["best"]["epoch"] -= 1
    torch.save(state, out / "last.pt")
    rows = _metrics(out)
    (out / "metrics.jsonl").write_text("".join(json.dumps({**r, "epoch": r["epoch"] - 1}) + "\n" for r in rows))
    monkeypatch.setattr(loop, "evaluate", real_evaluate)
    results = loop.fit(CFG, *data, out)
    assert _metrics(out) == _metrics(reference_run)
    assert results["best"] == json.loads((reference_run / "results.json").read_text())["best"]


def test_select_last_exports_the_last_epochs_weights_without_training_again(
    data, reference_run: Path, tmp_path: Path
) -> None:
    """A finished run resumed with select=last trains nothing and exports last.onnx, whose AP on the validation
    images is the last epoch's (best.onnx stays the best epoch's)."""
    from eval.onnx_model import OnnxDetector
    from eval.score import score

    out = tmp_path / "copy"
    shutil.copytree(reference_run, out)
    results = loop.fit(replace(CFG, select="last"), *data, out)
    last = _metrics(reference_run)[-1]
    assert _metrics(out) == _metrics(reference_run)  # nothing trained again
    assert results["onnx"] == "last.onnx" and results["selected"]["epoch"] == last["epoch"] == CFG.epochs
    scored = score(OnnxDetector(out / "last.onnx"), data[1]).metrics.summary
    assert scored["AP"] == pytest.approx(last["AP"], abs=2e-3) and scored["AP50"] == pytest.approx(
        last["AP50"], abs=2e-3
    )
    assert json.loads((reference_run / "results.json").read_text())["onnx"] == "best.onnx"


def test_resume_refuses_another_config(data, reference_run: Path, tmp_path: Path) -> None:
    shutil.copytree(reference_run, tmp_path / "copy")
    other = TrainConfig(epochs=2, imgsz=64, batch=8, seed=6)
    with pytest.raises(loop.ResumeError, match="another config"):
        loop.fit(other, *data, tmp_path / "copy")


FROZEN = replace(
    CFG,
    epochs=3,
    model=DetectorConfig(backbone="efficientnet-lite0", freeze=3),
    feature_views=2,
    optim=OptimConfig(optimizer="adamw", lr0=0.002, momentum=0.9, warmup_min_iters=2, nominal_batch=16),
)


@pytest.mark.parametrize("cfg", [CFG, FROZEN], ids=["cspdarknet", "lite0-frozen"])
def test_best_epoch_ap_equals_scoring_best_onnx(data, cfg: TrainConfig, tmp_path: Path) -> None:
    """The AP that chose the best epoch is the AP ``fuzzyfire score`` reports for best.onnx on the same images."""
    from eval.onnx_model import OnnxDetector
    from eval.score import score

    results = loop.fit(cfg, *data, tmp_path / "run")
    scored = score(OnnxDetector(tmp_path / "run" / "best.onnx"), data[1]).metrics.summary
    assert results["best"]["AP50"] > 0.0  # something was learnt, so the comparison means something
    assert scored["AP"] == pytest.approx(results["best"]["AP"], abs=2e-3)
    assert scored["AP50"] == pytest.approx(results["best"]["AP50"], abs=2e-3)


def test_frozen_run_is_deterministic_and_keeps_imagenet_weights(data, tmp_path: Path) -> None:
    from curate.effnet import efficientnet_lite0

    loop.fit(FROZEN, *data, tmp_path / "a")
    loop.fit(FROZEN, *data, tmp_path / "b")
    a, b = _weights(tmp_path / "a"), _weights(tmp_path / "b")
    assert all(torch.equal(a[k], b[k]) for k in a) and _metrics(tmp_path / "a") == _metrics(tmp_path / "b")
    reference = efficientnet_lite0().state_dict()
    assert torch.equal(a["backbone.blocks.2._depthwise_conv.weight"], reference["_blocks.2._depthwise_conv.weight"])
    assert not torch.equal(a["backbone.blocks.9._depthwise_conv.weight"], reference["_blocks.9._depthwise_conv.weight"])


def test_mixed_precision_path_runs_and_resumes(data, tmp_path: Path, monkeypatch) -> None:
    """The CUDA path (autocast + gradient scaler) exercised on the CPU: the same code, bfloat16 autocast."""
    monkeypatch.setattr(loop, "uses_amp", lambda device: True)
    cfg = replace(CFG, epochs=1)
    results = loop.fit(cfg, *data, tmp_path / "amp")
    state = torch.load(tmp_path / "amp" / "last.pt", weights_only=False)
    assert state["scaler"] and results["onnx"] == "best.onnx"
    assert all(torch.isfinite(v).all() for v in state["model"].values() if v.is_floating_point())
    again = loop.fit(cfg, *data, tmp_path / "amp")  # resumes from last.pt, scaler state included: nothing to do
    assert again["best"] == results["best"]


def _sourced(ds, synthetic_every: int):
    """``ds`` with every ``synthetic_every``-th image tagged synthetic, the others real (as a mixture tags them)."""
    images = tuple(
        replace(img, source="synth:method2" if k % synthetic_every == 0 else "real:painted")
        for k, img in enumerate(ds.images)
    )
    return replace(ds, images=images)


def test_real_from_is_the_first_real_only_epoch_when_there_are_both_kinds(data, capsys) -> None:
    from train.data import cache_images

    train, _ = data
    mixed, real_only = cache_images(_sourced(train, 2), 64), cache_images(train, 64)
    assert loop.real_from(replace(CFG, epochs=10, real_finetune=3), mixed) == 7
    assert loop.real_from(replace(CFG, epochs=10, real_finetune=0), mixed) is None
    assert loop.real_from(replace(CFG, epochs=10, real_finetune=3), real_only) is None
    assert "no synthetic images" in capsys.readouterr().out
    synthetic_only = cache_images(_sourced(train, 1), 64)
    assert loop.real_from(replace(CFG, epochs=10, real_finetune=3), synthetic_only) is None
    assert "no real images" in capsys.readouterr().out


def test_real_finetune_trains_other_weights(data, reference_run, tmp_path) -> None:
    train, val = data
    tuned = loop.fit(replace(CFG, real_finetune=1), _sourced(train, 2), val, tmp_path / "tuned")
    assert tuned["config"]["real_finetune"] == 1 and len(_metrics(tmp_path / "tuned")) == CFG.epochs
    plain = _weights(reference_run)
    assert any(not torch.equal(v, plain[k]) for k, v in _weights(tmp_path / "tuned").items() if v.is_floating_point())

"""bench/gpu_check.py: on a machine without a GPU every check says it is skipped and why, within seconds;
its pure helpers (loss-curve comparison, verdict) pass what agrees and fail what does not."""

from __future__ import annotations

import importlib.util
import math
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "bench" / "gpu_check.py"
NAMES = ("gpu_train", "gpu_score", "gpu_embed", "gpu_ray")


@pytest.fixture(scope="module")
def gpu_check():
    """The script as a module (nothing runs at import)."""
    spec = importlib.util.spec_from_file_location("bench_gpu_check", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    yield module
    del sys.modules[spec.name]


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(SCRIPT), *args], cwd=REPO, capture_output=True, text=True, timeout=120, check=False
    )


def _skip_lines(stdout: str) -> dict[str, str]:
    """Check name -> the reason of its ``name: skipped (reason)`` line (each name once)."""
    lines = [ln for ln in stdout.splitlines() if ln.split(":")[0] in NAMES]
    found = {ln.split(":")[0]: ln for ln in lines}
    assert len(found) == len(lines), stdout  # one line per check
    reasons = {}
    for name, line in found.items():
        prefix = f"{name}: skipped ("
        assert line.startswith(prefix) and line.endswith(")"), line
        reasons[name] = line[len(prefix) : -1]
    return reasons


def _has_gpu() -> bool:
    import onnxruntime as ort
    import torch

    return torch.cuda.is_available() or "CUDAExecutionProvider" in ort.get_available_providers()


def test_without_gpu_every_check_is_skipped_with_its_reason():
    if _has_gpu():
        pytest.skip("a GPU is here: the script runs its checks (minutes) instead of skipping them")
    result = _run()
    assert result.returncode == 0, result.stderr
    reasons = _skip_lines(result.stdout)
    assert list(reasons) == list(NAMES)
    assert "no CUDA GPU is available" in reasons["gpu_train"] and "torch" in reasons["gpu_train"]
    for name in ("gpu_score", "gpu_embed", "gpu_ray"):
        assert "has no CUDA provider: pip install onnxruntime-gpu" in reasons[name]
    assert result.stdout.splitlines()[-1] == "gpu_check: skipped (no check could run on this machine)"


def test_without_data_every_check_is_skipped(tmp_path):
    """The CPU standing in for the GPU, so that only the missing data stops the checks."""
    result = _run("--device-under-test", "cpu", "--data", str(tmp_path / "none"))
    assert result.returncode == 0, result.stderr
    reasons = _skip_lines(result.stdout)
    assert list(reasons) == list(NAMES)
    assert all(r.startswith(f"{tmp_path / 'none' / 'fire-cctv-416'} not found") for r in reasons.values()), reasons
    assert result.stdout.splitlines()[-1] == "gpu_check: skipped (no check could run on this machine)"


def test_checks_are_the_ones_reported(gpu_check):
    assert gpu_check.CHECKS == NAMES


def _curve(*losses: tuple[float, float, float]) -> list[dict[str, float]]:
    return [
        {"epoch": i + 1, "loss_box": b, "loss_obj": o, "loss_cls": c, "AP": 0.0} for i, (b, o, c) in enumerate(losses)
    ]


def test_curve_gap_within_and_beyond_the_tolerance(gpu_check):
    cpu = _curve((0.10, 0.02, 0.0), (0.08, 0.018, 0.0))
    assert gpu_check.curve_gap(cpu, cpu) == (0.0, 2)
    close = _curve((0.105, 0.02, 0.0), (0.08, 0.0189, 0.0))
    gap, epochs = gpu_check.curve_gap(close, cpu)
    assert epochs == 2 and gap == pytest.approx(0.05 / 1.05) and gap <= gpu_check.LOSS_RTOL
    far = _curve((0.10, 0.02, 0.0), (0.08, 0.018, 0.01))  # cls loss appears on one side only
    assert gpu_check.curve_gap(far, cpu)[0] == 1.0 > gpu_check.LOSS_RTOL
    diverged = _curve((0.10, 0.02, 0.0), (float("nan"), 0.018, 0.0))
    assert gpu_check.curve_gap(diverged, cpu)[0] == math.inf


def test_curve_gap_compares_the_common_prefix(gpu_check):
    cpu = _curve((0.10, 0.02, 0.0))
    longer = _curve((0.10, 0.02, 0.0), (5.0, 5.0, 5.0))
    assert gpu_check.curve_gap(longer, cpu) == (0.0, 1)
    with pytest.raises(ValueError, match="share no epoch"):
        gpu_check.curve_gap(longer, [])
    shifted = [{**row, "epoch": row["epoch"] + 1} for row in cpu]
    with pytest.raises(ValueError, match="number their epochs"):
        gpu_check.curve_gap(shifted, cpu)


def test_small_helpers(gpu_check):
    assert gpu_check.relative_gap(0.0, 0.0) == 0.0
    assert gpu_check.relative_gap(2.0, 1.0) == 0.5
    assert gpu_check.overall_rate([100.0, 50.0]) == pytest.approx(200 / 3)  # equal work at each rate
    with pytest.raises(ValueError):
        gpu_check.overall_rate([])
    assert gpu_check.metric_gap(None, None) == 0.0
    assert gpu_check.metric_gap(0.5, None) == math.inf
    assert gpu_check.metric_gap(0.5, 0.25) == 0.25


def test_skip_reasons_name_every_cause(gpu_check):
    reasons = gpu_check.skip_reasons("no torch GPU", None, None, "--skip-ray")
    assert reasons == {"gpu_train": "no torch GPU", "gpu_score": None, "gpu_embed": None, "gpu_ray": "--skip-ray"}
    reasons = gpu_check.skip_reasons(None, "no ORT GPU", "no data")
    assert reasons["gpu_train"] == "no data" and reasons["gpu_ray"] == "no ORT GPU; no data"


def test_verdict(gpu_check):
    passed, failed = gpu_check.Outcome("passed", "ok"), gpu_check.Outcome("failed", "AP differs")
    skipped = gpu_check.Outcome("skipped", "no GPU")
    assert gpu_check.verdict({"a": passed, "b": failed, "c": skipped}) == ("gpu_check: failed (b)", 1)
    assert gpu_check.verdict({"a": passed, "c": skipped}) == ("gpu_check: passed (a; skipped: c)", 0)
    assert gpu_check.verdict({"c": skipped})[1] == 0
    assert failed.line("gpu_score") == "gpu_score: failed (AP differs)"

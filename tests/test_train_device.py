"""Torch devices: auto picks the CPU on a machine without a GPU; CUDA asked for on such a machine is a one-line
error; an index beyond the GPUs is named."""

from __future__ import annotations

import pytest
import torch

from train.device import DeviceError, resolve_device, uses_amp


def test_cpu_and_auto() -> None:
    assert resolve_device("cpu") == torch.device("cpu") and not uses_amp(torch.device("cpu"))
    expected = torch.device("cuda", 0) if torch.cuda.is_available() else torch.device("cpu")
    assert resolve_device("auto") == expected
    assert uses_amp(torch.device("cuda", 0))


@pytest.mark.skipif(torch.cuda.is_available(), reason="this machine has a GPU")
def test_cuda_without_gpu_is_one_line() -> None:
    with pytest.raises(DeviceError) as info:
        resolve_device("cuda:0")
    assert "no CUDA GPU is available" in str(info.value) and "\n" not in str(info.value)


def test_cuda_index_beyond_the_devices(monkeypatch) -> None:
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 1)
    assert resolve_device("cuda") == torch.device("cuda", 0)
    with pytest.raises(DeviceError, match="has 1 CUDA device"):
        resolve_device("cuda:3")

"""Where training runs: ``auto`` (the first CUDA GPU when torch sees one, else the CPU), ``cpu``, ``cuda`` or
``cuda:N``. One code path for every device: the model, EMA, batches and loss tensors are moved with ``.to``;
mixed precision (float16 autocast with a gradient scaler) is used on CUDA only.

Under Ray a task that reserved a GPU sees it as ``cuda:0`` (Ray sets ``CUDA_VISIBLE_DEVICES``), so ``auto``
picks the GPU a run was given.
"""

from __future__ import annotations

import torch

from ground.run.device import DeviceError, parse_device

__all__ = ["DeviceError", "parse_device", "resolve_device", "uses_amp"]


def resolve_device(spec: str) -> torch.device:
    """The torch device for ``spec`` (see :func:`parse_device`); a CUDA device that is not there raises
    :class:`DeviceError` with a one-line reason."""
    kind, index = parse_device(spec)
    if kind == "cpu":
        return torch.device("cpu")
    available = torch.cuda.is_available()
    if kind == "auto":
        return torch.device("cuda", 0) if available else torch.device("cpu")
    if not available:
        build = "a CPU-only build" if torch.version.cuda is None else f"CUDA {torch.version.cuda}"
        raise DeviceError(f"device {spec!r}: no CUDA GPU is available (torch {torch.__version__}, {build})")
    count = torch.cuda.device_count()
    if index is not None and index >= count:
        raise DeviceError(f"device {spec!r}: this machine has {count} CUDA device(s) (cuda:0..cuda:{count - 1})")
    return torch.device("cuda", index or 0)


def uses_amp(device: torch.device) -> bool:
    """Mixed precision on CUDA only (CPU float16/bfloat16 autocast is slower than float32 here)."""
    return device.type == "cuda"

"""Device strings shared by training (torch) and scoring (onnxruntime): ``auto``, ``cpu``, ``cuda`` or
``cuda:N``. Only the syntax lives here; :mod:`train.device` resolves them for torch, :func:`onnx_providers` for onnxruntime."""

from __future__ import annotations

import re
from collections.abc import Sequence

DEVICE_CHOICES = "auto | cpu | cuda | cuda:N"
_PATTERN = re.compile(r"^(auto|cpu|cuda)(?::(\d+))?$")


class DeviceError(ValueError):
    """A device string we do not understand, or a device this machine does not have."""


def parse_device(spec: str) -> tuple[str, int | None]:
    """``"cuda:1"`` -> ``("cuda", 1)``; ``"auto"`` -> ``("auto", None)``. Raises :class:`DeviceError`."""
    match = _PATTERN.match(spec.strip().lower()) if isinstance(spec, str) else None
    if match is None or (match.group(2) is not None and match.group(1) != "cuda"):
        raise DeviceError(f"device {spec!r}: expected {DEVICE_CHOICES}")
    return match.group(1), None if match.group(2) is None else int(match.group(2))


def onnx_providers(device: str, available: Sequence[str] | None = None) -> tuple[list, str | None]:
    """onnxruntime providers for ``device`` (``auto | cpu | cuda | cuda:N``) and a one-line notice when a GPU
    was asked for but onnxruntime has no CUDA provider here (then the CPU is used). ``auto`` takes CUDA when the
    provider is there (``pip install onnxruntime-gpu``), else the CPU without a word."""
    kind, index = parse_device(device)
    if available is None:
        import onnxruntime as ort

        available = ort.get_available_providers()
    cpu = ["CPUExecutionProvider"]
    if kind == "cpu":
        return cpu, None
    if "CUDAExecutionProvider" in available:
        return [("CUDAExecutionProvider", {"device_id": index or 0}), *cpu], None
    if kind == "auto":
        return cpu, None
    return cpu, "notice: onnxruntime has no CUDA provider here (pip install onnxruntime-gpu); running on the CPU"

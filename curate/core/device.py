"""Device strings shared by training (torch) and scoring (onnxruntime): ``auto``, ``cpu``, ``cuda`` or
``cuda:N``. Only the syntax lives here; :mod:`train.device` and :mod:`eval.onnx_model` resolve them."""

from __future__ import annotations

import re

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

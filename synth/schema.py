"""Helpers for the frozen config dataclasses of synth (``Method1Config``, ``Method2Config``,
``FlameLibraryConfig``): range checks in ``__post_init__`` and plain-JSON copies for manifests."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any


def check_range(name: str, value: tuple[float, ...], low: float | None = None) -> None:
    """Raise ValueError unless ``value`` is ``(lo, hi)`` with ``lo <= hi`` (and ``lo >= low`` when given)."""
    if len(value) != 2 or value[0] > value[1] or (low is not None and value[0] < low):
        bound = f" with lo >= {low}" if low is not None else ""
        raise ValueError(f"{name} must be [lo, hi] with lo <= hi{bound}, got {list(value)}")


def to_json(value: Any) -> Any:
    """Plain JSON data of a config: dataclasses -> dicts, tuples -> lists, paths -> POSIX strings."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_json(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (list, tuple)):
        return [to_json(v) for v in value]
    if isinstance(value, dict):
        return {str(k): to_json(v) for k, v in value.items()}
    if isinstance(value, Path):
        return value.as_posix()
    return value

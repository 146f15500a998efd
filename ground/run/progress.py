"""Progress bars for long loops: shown on a terminal, silent in logs and for short loops."""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import TypeVar

from tqdm import tqdm

T = TypeVar("T")


def progress(
    items: Iterable[T], total: int | None = None, desc: str = "", unit: str = "img", min_items: int = 200
) -> Iterable[T]:
    """Wrap ``items`` in a tqdm bar on stderr when stderr is a terminal and there are ``min_items`` or more."""
    count = total if total is not None else (len(items) if hasattr(items, "__len__") else None)  # type: ignore[arg-type]
    quiet = not sys.stderr.isatty() or (count is not None and count < min_items)
    return tqdm(items, total=count, desc=desc, unit=unit, leave=False, disable=quiet)

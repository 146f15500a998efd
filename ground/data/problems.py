"""A problem found in a user's data: which file, what is wrong, how bad.

Readers and validators never raise on bad data; they return :class:`Problem` records and keep going.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

Level = Literal["error", "warning", "info"]
LEVELS: tuple[Level, ...] = ("error", "warning", "info")


@dataclass(frozen=True)
class Problem:
    """One finding. ``path`` is the file it concerns (label, image or annotation file)."""

    path: str
    reason: str
    level: Level = "error"
    code: str = ""  # machine-readable kind, e.g. "unknown-class:default" ("" when none is needed)

    def __str__(self) -> str:
        return f"{self.path}: {self.reason}"

    def to_dict(self) -> dict[str, str]:
        out = {"path": self.path, "reason": self.reason, "level": self.level}
        return {**out, "code": self.code} if self.code else out


def count_levels(problems: Iterable[Problem]) -> dict[str, int]:
    """Number of problems per level, every level present (0 when none)."""
    counts = Counter(p.level for p in problems)
    return {level: counts.get(level, 0) for level in LEVELS}


def has_errors(problems: Iterable[Problem]) -> bool:
    return any(p.level == "error" for p in problems)

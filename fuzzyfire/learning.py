"""Whether a run learned: a run still learning at its last epoch, or one whose validation AP50 stays under a
floor, is flagged, never read as a result (its row in Table 2 is marked, the answer names it first with the key
that fixes it).

The curve is the run's validation AP50 per epoch (``train/metrics.jsonl``, :mod:`train.loop`). Two rules:

- **still learning**: the best epoch is among the last :func:`tail_epochs` epochs and AP50 rose over them by more
  than :data:`RISE` (a curve that has flattened out, or peaked earlier, is done).
- **below the floor**: the best validation AP50 is under :data:`FLOOR_AP50`. Every run of the shared study reaches
  20-40 AP50 after 40 epochs; a run under 5 has not learned to find the objects (a 5-epoch run on a user's web
  export read 2.7), and its false alarms, recall and differences say nothing about its training data.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from eval.tables import UNLEARNED

LEARNING = UNLEARNED  # the key of a result row: None when the run learned (or had no curve), else its Flag's text
FLOOR_AP50 = 0.05  # validation AP50 (0..1) under which a run has not learned
RISE = 0.005  # AP50 (0..1) gained over the last epochs that counts as still rising
CURVE = "train/metrics.jsonl"  # the curve in a run folder


@dataclass(frozen=True)
class Flag:
    """Why a run's figures are not results: ``kind`` (``still learning`` | ``below the floor``), its epochs, best
    epoch (from 1), validation AP50 (0..1) at the best epoch and ``before`` the last :func:`tail_epochs` (below the
    floor: at the first epoch)."""

    kind: str
    epochs: int
    best_epoch: int
    best: float
    before: float

    def text(self) -> str:
        """``still learning: validation AP50 2.1 at epoch 2 -> 2.7 at epoch 5 of 5`` (points)."""
        if self.kind == "still learning":
            start = self.epochs - tail_epochs(self.epochs)
            return (f"still learning: validation AP50 {100 * self.before:.1f} at epoch {start} -> "
                    f"{100 * self.best:.1f} at epoch {self.best_epoch} of {self.epochs}")  # fmt: skip
        return f"below the floor: best validation AP50 {100 * self.best:.1f} < {100 * FLOOR_AP50:.0f} (epoch {self.best_epoch})"


def tail_epochs(epochs: int) -> int:
    """The last epochs a best epoch counts as late in: 3, or a tenth of a longer training."""
    return min(epochs - 1, max(3, math.ceil(epochs / 10))) if epochs > 1 else 0


def learning_flag(curve: Sequence[Mapping[str, Any]]) -> Flag | None:
    """The :class:`Flag` of a validation curve (rows with ``AP50`` in 0..1, one per epoch, in order), None when
    the run learned or has no curve."""
    ap = [float(r["AP50"]) for r in curve if r.get("AP50") is not None]
    if not ap:
        return None
    n, best = len(ap), int(max(range(len(ap)), key=lambda i: (ap[i], -i)))  # the first best epoch
    if ap[best] < FLOOR_AP50:
        return Flag("below the floor", n, best + 1, ap[best], ap[0])
    tail = tail_epochs(n)
    if tail and best >= n - tail and ap[-1] - ap[n - 1 - tail] > RISE:
        return Flag("still learning", n, best + 1, ap[best], ap[n - 1 - tail])
    return None


def run_flag(run: Path) -> Flag | None:
    """:func:`learning_flag` of a run folder's curve (:data:`CURVE`); None without one (a run trained by another
    engine)."""
    path = Path(run) / CURVE
    if not path.is_file():
        return None
    rows = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
    return learning_flag(rows)

"""A run still learning at its last epoch, or under the AP50 floor, is flagged; a finished curve is not."""

from __future__ import annotations

import json
from pathlib import Path

from fuzzyfire.learning import FLOOR_AP50, learning_flag, run_flag, tail_epochs


def _curve(values: list[float]) -> list[dict]:
    return [{"epoch": i + 1, "AP50": v} for i, v in enumerate(values)]


def test_a_curve_still_rising_at_its_last_epochs_is_flagged() -> None:
    flag = learning_flag(_curve([0.06, 0.10, 0.14, 0.19, 0.27]))  # 5 epochs, best at the last, still rising
    assert flag is not None and flag.kind == "still learning" and flag.best_epoch == 5
    assert flag.text() == "still learning: validation AP50 10.0 at epoch 2 -> 27.0 at epoch 5 of 5"


def test_a_flat_or_early_peaking_curve_is_not() -> None:
    assert learning_flag(_curve([0.1 * min(i, 20) / 20 + 0.2 for i in range(40)])) is None  # flat over the last 4
    assert learning_flag(_curve([0.2, 0.35, 0.3, 0.31, 0.32, 0.33])) is None  # best epoch 2, not among the last 3
    assert learning_flag([]) is None and tail_epochs(1) == 0 and tail_epochs(40) == 4


def test_a_run_under_the_floor_is_flagged_whatever_its_shape() -> None:
    flag = learning_flag(_curve([0.0, 0.01, 0.02, 0.027]))
    assert flag is not None and flag.kind == "below the floor" and flag.best < FLOOR_AP50


def test_the_curve_of_a_run_folder(tmp_path: Path) -> None:
    assert run_flag(tmp_path) is None  # no curve (another engine trained it): nothing said
    (tmp_path / "train").mkdir()
    (tmp_path / "train" / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in _curve([0.3, 0.4, 0.5])))
    assert run_flag(tmp_path).kind == "still learning"  # type: ignore[union-attr]

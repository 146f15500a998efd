"""Figures kept beside a run's predictions are read back only for the same predictions."""

from __future__ import annotations

from pathlib import Path

from fuzzyfire.kept import digest, keep, kept


def test_kept_figures_follow_the_predictions_they_came_from(tmp_path: Path) -> None:
    first, second = b'[{"score": 0.9}]', b'[{"score": 0.8}]'
    path = tmp_path / "figures.json"
    assert kept(path, first) is None
    keep(path, first, {"AP25": 0.5})
    assert kept(path, first) == {"predictions": digest(first), "AP25": 0.5}
    assert kept(path, second) is None and digest(first) != digest(second)

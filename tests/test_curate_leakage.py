"""Leakage between two sets: planted exact and near copies found, nothing else."""

from __future__ import annotations

from pathlib import Path

import pytest
from curate_helpers import save, scene, transformed, use_session_cache

from curate.embed import load_embedder
from curate.leakage import find_leaks, leak_summary
from curate.scan import list_image_files, scan_images
from fuzzyfire.cli import main


@pytest.fixture(scope="module")
def sets(tmp_path_factory: pytest.TempPathFactory) -> Path:
    use_session_cache(tmp_path_factory)
    root = tmp_path_factory.mktemp("leak")
    for i in range(6):
        save(scene(50 + i), root / "train" / f"t{i}.jpg")
    for i in range(3):
        save(scene(60 + i), root / "test" / f"q{i}.jpg")
    (root / "test" / "q_exact.jpg").write_bytes((root / "train" / "t0.jpg").read_bytes())
    save(transformed(scene(51), "crop"), root / "test" / "q_near.jpg")
    return root


def test_planted_leaks_found(sets: Path) -> None:
    emb = load_embedder()
    a = scan_images(list_image_files([sets / "train"]), emb)
    b = scan_images(list_image_files([sets / "test"]), emb)
    leaks = find_leaks(a, b, 0.45)
    assert {(Path(x.a).name, Path(x.b).name, x.kind) for x in leaks} == {
        ("t0.jpg", "q_exact.jpg", "exact"),
        ("t1.jpg", "q_near.jpg", "near"),
    }
    assert leak_summary(a, b, leaks) == {
        "images_a": 6,
        "images_b": 5,
        "pairs": 2,
        "exact_pairs": 1,
        "a_with_leak": 2,
        "b_with_leak": 2,
    }
    assert find_leaks(a, b, 0.0) == [leaks[0]]  # exact copies need no threshold


def test_cli_exit_code_and_json(sets: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "leaks.json"
    assert main(["leakage", str(sets / "train"), str(sets / "test"), "--json", str(out)]) == 1
    assert '"pairs": 2' in out.read_text()
    assert main(["leakage", str(sets / "train"), str(sets / "test"), "--threshold", "0"]) == 1
    (tmp_path / "clean").mkdir()
    save(scene(70), tmp_path / "clean" / "c.jpg")
    assert main(["leakage", str(sets / "train"), str(tmp_path / "clean")]) == 0
    assert "0 duplicate pairs" in capsys.readouterr().out

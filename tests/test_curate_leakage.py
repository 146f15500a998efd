"""Leakage between two sets: planted exact and near copies found, nothing else; near leaks carry float64
two-view distances, the same for every backend."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from curate_helpers import save, scene, transformed, use_session_cache

from curate.embed import l2_normalize, load_embedder
from curate.embedcache import FileFacts
from curate.leakage import find_leaks, leak_summary
from curate.scan import ScannedImage, ScanResult, list_image_files, scan_images
from curate.search import two_view_distances
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


def _vectors_scan(vectors: np.ndarray, crops: np.ndarray, name: str) -> ScanResult:
    images = [
        ScannedImage(f"/{name}/{i:04d}.jpg", FileFacts(f"{name}{i:060x}", 1000, 64, 64, f"{name}p{i}", 1.0))
        for i in range(len(vectors))
    ]
    return ScanResult(images, vectors, crops)


def test_near_leaks_carry_float64_two_view_distances_the_same_for_every_backend() -> None:
    """Planted near copies across two sets of vectors: each leak's distance is the float64 two-view distance,
    the same bits for numpy and faiss; a threshold at a leak's distance leaves it out, the next float takes it."""
    rng = np.random.default_rng(0)
    a = l2_normalize(rng.standard_normal((300, 40)))
    b = l2_normalize(np.concatenate([a[:60] + 0.04 * rng.standard_normal((60, 40)), rng.standard_normal((200, 40))]))
    a_crops, b_crops = (
        l2_normalize(a + 0.1 * rng.standard_normal(a.shape)),
        l2_normalize(b + 0.1 * rng.standard_normal(b.shape)),
    )
    sa, sb = _vectors_scan(a, a_crops, "a"), _vectors_scan(b, b_crops, "b")
    leaks = find_leaks(sa, sb, 0.45, "numpy")
    assert len(leaks) >= 60 and all(x.kind == "near" for x in leaks)
    assert find_leaks(sa, sb, 0.45, "flat") == leaks
    ia = np.array([int(Path(x.a).stem) for x in leaks])
    ib = np.array([int(Path(x.b).stem) for x in leaks])
    assert [x.distance for x in leaks] == two_view_distances(a, a_crops, b, b_crops, ia, ib).tolist()
    edge = leaks[len(leaks) // 2]
    assert edge not in find_leaks(sa, sb, edge.distance, "flat")
    assert edge in find_leaks(sa, sb, float(np.nextafter(edge.distance, 3.0)), "flat")

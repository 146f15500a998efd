"""Scanning files: hashes, facts, embeddings in input order, cache hits on rerun, bad files reported."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
from curate_helpers import save, scene
from factories import garbled_jpeg

from curate.embed import OnnxEmbedder
from curate.embedcache import EmbeddingCache
from curate.scan import bounded_map, list_image_files, scan_images


@pytest.fixture()
def folder(tmp_path: Path) -> Path:
    root = tmp_path / "imgs"
    for i in range(5):
        save(scene(i), root / f"s{i}.jpg")
    save(scene(1), root / "nested" / "s1.png")  # same scene as s1.jpg, other encoding
    (root / "broken.jpg").write_bytes(b"\xff\xd8\xff\xe0 not really a jpeg")
    (root / "garbled.jpg").write_bytes(garbled_jpeg())  # decodes grey in OpenCV, with only a warning on stderr
    (root / "empty.png").write_bytes(b"")
    (root / "notes.txt").write_text("not an image")
    return root


def test_scan_reports_bad_files_and_keeps_going(folder: Path, embedder: OnnxEmbedder, tmp_path: Path) -> None:
    paths = list_image_files([folder])
    assert [p.name for p in paths] == [
        "broken.jpg",
        "empty.png",
        "garbled.jpg",
        "s1.png",
        "s0.jpg",
        "s1.jpg",
        "s2.jpg",
        "s3.jpg",
        "s4.jpg",
    ]
    before = {p: p.read_bytes() for p in paths}
    with EmbeddingCache(tmp_path / "c.sqlite") as cache:
        result = scan_images(paths, embedder, cache, batch_size=4)
    assert sorted(Path(p.path).name for p in result.problems) == ["broken.jpg", "empty.png", "garbled.jpg"]
    assert "corrupt JPEG data" in next(p.reason for p in result.problems if p.path.endswith("garbled.jpg"))
    assert [Path(im.path).name for im in result.images] == ["s1.png", "s0.jpg", "s1.jpg", "s2.jpg", "s3.jpg", "s4.jpg"]
    assert result.vectors.shape == result.crops.shape == (6, 320)
    np.testing.assert_allclose(np.linalg.norm(result.vectors, axis=1), 1.0, rtol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(result.crops, axis=1), 1.0, rtol=1e-5)
    assert not np.allclose(result.vectors, result.crops)
    s0 = result.images[1]
    assert s0.facts.sha256 == hashlib.sha256((folder / "s0.jpg").read_bytes()).hexdigest()
    assert (s0.facts.width, s0.facts.height) == (160, 120) and s0.facts.sharpness > 0
    assert before == {p: p.read_bytes() for p in paths}  # originals untouched


def test_rerun_hits_cache_with_identical_vectors(folder: Path, embedder: OnnxEmbedder, tmp_path: Path) -> None:
    paths = list_image_files([folder])
    with EmbeddingCache(tmp_path / "c.sqlite") as cache:
        first = scan_images(paths, embedder, cache)
    with EmbeddingCache(tmp_path / "c.sqlite") as cache:
        second = scan_images(list(reversed(paths)), embedder, cache)
    assert first.cached == 0 and second.cached == 6
    index = {im.path: i for i, im in enumerate(first.images)}
    assert [im.path for im in second.images] == [im.path for im in reversed(first.images)]
    np.testing.assert_array_equal(second.vectors, first.vectors[[index[im.path] for im in second.images]])
    np.testing.assert_array_equal(second.crops, first.crops[[index[im.path] for im in second.images]])


def test_a_garbled_jpeg_cached_by_an_older_reader_is_still_refused(
    folder: Path, embedder: OnnxEmbedder, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import ground.image.imageio as imageio

    paths = [folder / "garbled.jpg", folder / "s0.jpg"]
    with monkeypatch.context() as older:  # a reader without the scan-data check caches the grey decode
        older.setattr(imageio, "_check_scan_data", lambda *args: None)
        with EmbeddingCache(tmp_path / "c.sqlite") as cache:
            assert len(scan_images(paths, embedder, cache).images) == 2
    with EmbeddingCache(tmp_path / "c.sqlite") as cache:
        again = scan_images(paths, embedder, cache)
    assert [Path(im.path).name for im in again.images] == ["s0.jpg"] and again.cached == 1
    assert [(Path(p.path).name, p.reason.split(" (")[0]) for p in again.problems] == [
        ("garbled.jpg", "corrupt JPEG data")
    ]


def test_bounded_map_keeps_order() -> None:
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(3) as pool:
        assert list(bounded_map(lambda x: x * x, list(range(50)), pool, ahead=4)) == [x * x for x in range(50)]


def test_big_jpegs_decode_reduced_with_the_same_near_duplicates(embedder: OnnxEmbedder, tmp_path: Path) -> None:
    """Photos decoded at 1/4 (DCT scaling) embed within tolerance of the full decode and give the same
    near-duplicate pairs; facts keep the full size."""
    import cv2

    from ground.image.imageio import read_image

    def pairs(v: np.ndarray, threshold: float) -> set[tuple[int, int]]:
        d = np.linalg.norm(v[:, None] - v[None], axis=2)
        return {(i, j) for i in range(len(v)) for j in range(i + 1, len(v)) if d[i, j] < threshold}

    paths = []
    for i in range(4):
        big = cv2.resize(scene(i), (1600, 1200), interpolation=cv2.INTER_CUBIC)
        paths.append(save(big, tmp_path / f"p{i}.jpg"))
        shifted = np.roll(big, 12, axis=1)  # a near duplicate: the same picture moved a little
        paths.append(save(shifted, tmp_path / f"p{i}_moved.jpg"))
    result = scan_images(paths, embedder)
    assert all((im.facts.width, im.facts.height) == (1600, 1200) for im in result.images)
    full = np.stack([embedder.embed(embedder.preprocess.views(read_image(p)))[0] for p in paths])
    full /= np.linalg.norm(full, axis=1, keepdims=True)
    cosine = np.sum(full * result.vectors, axis=1)
    assert cosine.min() > 0.995, cosine  # reduced vs full decode
    for threshold in (0.3, 0.45, 0.6):
        assert pairs(result.vectors, threshold) == pairs(full, threshold)
    assert pairs(full, 0.45) >= {(0, 1), (2, 3), (4, 5), (6, 7)}  # the moved copies are found

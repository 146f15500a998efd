"""Dedup finds the planted duplicates (as sets of file names), in any input order, with the keeper policy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from curate_helpers import save, scene, transformed
from PIL import Image

from curate.dedup import UnionFind, find_duplicates
from curate.embed import OnnxEmbedder
from curate.scan import ScanResult, list_image_files, scan_images

#: (removed, kept) for every planted copy; resolution, then file size, then path decide who stays.
ORDERED = {
    ("s1_crop.jpg", "s1.jpg"),  # largest resolution stays
    ("s2_resize.jpg", "s2.jpg"),
    ("s4.jpg", "s4_bytes.jpg"),  # byte-identical: path order, ".../copies/..." < ".../s4.jpg"
    ("s5_pixels.png", "s5.png"),  # same pixels: the larger file (less compressed PNG) stays
}
UNORDERED = {frozenset({"s0.jpg", "s0_hflip.jpg"}), frozenset({"s3.jpg", "s3_bright.jpg"})}


@pytest.fixture(scope="module")
def planted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """10 distinct scenes (s5 as PNG), 4 near copies, a byte copy and a pixel copy, in copies/."""
    root = tmp_path_factory.mktemp("planted")
    for i in range(10):
        if i != 5:
            save(scene(i), root / f"s{i}.jpg")
    for i, kind in enumerate(("hflip", "crop", "resize", "bright")):
        save(transformed(scene(i), kind), root / "copies" / f"s{i}_{kind}.jpg", quality=85)
    (root / "copies" / "s4_bytes.jpg").write_bytes((root / "s4.jpg").read_bytes())
    Image.fromarray(scene(5)).save(root / "s5.png", compress_level=0)
    Image.fromarray(scene(5)).save(root / "copies" / "s5_pixels.png", compress_level=9)
    return root


def _scan(folder: Path, embedder: OnnxEmbedder, shuffle_seed: int | None = None) -> ScanResult:
    paths = list_image_files([folder])
    if shuffle_seed is not None:
        paths = [paths[i] for i in np.random.default_rng(shuffle_seed).permutation(len(paths))]
    return scan_images(paths, embedder, cache=None)


def _name(scan: ScanResult, i: int) -> str:
    return Path(scan.images[i].path).name


def _outcome(scan: ScanResult, result) -> tuple[set, set, set]:
    removed = {(_name(scan, r.index), _name(scan, r.duplicate_of), r.kind) for r in result.removed}
    kept = {_name(scan, i) for i in result.kept}
    groups = {frozenset(_name(scan, i) for i in g) for g in result.groups}
    return removed, kept, groups


def test_finds_planted_pairs_with_keeper_policy(planted: Path, embedder: OnnxEmbedder) -> None:
    scan = _scan(planted, embedder)
    removed, kept, groups = _outcome(scan, find_duplicates(scan.images, scan.vectors, crops=scan.crops))
    assert {frozenset(r[:2]) for r in removed} == {frozenset(p) for p in ORDERED} | UNORDERED
    assert ORDERED <= {r[:2] for r in removed}
    kinds = {r[0]: r[2] for r in removed}
    assert kinds["s4.jpg"] == kinds["s5_pixels.png"] == "exact" and kinds["s1_crop.jpg"] == "near"
    assert len(kept) == 10 and groups == {frozenset(p) for p in ORDERED} | UNORDERED


def test_same_result_for_any_input_order(planted: Path, embedder: OnnxEmbedder) -> None:
    scan = _scan(planted, embedder)
    reference = _outcome(scan, find_duplicates(scan.images, scan.vectors, crops=scan.crops))
    for seed in (1, 2):
        shuffled = _scan(planted, embedder, shuffle_seed=seed)
        assert _outcome(shuffled, find_duplicates(shuffled.images, shuffled.vectors, crops=shuffled.crops)) == reference


def test_exact_only_and_protect(planted: Path, embedder: OnnxEmbedder) -> None:
    scan = _scan(planted, embedder)
    removed, _, _ = _outcome(scan, find_duplicates(scan.images, None, near=False))
    assert {r[0] for r in removed} == {"s4.jpg", "s5_pixels.png"}
    removed, kept, _ = _outcome(
        scan, find_duplicates(scan.images, scan.vectors, protect=[planted / "copies"], crops=scan.crops)
    )
    assert {r[0] for r in removed} == {"s0.jpg", "s1.jpg", "s2.jpg", "s3.jpg", "s4.jpg", "s5.png"}
    assert {"s0_hflip.jpg", "s1_crop.jpg", "s2_resize.jpg", "s3_bright.jpg", "s4_bytes.jpg", "s5_pixels.png"} <= kept


def test_threshold_bounds(planted: Path, embedder: OnnxEmbedder) -> None:
    scan = _scan(planted, embedder)
    with pytest.raises(ValueError, match="0..2"):
        find_duplicates(scan.images, scan.vectors, threshold=3.0)
    none = find_duplicates(scan.images, scan.vectors, threshold=0.0)
    assert all(r.kind == "exact" for r in none.removed)


def test_chains_are_not_collapsed() -> None:
    """a~b~c with a and c apart: greedy keeper keeps a and c (b removed as duplicate of the nearer)."""
    from curate.dedup import greedy_keep
    from curate.search import Pairs

    pairs = Pairs(np.array([0, 1]), np.array([1, 2]), np.array([0.3, 0.2], np.float32))
    removed = greedy_keep(3, pairs, [0, 2, 1], [True] * 3, [False] * 3)
    assert [(r.index, r.duplicate_of) for r in removed] == [(1, 2)]


def test_union_find_components() -> None:
    uf = UnionFind(6)
    uf.union(4, 1)
    uf.union(1, 3)
    uf.union(5, 0)
    assert uf.components() == [[0, 5], [1, 3, 4], [2]]


def test_near_ties_are_decided_by_keeper_order_not_float_bits() -> None:
    """Image 2 duplicates kept images 0 and 1 at distances that differ by float noise (3e-6, inside one
    DISTANCE_GRID cell): it names the earlier keeper, whichever float is smaller."""
    from curate.dedup import greedy_keep
    from curate.search import Pairs

    for eps in (3e-6, -3e-6):
        pairs = Pairs(np.array([0, 1]), np.array([2, 2]), np.array([0.30005, 0.30005 + eps], np.float32))
        removed = greedy_keep(3, pairs, [1, 0, 2], [True] * 3, [False] * 3)
        assert [(r.index, r.duplicate_of) for r in removed] == [(2, 1)]
    far = Pairs(np.array([0, 1]), np.array([2, 2]), np.array([0.3001, 0.3004], np.float32))  # other cells
    assert greedy_keep(3, far, [1, 0, 2], [True] * 3, [False] * 3)[0].duplicate_of == 0


def test_keeper_order_breaks_sharpness_noise_by_content() -> None:
    from curate.dedup import keeper_order
    from curate.embedcache import FileFacts
    from curate.scan import ScannedImage

    def image(path: str, sha: str, sharpness: float) -> ScannedImage:
        return ScannedImage(path, FileFacts(sha, 1000, 64, 48, sha, sharpness))

    for noise in (1e-12, -1e-12):  # the summation order of another CPU
        images = [image("/a.jpg", "f" * 64, 123.456789), image("/b.jpg", "0" * 64, 123.456789 + noise)]
        assert keeper_order(images, [False, False]) == [1, 0]  # content decides, not the last float bit
    sharper = [image("/a.jpg", "f" * 64, 123.5), image("/b.jpg", "0" * 64, 123.4)]
    assert keeper_order(sharper, [False, False]) == [0, 1]

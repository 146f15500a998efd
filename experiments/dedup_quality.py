"""Dedup quality on a ground truth built from real images (../shared/data): 100 source images, each with
7 known copies (hflip, 80 % crop, 50 % resize, JPEG q30, gaussian noise sigma 10, +-30 % brightness, 5 degree
rotation), plus 200 distinct distractors. Sources and distractors are picked far apart in raw pixel space
(k-center on 32 x 32 thumbnails, independent of both methods). Reports pair precision, recall and F1 of the
duplicate groups and throughput, for our embeddings and for a 64-bit perceptual-hash baseline (DCT pHash,
Hamming <= 10, imagededup's default) run in the same process.

.venv/bin/python experiments/dedup_quality.py [DATA_DIR] [SEED]   # goal: pair F1 >= 0.95
(the default threshold was chosen on seed 0; other seeds pick other images: a held-out check)
"""

from __future__ import annotations

import itertools
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from curate.calibrate import _bright, _jpeg, _noise, _resize, _rotate, centre_crop, hflip
from curate.dedup import DEFAULT_THRESHOLD, UnionFind, find_duplicates
from curate.embed import load_embedder
from curate.rank import k_center
from curate.scan import list_image_files, scan_images
from ground.image.imageio import read_image

DEFAULT = Path(__file__).resolve().parents[1].parent / "shared" / "data"
SOURCES, DISTRACTORS = 100, 200
TRANSFORMS = ("hflip", "crop80", "resize50", "jpeg30", "noise10", "bright30", "rotate5")


def transform(img: np.ndarray, kind: str, k: int, rng: np.random.Generator) -> np.ndarray:
    if kind == "hflip":
        return hflip(img)
    if kind == "crop80":
        return centre_crop(img, 10)
    if kind == "resize50":
        return _resize(img, 0.5)
    if kind == "jpeg30":
        return _jpeg(img, 30)
    if kind == "noise10":
        return _noise(img, rng, 10.0)
    if kind == "bright30":
        return _bright(img, 1.3 if k % 2 == 0 else 0.7)
    return _rotate(img, 5.0)


def pick_distinct(paths: list[Path], n: int, rng: np.random.Generator) -> list[Path]:
    thumbs = np.stack([cv2.resize(read_image(p), (32, 32), interpolation=cv2.INTER_AREA) for p in paths])
    x = thumbs.reshape(len(paths), -1).astype(np.float32) / 255.0
    return [paths[i] for i in k_center(x, n, int(rng.integers(len(paths))))]


def build_benchmark(data: Path, out: Path, rng: np.random.Generator) -> list[set[str]]:
    """Write the images into ``out``; returns the families (sets of file names that are duplicates)."""
    pool = list_image_files([data / "fire-cctv-416", data / "fire-smoke-608"])
    chosen = pick_distinct(pool, SOURCES + DISTRACTORS, rng)
    families = []
    for k, path in enumerate(chosen):
        (out / f"s{k:03d}_orig{path.suffix}").write_bytes(path.read_bytes())
        if k >= SOURCES:
            continue
        img = read_image(path)
        names = {f"s{k:03d}_orig{path.suffix}"}
        for kind in TRANSFORMS:
            name = f"s{k:03d}_{kind}.png" if kind == "jpeg30" else f"s{k:03d}_{kind}.jpg"
            copy = transform(img, kind, k, rng)
            params = [cv2.IMWRITE_JPEG_QUALITY, 95] if name.endswith(".jpg") else []
            cv2.imwrite(str(out / name), copy[:, :, ::-1], params)
            names.add(name)
        families.append(names)
    return families


def phash(img: np.ndarray) -> int:
    """64-bit DCT perceptual hash: 32 x 32 grey, top-left 8 x 8 DCT block (DC dropped) against its median."""
    grey = cv2.resize(cv2.cvtColor(img, cv2.COLOR_RGB2GRAY), (32, 32), interpolation=cv2.INTER_AREA)
    block = cv2.dct(grey.astype(np.float32))[:8, :8].ravel()
    bits = block > np.median(block[1:])
    return int("".join("1" if b else "0" for b in bits), 2)


def groups_to_pairs(groups: list[list[str]]) -> set[frozenset[str]]:
    return {frozenset(p) for g in groups for p in itertools.combinations(sorted(g), 2)}


def scores(pred: set[frozenset[str]], truth: set[frozenset[str]]) -> tuple[float, float, float]:
    tp = len(pred & truth)
    p = tp / len(pred) if pred else 1.0
    r = tp / len(truth) if truth else 1.0
    return p, r, 2 * p * r / (p + r) if p + r else 0.0


def run_phash(paths: list[Path], max_distance: int = 10) -> list[list[str]]:
    hashes = np.array([phash(read_image(p)) for p in paths], dtype=np.uint64)
    uf = UnionFind(len(paths))
    for i in range(len(paths)):
        x = np.bitwise_xor(hashes[i + 1 :], hashes[i])
        dist = np.unpackbits(x.view(np.uint8).reshape(-1, 8), axis=1).sum(axis=1)
        for j in np.nonzero(dist <= max_distance)[0]:
            uf.union(i, i + 1 + int(j))
    return [[paths[i].name for i in g] for g in uf.components() if len(g) > 1]


def main() -> int:
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT
    if not (data / "fire-cctv-416").is_dir():
        print(f"dedup_quality_skipped: {data} not found", file=sys.stderr)
        return 0
    rng = np.random.default_rng(int(sys.argv[2]) if len(sys.argv) > 2 else 0)
    with tempfile.TemporaryDirectory() as tmp:
        families = build_benchmark(data, Path(tmp), rng)
        truth = groups_to_pairs([sorted(f) for f in families])
        paths = list_image_files([tmp])
        embedder = load_embedder()
        start = time.perf_counter()
        scan = scan_images(paths, embedder, cache=None)
        ours_s = time.perf_counter() - start
        for t in (0.35, DEFAULT_THRESHOLD, 0.55):
            t0 = time.perf_counter()
            result = find_duplicates(scan.images, scan.vectors, t, crops=scan.crops)
            seconds = ours_s + time.perf_counter() - t0
            pred = groups_to_pairs([[Path(scan.images[i].path).name for i in g] for g in result.groups])
            p, r, f1 = scores(pred, truth)
            tag = "" if t != DEFAULT_THRESHOLD else " (default threshold)"
            print(f"dedup_quality_embed_t{t:.2f}: precision {p:.3f} recall {r:.3f} F1 {f1:.3f}{tag}")
        print(f"dedup_quality_embed_throughput: {len(paths) / seconds:.0f} img/s ({len(paths)} images)")
        start = time.perf_counter()
        groups = run_phash(paths)
        ph_s = time.perf_counter() - start
        p, r, f1 = scores(groups_to_pairs(groups), truth)
        print(f"dedup_quality_phash: precision {p:.3f} recall {r:.3f} F1 {f1:.3f} (Hamming <= 10)")
        print(f"dedup_quality_phash_throughput: {len(paths) / ph_s:.0f} img/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

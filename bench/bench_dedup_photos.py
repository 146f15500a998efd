"""``fuzzyfire dedup`` on ordinary multi-megapixel photos against the same pictures as 416-px frames.

Makes two folders from the first ``--n`` training frames of ../shared/data/fire-cctv-416: ``frames/`` (the
416x416 JPEGs as they are) and ``photos/`` (each upscaled to 1-12 MP, 4:3 / 3:4 / 16:9, JPEG quality 92, as a
phone or web photo), plus one 16000x16000 PNG in ``photos/`` (a decompression bomb for a naive reader). Then
runs ``fuzzyfire dedup`` cold (empty cache) on each, every run in its own process.

Prints: throughput on each folder (target >= 100 img/s on photos), their ratio (target >= 0.7), each run's
peak RSS (target <= 2 GB), and how well the duplicate groups found on the photos agree with those found on the
frames (same pictures: reduced decoding and upscaling must not change what is a duplicate).

.venv/bin/python bench/bench_dedup_photos.py [--n 600] [--keep DIR]
Figures depend on the machine and on other load: take them on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
SOURCE = REPO.parent / "shared" / "data" / "fire-cctv-416" / "train" / "images"
CHILD = (
    "import resource, sys; from fuzzyfire.cli import main; code = main(sys.argv[1:]); "
    "print('maxrss_kb', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr); sys.exit(code)"
)
ASPECTS = (4 / 3, 3 / 4, 16 / 9)


def make_folders(n: int, root: Path, rng: np.random.Generator) -> tuple[Path, Path, float]:
    """``root/frames`` and ``root/photos`` (module docstring); returns them and the photos' mean megapixels."""
    frames, photos = root / "frames", root / "photos"
    frames.mkdir(parents=True)
    photos.mkdir()
    megapixels = []
    for src in sorted(SOURCE.glob("*.jpg"))[:n]:
        (frames / src.name).write_bytes(src.read_bytes())
        image = cv2.imread(str(src))
        mp, aspect = rng.uniform(1.0, 12.0), ASPECTS[int(rng.integers(len(ASPECTS)))]
        w = int(round(np.sqrt(mp * 1e6 * aspect)))
        h = int(round(w / aspect))
        big = cv2.resize(image, (w, h), interpolation=cv2.INTER_CUBIC)
        cv2.imwrite(str(photos / src.name), big, [cv2.IMWRITE_JPEG_QUALITY, 92])
        megapixels.append(w * h / 1e6)
    write_big_png(photos / "zz_huge_16000.png", 16000, 16000)
    return frames, photos, float(np.mean(megapixels))


def write_big_png(path: Path, width: int, height: int) -> None:
    """An RGB PNG of a horizontal gradient, written row by row (never the whole image in memory)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    row = b"\0" + np.repeat(np.linspace(0, 255, width).astype(np.uint8), 3).tobytes()  # filter byte + pixels
    comp = zlib.compressobj(6)
    body = b"".join(comp.compress(row) for _ in range(height)) + comp.flush()
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", body) + chunk(b"IEND", b""))


def dedup(folder: Path, out: Path, env: dict[str, str]) -> tuple[float, float, dict]:
    """(seconds, peak RSS MB, dedup.json) of one cold ``fuzzyfire dedup`` in its own process."""
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, "dedup", str(folder), "--out", str(out)],
        env=env,
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    seconds = time.perf_counter() - start
    rss_kb = next(int(line.split()[1]) for line in proc.stderr.splitlines()[::-1] if line.startswith("maxrss_kb"))
    return seconds, rss_kb / 1024, json.loads((out / "dedup.json").read_text())


def same_group_pairs(doc: dict) -> set[tuple[str, str]]:
    """Unordered pairs of file names that dedup put in one duplicate group (each removed image with the copy it
    was removed for, transitively): which copy is kept depends on resolution, which differs between the photos,
    so the groups are compared, not the (removed, kept) pairs."""
    parent: dict[str, str] = {}

    def find(x: str) -> str:
        while parent.setdefault(x, x) != x:
            x = parent[x]
        return x

    for r in doc["removed"]:
        parent[find(Path(r["path"]).name)] = find(Path(r["duplicate_of"]).name)
    groups: dict[str, list[str]] = {}
    for name in list(parent):
        groups.setdefault(find(name), []).append(name)
    return {(a, b) for g in groups.values() for a in g for b in g if a < b}


def reduced_vs_full(photos: Path, count: int) -> tuple[float, int, int, int]:
    """On the first ``count`` photos: the smallest cosine between an embedding from the reduced decode (as dedup
    makes it) and one from the full decode, and the near-duplicate pairs (distance < 0.45) each way and in both."""
    from curate.embed import l2_normalize, load_embedder
    from curate.scan import scan_images
    from ground.image.imageio import read_image

    paths = sorted(photos.glob("*.jpg"))[:count]
    embedder = load_embedder()
    reduced = scan_images(paths, embedder).vectors
    full = l2_normalize(np.stack([embedder.embed(embedder.preprocess.views(read_image(p)))[0] for p in paths]))

    def pairs(v: np.ndarray) -> set[tuple[int, int]]:
        d = np.sqrt(np.maximum(2.0 - 2.0 * v @ v.T, 0.0))
        i, j = np.nonzero(np.triu(d < 0.45, k=1))
        return set(zip(i.tolist(), j.tolist()))

    a, b = pairs(reduced), pairs(full)
    return float(np.sum(reduced * full, axis=1).min()), len(a), len(b), len(a & b)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=600, help="pictures (default 600)")
    parser.add_argument("--keep", type=Path, help="make the folders here and keep them (default: a temp folder)")
    args = parser.parse_args()
    if not SOURCE.is_dir():
        print(f"dedup_photos_skipped: {SOURCE} not found", file=sys.stderr)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        root = args.keep or Path(tmp)
        env = {**os.environ, "FUZZYFIRE_CACHE": str(Path(tmp) / "cache")}
        subprocess.run(
            [sys.executable, "-c", "from curate.embed import builtin_model_path; builtin_model_path()"],
            env=env,
            check=True,
        )
        start = time.perf_counter()
        frames, photos, mean_mp = make_folders(args.n, root / "data", np.random.default_rng(0))
        make_s = time.perf_counter() - start
        # one cache, the model exported into it beforehand (timed apart, once per install); frames and photos differ
        # in content, so neither run finds the other's embeddings: both are cold
        f_s, f_rss, f_doc = dedup(frames, root / "out-frames", env)
        p_s, p_rss, p_doc = dedup(photos, root / "out-photos", env)
        n_sample = min(150, args.n)
        cosine, n_reduced, n_full, n_both = reduced_vs_full(photos, n_sample)
    n = args.n
    huge = [p["reason"] for p in p_doc["problems"] if "zz_huge" in p["path"]]
    a, b = same_group_pairs(f_doc), same_group_pairs(p_doc)
    print(f"dedup_photos_folder_made: {make_s:.0f} s ({n} photos, mean {mean_mp:.1f} MP, + one 16000x16000 PNG)")
    print(f"dedup_frames416_throughput: {n / f_s:.0f} img/s ({f_s:.1f} s)")
    print(f"dedup_photos_throughput: {n / p_s:.0f} img/s ({p_s:.1f} s; target >= 100)")
    print(f"dedup_photos_vs_frames: {(n / p_s) / (n / f_s):.2f} ratio (target >= 0.7)")
    print(f"dedup_frames416_peak_rss: {f_rss:.0f} MB")
    print(f"dedup_photos_peak_rss: {p_rss:.0f} MB (target <= 2048)")
    print(f"dedup_photos_removed: {len(p_doc['removed'])} images (frames: {len(f_doc['removed'])})")
    print(f"dedup_photos_same_group_pairs: {len(b)} pairs (frames: {len(a)}; in both {len(a & b)})")
    print(f"dedup_photos_groups_jaccard: {len(a & b) / max(len(a | b), 1):.3f} ratio (1 = the same groups)")
    print(f"dedup_photos_reduced_vs_full_min_cosine: {cosine:.4f} ({n_sample} photos, 1/r decode vs full decode)")
    print(f"dedup_photos_reduced_vs_full_pairs: {n_reduced} pairs reduced, {n_full} full, {n_both} in both")
    print(f"dedup_photos_huge_png: {huge[0] if huge else 'not reported'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

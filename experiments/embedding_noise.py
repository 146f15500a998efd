"""How far the dedup embeddings move between runs that should agree: the noise a decision must not hang on.

Embeds the same images (both views, :func:`curate.decode.decode_facts`) with the built-in Lite0 ONNX model
under settings that a different machine or build would change, and prints, per setting, the largest change of
the two-view distance over every pair closer than 0.7 (the decision region of dedup at 0.45 and of the split
groups at 0.6) and of any unit-vector component:

- ``threads2``: onnxruntime with 2 intra-op threads (the reference uses 1);
- ``batch1``: one image per call (the reference: 4);
- ``noopt``: onnxruntime's graph optimisations off (other kernels and fusions, like another build);
- ``torch``: the same weights run by torch eager (another implementation of every operator);
- ``torch_avx2``: the same in a process limited to AVX2 kernels (``ATEN_CPU_CAPABILITY=avx2``,
  ``ONEDNN_MAX_CPU_ISA=AVX2``), as on an older CPU.

Then, on the whole folder curated as ``configs/shared-data.yaml`` does it (dedup 0.45, split groups 0.6, seed 0),
how many kept images and split assignments change when every unit embedding is moved by Gaussian noise of
sigma 1e-5 .. 3e-4 per component (3 draws each; the worst draw is printed), and how close the nearest pair
distance lies to each threshold.

.venv/bin/python experiments/embedding_noise.py [FOLDER] [--n 400]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DEFAULT = REPO.parent / "shared" / "data" / "fire-cctv-416"
DECISION_REGION = 0.7


def views(paths: list[Path]) -> np.ndarray:
    """(2 N, S, S, 3) uint8: whole and centre view of each image, as dedup feeds the model."""
    from curate.decode import decode_facts
    from curate.embed import LITE0_PREPROCESS

    return np.concatenate([decode_facts(p, LITE0_PREPROCESS)[1] for p in paths])


def onnx_vectors(batch: np.ndarray, threads: int = 1, per_call: int = 8, optimise: bool = True) -> np.ndarray:
    """(2 N, D) raw embeddings by onnxruntime, ``per_call`` views per run."""
    import onnxruntime as ort

    from curate.embed import LITE0_PREPROCESS, builtin_model_path

    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    if not optimise:
        opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_DISABLE_ALL
    session = ort.InferenceSession(str(builtin_model_path()), opts, providers=["CPUExecutionProvider"])
    out = []
    for s in range(0, len(batch), per_call):
        x = LITE0_PREPROCESS.normalize(batch[s : s + per_call])
        out.append(session.run(["embedding"], {"input": x})[0])
    return np.concatenate(out).astype(np.float32)


def torch_vectors(batch: np.ndarray) -> np.ndarray:
    """(2 N, D) raw embeddings by torch eager with the same weights."""
    import torch

    from curate.effnet import efficientnet_lite0
    from curate.embed import LITE0_PREPROCESS

    net = efficientnet_lite0(image_size=LITE0_PREPROCESS.size)
    with torch.no_grad():
        return np.concatenate(
            [
                net(torch.from_numpy(LITE0_PREPROCESS.normalize(batch[s : s + 8])))[0].numpy()
                for s in range(0, len(batch), 8)
            ]
        ).astype(np.float32)


def two_view_distances(raw: np.ndarray) -> np.ndarray:
    """(N, N) two-view distance (:func:`curate.search.duplicate_pairs`) of raw [whole, centre] rows (2 N, D)."""
    from curate.embed import l2_normalize

    whole, centre = l2_normalize(raw[0::2]).astype(np.float64), l2_normalize(raw[1::2]).astype(np.float64)

    def dist(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.sqrt(np.maximum(2 - 2 * a @ b.T, 0))

    return np.minimum(dist(whole, whole), np.minimum(dist(centre, whole), dist(whole, centre)))


def compare(ref: np.ndarray, other: np.ndarray) -> tuple[float, float]:
    """(largest distance change over pairs in the decision region, largest unit-vector component change)."""
    from curate.embed import l2_normalize

    d_ref, d_other = two_view_distances(ref), two_view_distances(other)
    region = np.triu(d_ref < DECISION_REGION, 1)
    dist_change = float(np.abs(d_ref - d_other)[region].max()) if region.any() else 0.0
    return dist_change, float(np.abs(l2_normalize(ref) - l2_normalize(other)).max())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT)
    parser.add_argument("--n", type=int, default=400, help="images (default 400)")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)  # internal: torch vectors of a views file
    args = parser.parse_args()
    if args.child:
        np.save(args.child.with_suffix(".out.npy"), torch_vectors(np.load(args.child)))
        return 0
    if not args.folder.is_dir():
        print(f"embedding_noise_skipped: {args.folder} not found", file=sys.stderr)
        return 0
    paths = sorted(args.folder.rglob("*.jpg"))[:: max(1, len(list(args.folder.rglob("*.jpg"))) // args.n)][: args.n]
    batch = views(paths)
    ref = onnx_vectors(batch, per_call=8)
    settings = {
        "threads2": lambda: onnx_vectors(batch, threads=2),
        "batch1": lambda: onnx_vectors(batch, per_call=2),
        "noopt": lambda: onnx_vectors(batch, optimise=False),
        "torch": lambda: torch_vectors(batch),
        "torch_avx2": lambda: _torch_in_child(batch, {"ATEN_CPU_CAPABILITY": "avx2", "ONEDNN_MAX_CPU_ISA": "AVX2"}),
    }
    print(f"embedding_noise_images: {len(paths)} images")
    print(f"embedding_noise_pairs_in_region: {int(np.triu(two_view_distances(ref) < DECISION_REGION, 1).sum())} pairs")
    for name, run in settings.items():
        dist_change, component = compare(ref, run())
        print(f"embedding_noise_{name}_distance: {dist_change:.2e} max abs")
        print(f"embedding_noise_{name}_component: {component:.2e} max abs")
    perturbation_sweep(args.folder)
    return 0


def perturbation_sweep(folder: Path) -> None:
    """Kept images and split assignments changed by Gaussian moves of the unit embeddings (worst of 3 draws)."""
    from dataclasses import replace

    from curate.curation import assign_splits
    from curate.dedupjob import dedup_options, run_dedup
    from curate.embed import embedding_cache_path, l2_normalize, load_embedder
    from curate.embedcache import EmbeddingCache
    from fuzzyfire.experiment_config import ExperimentConfig
    from ground.config.loader import load_config

    cfg = load_config(REPO / "configs" / "shared-data.yaml", ExperimentConfig).real.curate_config()
    embedder = load_embedder()
    paths = list_images(folder)
    opts = dedup_options(replace(cfg.dedup, near=True, backend="auto"), replace(cfg.rank, top=None))
    with EmbeddingCache(embedding_cache_path()) as cache:
        scan = run_dedup(paths, embedder, cache, opts).scan

    def outcome(vectors: np.ndarray, crops: np.ndarray) -> tuple[set[int], dict[int, str]]:
        run = run_dedup(paths, embedder, None, opts, replace(scan, vectors=vectors, crops=crops))
        run.selected = sorted(run.ranking)
        return set(run.result.kept), assign_splits(run, cfg.split, len(run.selected))[0]

    kept, split = outcome(scan.vectors, scan.crops)
    print(f"embedding_noise_kept: {len(kept)} images")
    for threshold in (cfg.dedup.threshold, cfg.split.group_threshold):
        margin = _nearest_to(scan.vectors, scan.crops, threshold)
        print(f"embedding_noise_nearest_pair_to_{threshold:g}: {margin:.1e} distance")
    for sigma in (1e-5, 3e-5, 1e-4, 3e-4):
        worst_kept = worst_split = 0
        for seed in range(3):
            rng = np.random.default_rng(seed)
            move = [
                l2_normalize(v + rng.normal(0, sigma, v.shape).astype(np.float32)) for v in (scan.vectors, scan.crops)
            ]
            k, s = outcome(*move)
            worst_kept = max(worst_kept, len(k ^ kept))
            worst_split = max(worst_split, sum(s.get(i) != name for i, name in split.items()))
        print(f"embedding_noise_sigma_{sigma:g}_kept_changed: {worst_kept} images")
        print(f"embedding_noise_sigma_{sigma:g}_split_changed: {worst_split} images")


def list_images(folder: Path) -> list[Path]:
    from curate.scan import list_image_files

    return list_image_files([folder])


def _nearest_to(vectors: np.ndarray, crops: np.ndarray, threshold: float) -> float:
    """Smallest |two-view distance - threshold| over all pairs, in row blocks (N x 512 at a time)."""
    w, c = vectors.astype(np.float64), crops.astype(np.float64)
    best = np.inf
    for s in range(0, len(w), 512):
        sims = np.maximum(np.maximum(w[s : s + 512] @ w.T, c[s : s + 512] @ w.T), w[s : s + 512] @ c.T)
        d = np.sqrt(np.maximum(2 - 2 * sims, 0))
        rows = np.arange(s, min(s + 512, len(w)))
        d[np.arange(len(rows)), rows] = np.inf  # not an image with itself
        best = min(best, float(np.abs(d - threshold).min()))
    return best


def _torch_in_child(batch: np.ndarray, env: dict[str, str]) -> np.ndarray:
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "views.npy"
        np.save(src, batch)
        subprocess.run([sys.executable, __file__, "--child", str(src)], env={**os.environ, **env}, check=True)
        return np.load(src.with_suffix(".out.npy"))


if __name__ == "__main__":
    sys.exit(main())

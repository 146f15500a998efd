"""Pick the near-duplicate threshold from the user's own images.

A seeded random sample of images is augmented (flip, crop, resize, JPEG, noise, brightness, rotation); the
pairs (original, its copy) are the positives and the pairs of different originals the negatives. The threshold
is the largest distance at which the *balanced* pair precision ``R / (R + F)`` is still >= the target (R, F:
shares of positive and negative pairs closer than the threshold). Balancing makes the answer independent of
the sample size (negative pairs grow quadratically with it, positives linearly). Distances follow the two-view
rule of :func:`curate.search.duplicate_pairs`. At the default target 0.99 at
most ~1 % of random image pairs of the folder fall under the threshold; consecutive video frames among them are
counted as negatives, so the estimate errs on the side of keeping images.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.embed import OnnxEmbedder, l2_normalize
from curate.search import two_view_distances
from ground.image.imageio import ImageError, read_image

Image = NDArray[np.uint8]


def hflip(img: Image) -> Image:
    """``img`` mirrored left to right, (H, W, 3)."""
    return np.ascontiguousarray(img[:, ::-1])


def centre_crop(img: Image, parts: int) -> Image:
    """``img`` less ``H // parts`` rows at the top and bottom and ``W // parts`` columns at each side."""
    h, w = img.shape[:2]
    dy, dx = h // parts, w // parts
    return np.ascontiguousarray(img[dy : h - dy, dx : w - dx])


def _crop(img: Image, rng: np.random.Generator, keep: float) -> Image:
    h, w = img.shape[:2]
    ch, cw = max(1, round(h * keep)), max(1, round(w * keep))
    y, x = int(rng.integers(0, h - ch + 1)), int(rng.integers(0, w - cw + 1))
    return np.ascontiguousarray(img[y : y + ch, x : x + cw])


def _jpeg(img: Image, quality: int) -> Image:
    ok, buf = cv2.imencode(".jpg", img[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, quality])
    assert ok, "JPEG encoding of a valid array cannot fail"
    return np.ascontiguousarray(cv2.imdecode(buf, cv2.IMREAD_COLOR)[:, :, ::-1])


def _rotate(img: Image, degrees: float) -> Image:
    h, w = img.shape[:2]
    m = cv2.getRotationMatrix2D((w / 2, h / 2), degrees, 1.0)
    return cv2.warpAffine(img, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def _resize(img: Image, scale: float) -> Image:
    h, w = img.shape[:2]
    return cv2.resize(img, (max(1, round(w * scale)), max(1, round(h * scale))), interpolation=cv2.INTER_AREA)


def _noise(img: Image, rng: np.random.Generator, sigma: float) -> Image:
    return np.clip(img + rng.normal(0, sigma, img.shape), 0, 255).astype(np.uint8)


def _bright(img: Image, factor: float) -> Image:
    return np.clip(img.astype(np.float32) * factor, 0, 255).astype(np.uint8)


#: name -> f(image (H, W, 3) uint8 RGB, rng) -> new image; parameters drawn from ``rng`` in the given ranges.
AUGMENTATIONS: dict[str, Callable[[Image, np.random.Generator], Image]] = {
    "hflip": lambda im, rng: hflip(im),
    "crop": lambda im, rng: _crop(im, rng, float(rng.uniform(0.8, 0.95))),
    "resize": lambda im, rng: _resize(im, float(rng.uniform(0.5, 0.9))),
    "jpeg": lambda im, rng: _jpeg(im, int(rng.integers(30, 80))),
    "noise": lambda im, rng: _noise(im, rng, float(rng.uniform(3, 10))),
    "brightness": lambda im, rng: _bright(im, float(rng.choice([-1, 1]) * rng.uniform(0.1, 0.3) + 1)),
    "rotate": lambda im, rng: _rotate(im, float(rng.uniform(-5, 5))),
}


def augment(img: Image, kind: str, rng: np.random.Generator) -> Image:
    """A new augmented copy of ``img`` (the input is not modified)."""
    if kind not in AUGMENTATIONS:
        raise ValueError(f"unknown augmentation {kind!r}; choose one of {', '.join(AUGMENTATIONS)}")
    return AUGMENTATIONS[kind](img, rng)


@dataclass(frozen=True)
class Calibration:
    threshold: float
    precision: float  # pair precision at the threshold
    recall: float  # share of (original, copy) pairs within the threshold
    target: float
    images: int
    positives: int
    negatives: int

    def summary(self) -> str:
        return (
            f"calibrated threshold {self.threshold:.3f} on {self.images} images x {len(AUGMENTATIONS)} augmentations: "
            f"balanced pair precision {self.precision:.3f} (target {self.target}), recall {self.recall:.3f}"
        )


def threshold_at_precision(
    pos: NDArray[np.float32], neg: NDArray[np.float32], target: float
) -> tuple[float, float, float]:
    """Largest threshold t with balanced precision ``R(t) / (R(t) + F(t)) >= target``, where R is the share of
    positive pairs ``pos`` (P,) and F the share of negative pairs ``neg`` (Q,) closer than t (equal priors, so
    the answer does not depend on how many pairs of each kind were sampled). Returns (t, precision, recall)."""
    if len(pos) == 0:
        return 0.0, 1.0, 0.0
    cands = np.unique(np.concatenate([pos, neg]))
    cuts = np.concatenate([(cands[:-1] + cands[1:]) / 2, [cands[-1] + 1e-3]])
    recall = np.searchsorted(np.sort(pos), cuts, side="left") / len(pos)
    false = np.searchsorted(np.sort(neg), cuts, side="left") / max(len(neg), 1)
    precision = np.where(recall + false > 0, recall / np.maximum(recall + false, 1e-12), 1.0)
    ok = np.nonzero((precision >= target) & (recall > 0))[0]
    if len(ok) == 0:
        return 0.0, 1.0, 0.0
    k = int(ok[-1])
    return float(cuts[k]), float(precision[k]), float(recall[k])


def calibrate_threshold(
    paths: Sequence[Path],
    embedder: OnnxEmbedder,
    precision: float = 0.99,
    seed: int = 0,
    sample: int = 150,
) -> Calibration:
    """Threshold for ``embedder`` from ``sample`` images of ``paths`` and their augmented copies (module doc)."""
    if not 0 < precision <= 1:
        raise ValueError(f"target precision must be in (0, 1], got {precision}")
    if len(paths) < 2:
        raise ValueError("calibration needs at least 2 readable images")
    rng = np.random.default_rng(seed)
    chosen = sorted(rng.choice(len(paths), size=min(sample, len(paths)), replace=False).tolist())
    originals, copies = [], []
    for i in chosen:
        try:
            img = read_image(paths[i])
        except ImageError:
            continue
        originals.append(img)
        copies.append([augment(img, kind, rng) for kind in AUGMENTATIONS])
    if len(originals) < 2:
        raise ValueError("calibration needs at least 2 readable images")
    base, base_c = _embed(embedder, originals)
    aug, aug_c = _embed(embedder, [c for cs in copies for c in cs])
    copy_of = np.repeat(np.arange(len(base)), len(AUGMENTATIONS))  # (copies,) the original of each copy
    pos = two_view_distances(aug, aug_c, base, base_c, np.arange(len(aug)), copy_of)
    i, j = np.triu_indices(len(base), 1)
    neg = two_view_distances(base, base_c, base, base_c, i, j)  # float64, the same bits on any CPU
    t, p, r = threshold_at_precision(pos.astype(np.float32), neg.astype(np.float32), precision)
    return Calibration(t, p, r, precision, len(originals), len(pos), len(neg))


def _embed(
    embedder: OnnxEmbedder, images: list[Image], batch: int = 8
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """Unit embeddings of the whole and centre views, each (N, D)."""
    rows = [
        embedder.embed(np.concatenate([embedder.preprocess.views(im) for im in images[s : s + batch]]))
        for s in range(0, len(images), batch)
    ]
    both = np.concatenate(rows).reshape(len(images), 2, -1)
    return l2_normalize(both[:, 0]), l2_normalize(both[:, 1])

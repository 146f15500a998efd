"""Training and validation data: images decoded once and cached in RAM, seeded augmented batches.

Every image is decoded once, resized so its longest side is the training size and kept in memory (about
``3 * imgsz^2`` bytes per image: 0.3 MB at 320 px). A sample's augmentation draws from its own generator
seeded by ``(seed, epoch, index)``, so batches do not depend on threads or on where a run resumed.

Batches are ``(images, targets)``: images (B, 3, S, S) float32 RGB in [0, 1]; targets (T, 6) float32 rows
``[image index in batch, class (0-based), cx, cy, w, h]`` in input pixels.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray

from curate import boxes as bx
from curate.dataset import Dataset, ImageRecord
from curate.imageio import ImageError, read_image
from curate.progress import progress
from train.augment import Sample, augment, letterbox, resize_longest
from train.config import AugmentConfig


@dataclass(frozen=True)
class CachedImage:
    """A decoded image resized to longest side ``size`` with its labels, and the record it came from."""

    record: ImageRecord
    sample: Sample


def _load_one(ds: Dataset, img: ImageRecord, size: int, by_image: dict) -> CachedImage:
    pixels = read_image(ds.image_path(img))
    if pixels.shape[:2] != (img.height, img.width):
        raise ImageError(
            ds.image_path(img), f"decoded {pixels.shape[1]}x{pixels.shape[0]}, expected {img.width}x{img.height}"
        )
    anns = [a for a in by_image[img.id] if not a.iscrowd]
    xyxy = bx.xywh_to_xyxy(np.array([a.bbox for a in anns], dtype=np.float64).reshape(-1, 4)).reshape(-1, 4)
    classes = np.array([a.category_id - 1 for a in anns], dtype=np.int64)
    return CachedImage(img, resize_longest(Sample(pixels, xyxy, classes), size))


def cache_images(ds: Dataset, size: int, desc: str = "decoding images", workers: int = 2) -> list[CachedImage]:
    """Decode every image of ``ds`` once (thread pool). Unreadable images are reported on stderr and left
    out; raises ValueError when none is readable."""
    by_image = ds.annotations_by_image()

    def one(img: ImageRecord) -> CachedImage | ImageError:
        try:
            return _load_one(ds, img, size, by_image)
        except ImageError as exc:
            return exc

    with ThreadPoolExecutor(max_workers=workers) as pool:
        results = list(progress(pool.map(one, ds.images), total=len(ds.images), desc=desc))
    cached = [r for r in results if isinstance(r, CachedImage)]
    for r in results:
        if isinstance(r, ImageError):
            print(f"warning: {r} (image left out)", file=sys.stderr)
    if not cached:
        raise ValueError(f"{ds.root}: no readable images")
    return cached


def collate(samples: list[Sample]) -> tuple[torch.Tensor, torch.Tensor]:
    """Square samples of one size -> (B, 3, S, S) float32 in [0, 1] and (T, 6) targets (cx, cy, w, h px)."""
    batch = np.stack([s.image for s in samples]).transpose(0, 3, 1, 2)
    images = torch.from_numpy(np.ascontiguousarray(batch)).float().div_(255.0)
    rows = []
    for i, s in enumerate(samples):
        cxcywh = bx.xyxy_to_cxcywh(s.boxes.reshape(-1, 4)).reshape(-1, 4)
        rows.append(np.concatenate((np.full((len(cxcywh), 1), i), s.classes.reshape(-1, 1), cxcywh), axis=1))
    targets = torch.from_numpy(np.concatenate(rows).astype(np.float32)) if rows else torch.zeros(0, 6)
    return images, targets


def sample_rng(seed: int, epoch: int, index: int) -> np.random.Generator:
    """The generator of one sample's augmentation in one epoch."""
    return np.random.default_rng([seed, epoch, index])


def epoch_order(count: int, seed: int, epoch: int) -> NDArray[np.int64]:
    """The shuffled sample order of ``epoch``."""
    return np.random.default_rng([seed, epoch]).permutation(count)


class TrainBatches:
    """Augmented batches of a cached training set; the last partial batch is kept."""

    def __init__(self, cache: list[CachedImage], size: int, batch: int, cfg: AugmentConfig, seed: int) -> None:
        self.cache, self.size, self.batch, self.cfg, self.seed = cache, size, batch, cfg, seed

    def __len__(self) -> int:
        return -(-len(self.cache) // self.batch)

    def _sample(self, epoch: int, index: int) -> Sample:
        def load(i: int) -> Sample:
            return self.cache[i].sample

        return augment(load, index, len(self.cache), self.size, self.cfg, sample_rng(self.seed, epoch, index))

    def _batch(self, epoch: int, indices: NDArray[np.int64]) -> tuple[torch.Tensor, torch.Tensor]:
        return collate([self._sample(epoch, int(i)) for i in indices])

    def epoch(self, epoch: int, start: int = 0) -> Iterator[tuple[torch.Tensor, torch.Tensor]]:
        """Batches of ``epoch`` from batch number ``start``; the next batch is prepared in a thread while the
        caller trains on the current one."""
        order = epoch_order(len(self.cache), self.seed, epoch)
        chunks = [order[i : i + self.batch] for i in range(start * self.batch, len(order), self.batch)]
        with ThreadPoolExecutor(max_workers=1) as pool:
            pending: Future | None = pool.submit(self._batch, epoch, chunks[0]) if chunks else None
            for k in range(len(chunks)):
                assert pending is not None
                current = pending.result()
                pending = pool.submit(self._batch, epoch, chunks[k + 1]) if k + 1 < len(chunks) else None
                yield current


def val_batches(cache: list[CachedImage], size: int, batch: int) -> Iterator[tuple[list[ImageRecord], torch.Tensor]]:
    """Letterboxed validation batches: (records, (B, 3, S, S) float32 in [0, 1])."""
    for i in range(0, len(cache), batch):
        chunk = cache[i : i + batch]
        images, _ = collate([letterbox(c.sample, size) for c in chunk])
        yield [c.record for c in chunk], images

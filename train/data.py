"""Training and validation data: images decoded once and cached in RAM, seeded augmented batches.

Every training image is decoded once, resized so its longest side is the training size and kept in memory
(about ``3 * imgsz^2`` bytes per image: 0.3 MB at 320 px). A sample's augmentation draws from its own
generator seeded by ``(seed, draw, index)`` (``draw`` is the epoch, or the view number when frozen features are
cached: :mod:`train.features`), so batches do not depend on threads, worker processes or where a run resumed.
Validation images are decoded and letterboxed exactly as ``fuzzyfire score`` does (:mod:`ground.detect.letterbox`).

Batches are ``(images, targets)``: images (B, 3, S, S) float32 RGB in [0, 1]; targets (T, 6) float32 rows
``[image index in batch, class (0-based), cx, cy, w, h]`` in input pixels.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial

import numpy as np
import torch
from numpy.typing import NDArray

from ground.data import boxes as bx
from ground.data.dataset import Dataset, ImageRecord
from ground.detect.letterbox import letterbox_image
from ground.image.imageio import ImageError, read_image
from ground.run.progress import progress
from train.augment import Sample, augment, resize_longest
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
    """Decode every image of ``ds`` once (thread pool), longest side ``size``. Unreadable images are reported
    on stderr and left out; raises ValueError when none is readable."""
    by_image = ds.annotations_by_image()
    return _decode_all(ds, lambda img: _load_one(ds, img, size, by_image), desc, workers)


@dataclass(frozen=True)
class LetterboxedImage:
    """A validation image as a scorer feeds it to the model: ``image`` (size, size, 3) uint8 RGB, letterboxed
    from the original pixels by :func:`ground.detect.letterbox.letterbox_image`."""

    record: ImageRecord
    image: NDArray[np.uint8]


def letterboxed_images(
    ds: Dataset, size: int, desc: str = "decoding images", workers: int = 2
) -> list[LetterboxedImage]:
    """Decode and letterbox every image of ``ds`` to ``size`` x ``size``; unreadable ones reported and left out."""

    def load(img: ImageRecord) -> LetterboxedImage:
        return LetterboxedImage(img, letterbox_image(read_image(ds.image_path(img)), size, size))

    return _decode_all(ds, load, desc, workers)


def _decode_all(ds: Dataset, load, desc: str, workers: int) -> list:
    def one(img: ImageRecord):
        try:
            return load(img)
        except ImageError as exc:
            return exc

    with ThreadPoolExecutor(max_workers=workers) as pool:
        results = list(progress(pool.map(one, ds.images), total=len(ds.images), desc=desc))
    for r in results:
        if isinstance(r, ImageError):
            print(f"warning: {r} (image left out)", file=sys.stderr)
    cached = [r for r in results if not isinstance(r, ImageError)]
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


def sample_rng(seed: int, draw: int, index: int) -> np.random.Generator:
    """The generator of one sample's augmentation in one draw (an epoch, or a cached view)."""
    return np.random.default_rng([seed, draw, index])


def epoch_order(count: int, seed: int, epoch: int) -> NDArray[np.int64]:
    """The shuffled sample order of ``epoch``."""
    return np.random.default_rng([seed, epoch]).permutation(count)


SYNTHETIC_SOURCE = "synth:"  # how a fuzzyfire mixture tags its synthetic images' source (curate.mix)


def is_real(image: CachedImage) -> bool:
    """Whether a cached image is not synthetic (its source does not start with :data:`SYNTHETIC_SOURCE`)."""
    return not image.record.source.startswith(SYNTHETIC_SOURCE)


def real_indices(cache: list[CachedImage]) -> NDArray[np.int64]:
    """Indices of the cached images that are real (:func:`is_real`)."""
    return np.asarray([i for i, c in enumerate(cache) if is_real(c)], np.int64)


class TrainBatches:
    """Augmented batches of a cached training set; the last partial batch is kept.

    ``real_from``: from this epoch on, batches hold only the real images (:func:`real_indices`), and a real
    image's mosaic partners are real in every epoch (None: every image in every epoch, mosaics of any four).
    ``workers`` > 0 prepares batches in that many worker processes (to keep a GPU fed); 0 prepares the next
    batch in a thread while the caller trains on the current one. Both give the same batches."""

    def __init__(
        self,
        cache: list[CachedImage],
        size: int,
        batch: int,
        cfg: AugmentConfig,
        seed: int,
        workers: int = 0,
        real_from: int | None = None,
    ) -> None:
        self.cache, self.size, self.batch, self.cfg, self.seed = cache, size, batch, cfg, seed
        self.workers, self.real_from = workers, real_from
        self.real = real_indices(cache) if real_from is not None else None  # None: no real-only epochs

    def __len__(self) -> int:
        """Batches in an epoch of every image."""
        return -(-len(self.cache) // self.batch)

    def count(self, epoch: int) -> int:
        """Batches in ``epoch`` (fewer from ``real_from`` on)."""
        return -(-len(self._images(epoch)) // self.batch)

    def _images(self, epoch: int) -> NDArray[np.int64]:
        if self.real is not None and epoch >= self.real_from:
            return self.real
        return np.arange(len(self.cache))

    def sample(self, draw: int, index: int) -> Sample:
        """The augmented view of image ``index`` in ``draw`` (size x size)."""

        def load(i: int) -> Sample:
            return self.cache[i].sample

        partners = self.real if self.real is not None and is_real(self.cache[index]) else len(self.cache)
        return augment(load, index, partners, self.size, self.cfg, sample_rng(self.seed, draw, index))

    def make_batch(self, draw: int, indices: NDArray[np.int64]) -> tuple[torch.Tensor, torch.Tensor]:
        """Collated views of ``indices`` in ``draw``: (B, 3, S, S) float32 in [0, 1] and (T, 6) targets."""
        return collate([self.sample(draw, int(i)) for i in indices])

    def chunks(self, epoch: int, start: int = 0) -> list[NDArray[np.int64]]:
        """Image indices of each batch of ``epoch`` from batch number ``start``."""
        images = self._images(epoch)
        order = images[epoch_order(len(images), self.seed, epoch)]
        return [order[i : i + self.batch] for i in range(start * self.batch, len(order), self.batch)]

    def epoch(self, epoch: int, start: int = 0) -> Iterator[tuple[torch.Tensor, torch.Tensor]]:
        """Batches of ``epoch`` from batch number ``start``."""
        chunks = self.chunks(epoch, start)
        if self.workers > 0:
            yield from _in_processes(partial(self.make_batch, epoch), chunks, self.workers)
        else:
            yield from prefetched(partial(self.make_batch, epoch), chunks)


def prefetched(make, items: list) -> Iterator:
    """``make(item)`` for each item in order, the next one computed in a thread while the caller uses the current."""
    with ThreadPoolExecutor(max_workers=1) as pool:
        pending: Future | None = pool.submit(make, items[0]) if items else None
        for k in range(len(items)):
            assert pending is not None
            current = pending.result()
            pending = pool.submit(make, items[k + 1]) if k + 1 < len(items) else None
            yield current


class _Chunks(torch.utils.data.Dataset):
    """``make(chunk)`` per item, for a DataLoader whose workers each build whole batches."""

    def __init__(self, make, chunks: list) -> None:
        self.make, self.items = make, chunks

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(self, k: int):
        return self.make(self.items[k])


def _in_processes(make, chunks: list, workers: int) -> Iterator:
    loader = torch.utils.data.DataLoader(
        _Chunks(make, chunks), batch_size=None, shuffle=False, num_workers=workers, prefetch_factor=4
    )
    yield from loader

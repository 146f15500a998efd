"""Frozen features computed once: the frozen part of the backbone (:mod:`train.backbones`) run on augmented
training views and on validation images, so epochs only pay for the trainable part.

Training. A *view* is one augmented sample of an image (mosaic, affine, HSV, flip: :mod:`train.augment`).
With ``views = V > 0`` every image gets V views, view ``v`` drawn with the generator ``(seed, v, index)``;
epoch ``e`` trains on view ``e mod V`` in that epoch's shuffled order. The frozen part thus runs V times per
image for the whole run instead of once per epoch, and each view's features stay in RAM as float16 (about
``2 * sum(C * H * W)`` bytes per view: 128 KB for Lite0 frozen through stage 3 at 320 px). When the cache
would exceed ``max_gb``, fewer views are kept (said on stdout). ``V = 0`` draws a fresh view every epoch
(generator ``(seed, epoch, index)``, as without a frozen part) and runs the frozen part on every batch.

The frozen part runs with onnxruntime on the CPU (about 4x faster than torch eager on Lite0's depthwise
convolutions at 320 px) and with torch on a GPU. A model with nothing frozen (cspdarknet) passes images
through, with augmentation drawn afresh every epoch.
"""

from __future__ import annotations

import io
from collections.abc import Iterator, Sequence

import numpy as np
import torch
from numpy.typing import NDArray
from torch import Tensor, nn

from ground.data.dataset import ImageRecord
from ground.detect.letterbox import to_nchw_float
from ground.run.progress import progress
from train.data import LetterboxedImage, TrainBatches, prefetched
from train.export import torch_to_onnx
from train.model import Detector

Features = tuple[Tensor, ...]


class _FrozenPart(nn.Module):
    def __init__(self, model: Detector) -> None:
        super().__init__()
        self.backbone = model.backbone

    def forward(self, images: Tensor) -> tuple[Tensor, ...]:
        return self.backbone.frozen_forward(images)


class FrozenRunner:
    """``runner(images)``: (B, 3, S, S) float32 in [0, 1] on the CPU -> the model's frozen features, float32
    tensors on ``device`` (``(images,)`` when nothing is frozen)."""

    def __init__(self, model: Detector, imgsz: int, device: torch.device, threads: int = 0) -> None:
        self.device = device
        self.identity = not model.has_frozen
        self.session = None
        self.model = model
        if not self.identity and device.type == "cpu":
            self.session = _ort_session(_FrozenPart(model).eval(), imgsz, threads)

    def __call__(self, images: Tensor) -> Features:
        if self.identity:
            return (images.to(self.device, non_blocking=True),)
        if self.session is not None:
            outs = self.session.run(None, {"images": images.numpy()})
            return tuple(torch.from_numpy(o) for o in outs)
        return self.model.frozen_features(images.to(self.device, non_blocking=True))


def _ort_session(module: nn.Module, imgsz: int, threads: int):
    """An onnxruntime session of ``module`` (input ``images`` (B, 3, imgsz, imgsz), dynamic batch)."""
    import onnxruntime as ort

    buffer = io.BytesIO()
    torch_to_onnx(module, imgsz, buffer)
    opts = ort.SessionOptions()
    if threads > 0:
        opts.intra_op_num_threads = threads
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")  # leave the cores to torch between calls
    return ort.InferenceSession(buffer.getvalue(), opts, providers=["CPUExecutionProvider"])


def cache_views(requested: int, images: int, bytes_per_view: int, max_gb: float) -> int:
    """How many views per image fit in ``max_gb`` (at most ``requested``; 0 when not even one fits)."""
    if requested <= 0:
        return 0
    fit = int(max_gb * 1e9 // max(images * bytes_per_view, 1))
    return min(requested, fit)


class FeatureBatches:
    """Training batches ``(frozen features, targets)``: features as :class:`FrozenRunner` returns them, targets
    (T, 6) ``[image index in batch, class, cx, cy, w, h]`` in input pixels, on the runner's device."""

    def __init__(self, samples: TrainBatches, runner: FrozenRunner, views: int = 0, max_gb: float = 4.0) -> None:
        self.samples, self.runner = samples, runner
        self.views = 0
        if not runner.identity and views > 0:
            shapes = [tuple(f.shape[1:]) for f in runner(torch.zeros(1, 3, samples.size, samples.size))]
            per_view = sum(int(np.prod(s)) for s in shapes) * 2
            self.views = cache_views(views, len(samples.cache), per_view, max_gb)
            if self.views < views:
                need = len(samples.cache) * per_view * views / 1e9
                kept = f"keeping {self.views}" if self.views else "none kept: a fresh view every epoch"
                print(f"feature cache: {views} views need {need:.1f} GB > {max_gb:g} GB (feature_cache_gb); {kept}")
            self._shapes = shapes
        self._store: dict[int, tuple[list[NDArray[np.float16]], list[NDArray[np.float32]]]] = {}

    def __len__(self) -> int:
        return len(self.samples)

    def count(self, epoch: int) -> int:
        """Batches in ``epoch`` (:meth:`train.data.TrainBatches.count`)."""
        return self.samples.count(epoch)

    def draw(self, epoch: int) -> int:
        """The augmentation draw an epoch trains on: its view when views are cached, else the epoch."""
        return epoch % self.views if self.views else epoch

    def epoch(self, epoch: int, start: int = 0) -> Iterator[tuple[Features, Tensor]]:
        """The batches of ``epoch`` from batch number ``start`` (its view's features computed on first use)."""
        device = self.runner.device
        if not self.views:
            for images, targets in self.samples.epoch(epoch, start):
                yield self.runner(images), targets.to(device, non_blocking=True)
            return
        arrays, targets = self._view(self.draw(epoch))
        for chunk in self.samples.chunks(epoch, start):
            feats = tuple(torch.from_numpy(a[chunk]).to(device).float() for a in arrays)
            rows = [
                np.concatenate((np.full((len(t), 1), k, np.float32), t), 1)
                for k, t in enumerate(targets[i] for i in chunk)
            ]
            yield feats, torch.from_numpy(np.concatenate(rows)).to(device)

    def _view(self, view: int) -> tuple[list[NDArray[np.float16]], list[NDArray[np.float32]]]:
        """The features (one (N, C, H, W) float16 array per frozen output) and per-image targets of ``view``,
        computed on first use."""
        if view in self._store:
            return self._store[view]
        n = len(self.samples.cache)
        arrays = [np.empty((n, *s), np.float16) for s in self._shapes]
        targets: list[NDArray[np.float32]] = [np.zeros((0, 5), np.float32)] * n
        size = max(self.samples.batch, 16)
        chunks = [np.arange(i, min(i + size, n)) for i in range(0, n, size)]
        batches = prefetched(lambda c: (c, *self.samples.make_batch(view, c)), chunks)
        for chunk, images, rows in progress(batches, total=len(chunks), desc=f"frozen features, view {view + 1}"):
            for a, f in zip(arrays, self.runner(images)):
                a[chunk] = f.cpu().numpy()
            rows = rows.numpy()
            for k, i in enumerate(chunk):
                targets[i] = rows[rows[:, 0] == k, 1:]
        self._store[view] = (arrays, targets)
        return arrays, targets


class ValidationInputs:
    """Validation images letterboxed once (as a scorer does) and, when the model has a frozen part, their frozen
    features computed once (float32). Iterating gives ``(records, features)`` batches on the runner's device."""

    def __init__(self, images: Sequence[LetterboxedImage], runner: FrozenRunner, batch: int) -> None:
        self.runner = runner
        self.batches: list[tuple[list[ImageRecord], object]] = []
        for i in range(0, len(images), batch):
            chunk = images[i : i + batch]
            pixels = np.stack([c.image for c in chunk])
            stored = pixels if runner.identity else tuple(f.cpu() for f in runner(_to_tensor(pixels)))
            self.batches.append(([c.record for c in chunk], stored))

    @property
    def records(self) -> list[ImageRecord]:
        return [r for records, _ in self.batches for r in records]

    def __iter__(self) -> Iterator[tuple[list[ImageRecord], Features]]:
        device = self.runner.device
        for records, stored in self.batches:
            if isinstance(stored, np.ndarray):
                yield records, (_to_tensor(stored).to(device),)
            else:
                yield records, tuple(f.to(device) for f in stored)


def _to_tensor(pixels: NDArray[np.uint8]) -> Tensor:
    """(B, S, S, 3) uint8 RGB -> (B, 3, S, S) float32 in [0, 1] (the scorer's conversion)."""
    return torch.from_numpy(to_nchw_float(list(pixels)))

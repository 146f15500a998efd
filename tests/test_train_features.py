"""Frozen features: onnxruntime equals torch, cached views are reused exactly and match the augmented batches
they came from, the RAM cap, and validation inputs equal to the scorer's preprocessing."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from factories_train import painted_dataset

from ground.detect.letterbox import letterbox_image, to_nchw_float
from ground.image.imageio import read_image
from train.config import AugmentConfig, DetectorConfig
from train.data import TrainBatches, cache_images, letterboxed_images
from train.features import FeatureBatches, FrozenRunner, ValidationInputs, cache_views
from train.model import build_model

CPU = torch.device("cpu")


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory):
    return painted_dataset(tmp_path_factory.mktemp("painted"), 10, seed=0)


@pytest.fixture(scope="module")
def model():
    return build_model(2, DetectorConfig(backbone="efficientnet-lite0", freeze=3), imgsz=64).eval()


def test_onnxruntime_equals_torch(model) -> None:
    runner = FrozenRunner(model, 64, CPU)
    x = torch.rand(3, 3, 64, 64, generator=torch.Generator().manual_seed(0))
    got = runner(x)
    expected = model.frozen_features(x)
    assert runner.session is not None and len(got) == len(expected) == 1
    np.testing.assert_allclose(got[0].numpy(), expected[0].numpy(), rtol=1e-3, atol=1e-4)


def test_nothing_frozen_passes_images_through() -> None:
    runner = FrozenRunner(build_model(1, DetectorConfig(backbone="cspdarknet"), imgsz=64), 64, CPU)
    x = torch.rand(2, 3, 64, 64)
    assert runner.identity and runner.session is None and torch.equal(runner(x)[0], x)


def test_cache_views_fits_the_budget() -> None:
    assert cache_views(10, images=100, bytes_per_view=1_000_000, max_gb=0.5) == 5
    assert cache_views(3, images=100, bytes_per_view=1_000_000, max_gb=4) == 3
    assert cache_views(10, images=100, bytes_per_view=1_000_000, max_gb=0.05) == 0
    assert cache_views(0, images=1, bytes_per_view=1, max_gb=1) == 0


def test_views_are_cached_reused_and_match_their_batches(dataset, model) -> None:
    samples = TrainBatches(cache_images(dataset, 64), 64, 4, AugmentConfig(), seed=3)
    runner = FrozenRunner(model, 64, CPU)
    batches = FeatureBatches(samples, runner, views=2)
    assert batches.views == 2 and [batches.draw(e) for e in range(4)] == [0, 1, 0, 1]
    epoch0 = list(batches.epoch(0))
    epoch2 = list(batches.epoch(2))  # view 0 again, in epoch 2's order
    order0, order2 = np.concatenate(samples.chunks(0)), np.concatenate(samples.chunks(2))
    feats0 = torch.cat([f[0] for f, _ in epoch0])[np.argsort(order0)]
    feats2 = torch.cat([f[0] for f, _ in epoch2])[np.argsort(order2)]
    assert torch.equal(feats0, feats2)
    (feats, targets), chunk = epoch0[0], samples.chunks(0)[0]
    images, expected = samples.make_batch(0, chunk)  # the same augmented views, freshly drawn
    np.testing.assert_allclose(feats[0].numpy(), runner(images)[0].numpy(), rtol=1e-2, atol=1e-2)  # float16 store
    assert torch.equal(targets, expected)


def test_fresh_views_without_cache(dataset, model) -> None:
    samples = TrainBatches(cache_images(dataset, 64), 64, 4, AugmentConfig(), seed=3)
    runner = FrozenRunner(model, 64, CPU)
    batches = FeatureBatches(samples, runner, views=0)
    (feats, targets), (images, expected) = next(iter(batches.epoch(5))), next(iter(samples.epoch(5)))
    assert batches.draw(5) == 5 and torch.equal(targets, expected)
    assert torch.equal(feats[0], runner(images)[0])


def test_ram_cap_keeps_fewer_views(dataset, model, capsys) -> None:
    samples = TrainBatches(cache_images(dataset, 64), 64, 4, AugmentConfig(), seed=3)
    per_view = 40 * 8 * 8 * 2  # (40, 8, 8) float16
    batches = FeatureBatches(samples, FrozenRunner(model, 64, CPU), views=8, max_gb=3 * 10 * per_view / 1e9)
    assert batches.views == 3 and "keeping 3" in capsys.readouterr().out


def test_validation_inputs_are_the_scorer_preprocessing(dataset, model) -> None:
    images = letterboxed_images(dataset, 64)
    first = images[0]
    expected = letterbox_image(read_image(dataset.image_path(first.record)), 64, 64)
    assert np.array_equal(first.image, expected)
    plain = ValidationInputs(
        images, FrozenRunner(build_model(2, DetectorConfig(backbone="cspdarknet"), imgsz=64), 64, CPU), batch=4
    )
    records, (x,) = next(iter(plain))
    assert [r.id for r in records] == [i.record.id for i in images[:4]]
    assert torch.equal(x, torch.from_numpy(to_nchw_float([i.image for i in images[:4]])))
    frozen = ValidationInputs(images, FrozenRunner(model, 64, CPU), batch=4)
    assert len(frozen.records) == len(images)
    _, (f,) = next(iter(frozen))
    np.testing.assert_allclose(f.numpy(), model.frozen_features(x)[0].numpy(), rtol=1e-3, atol=1e-4)

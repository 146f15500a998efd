"""Decode-once cache, batches and targets, seeded determinism."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from factories_train import painted_dataset

from ground.data.dataset import DatasetBuilder
from train.augment import Sample
from train.config import AugmentConfig
from train.data import TrainBatches, cache_images, collate, letterboxed_images, real_indices


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory):
    return painted_dataset(tmp_path_factory.mktemp("painted"), 10, seed=0)


def test_cache_resizes_once_and_keeps_labels(dataset) -> None:
    cache = cache_images(dataset, 40)
    assert len(cache) == 10
    first = cache[0]
    assert first.sample.image.shape == (32, 40, 3)  # 80 x 64 -> longest side 40
    anns = dataset.annotations_by_image()[first.record.id]
    assert len(first.sample.boxes) == len(anns)
    x, y, w, h = anns[0].bbox
    np.testing.assert_allclose(first.sample.boxes[0], [x / 2, y / 2, (x + w) / 2, (y + h) / 2])


def test_unreadable_image_is_reported_and_left_out(dataset, tmp_path: Path, capsys) -> None:
    (tmp_path / "bad.png").write_bytes(b"not an image")
    b = DatasetBuilder(tmp_path, ["fire"])
    b.add_image("bad.png", 10, 10)
    b.add_image(str(dataset.image_path(dataset.images[0])), 80, 64)
    cache = cache_images(b.build(), 40)
    assert len(cache) == 1
    assert "bad.png" in capsys.readouterr().err
    with pytest.raises(ValueError, match="no readable images"):
        cache_images(b.build().filter_images(lambda img: img.file_name == "bad.png"), 40)


def test_collate_targets_in_input_pixels() -> None:
    image = np.zeros((8, 8, 3), dtype=np.uint8)
    samples = [
        Sample(image, np.array([[0.0, 0.0, 4.0, 2.0]]), np.array([1])),
        Sample(image + 255, np.zeros((0, 4)), np.zeros(0, dtype=np.int64)),
    ]
    images, targets = collate(samples)
    assert images.shape == (2, 3, 8, 8) and images.dtype == torch.float32 and float(images[1].min()) == 1.0
    assert targets.tolist() == [[0.0, 1.0, 2.0, 1.0, 4.0, 2.0]]


def test_batches_are_seeded_and_resumable(dataset) -> None:
    cache = cache_images(dataset, 64)
    batches = TrainBatches(cache, 64, 4, AugmentConfig(), seed=3)
    assert len(batches) == 3
    first = list(batches.epoch(0))
    again = list(batches.epoch(0))
    assert [b[0].shape[0] for b in first] == [4, 4, 2]
    for (xa, ta), (xb, tb) in zip(first, again):
        assert torch.equal(xa, xb) and torch.equal(ta, tb)
    resumed = list(batches.epoch(0, start=1))
    assert torch.equal(resumed[0][0], first[1][0])
    other = next(iter(batches.epoch(1)))
    assert not torch.equal(other[0], first[0][0])
    for images, targets in first:
        assert images.shape[1:] == (3, 64, 64)
        if len(targets):
            assert float(targets[:, 2:].min()) >= 0 and float(targets[:, 2:4].max()) <= 64


def test_letterboxed_validation_images(dataset) -> None:
    images = letterboxed_images(dataset, 64)
    assert len(images) == 10 and images[0].image.shape == (64, 64, 3)
    assert tuple(images[0].image[0, 0]) == (114, 114, 114)  # 80 x 64 -> 64 x 51, grey bands


def test_worker_processes_give_the_same_batches(dataset) -> None:
    cache = cache_images(dataset, 64)
    threads = list(TrainBatches(cache, 64, 4, AugmentConfig(), seed=3).epoch(2))
    processes = list(TrainBatches(cache, 64, 4, AugmentConfig(), seed=3, workers=2).epoch(2))
    assert len(threads) == len(processes) == 3
    for (xa, ta), (xb, tb) in zip(threads, processes):
        assert torch.equal(xa, xb) and torch.equal(ta, tb)


def _tagged(cache: list, synthetic: set[int]) -> list:
    """``cache`` with the images at ``synthetic`` tagged as a fuzzyfire mixture tags its synthetic images."""
    return [
        replace(c, record=replace(c.record, source="synth:method2" if i in synthetic else "real:x"))
        for i, c in enumerate(cache)
    ]


def test_real_from_trains_the_last_epochs_on_real_images_only(dataset) -> None:
    cache = _tagged(cache_images(dataset, 64), {1, 4, 5, 8})
    assert real_indices(cache).tolist() == [0, 2, 3, 6, 7, 9]
    plain = TrainBatches(cache, 64, 4, AugmentConfig(), seed=3)
    tuned = TrainBatches(cache, 64, 4, AugmentConfig(), seed=3, real_from=2)
    for epoch in (0, 1):  # before real_from: every image once, in the same order as without it
        assert tuned.count(epoch) == len(tuned) == 3
        assert [c.tolist() for c in tuned.chunks(epoch)] == [c.tolist() for c in plain.chunks(epoch)]
    for epoch in (2, 5):
        chunks = tuned.chunks(epoch)
        assert tuned.count(epoch) == len(chunks) == 2 and len(tuned) == 3
        assert sorted(np.concatenate(chunks).tolist()) == [0, 2, 3, 6, 7, 9]
        assert [b[0].shape[0] for b in tuned.epoch(epoch)] == [4, 2]
    assert tuned.chunks(2, start=1)[0].tolist() == tuned.chunks(2)[1].tolist()


def test_real_from_leaves_synthetic_images_views_unchanged(dataset) -> None:
    """Only a real image's mosaic partners are restricted: a synthetic image's view is as it was."""
    cache = _tagged(cache_images(dataset, 64), {1, 4})
    plain = TrainBatches(cache, 64, 4, AugmentConfig(mosaic=1.0), seed=3)
    tuned = TrainBatches(cache, 64, 4, AugmentConfig(mosaic=1.0), seed=3, real_from=1)
    for draw in range(3):
        assert np.array_equal(plain.sample(draw, 1).image, tuned.sample(draw, 1).image)

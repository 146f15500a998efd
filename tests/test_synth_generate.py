"""The shared generation loop: every image staged once, an interrupted run resumes where it stopped, the
dataset is written with the method's source tag, an empty flame library is refused."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from curate.core.formats.registry import read_dataset
from synth.generate import generate
from synth.sprites import Sprite, SpriteSequence
from synth.staging import staging_dir


@dataclass(frozen=True)
class TinyConfig:
    n: int = 4
    seed: int = 0
    scenes: int = 1
    environments: tuple = ()
    images_per_view: int = 1
    width: int = 32
    height: int = 24
    smoke_class: bool = False


def _library() -> list[SpriteSequence]:
    sprite = Sprite(np.full((4, 4, 4), 255, np.uint8), np.zeros((4, 4, 3), np.uint8), np.ones((4, 4), bool))
    return [SpriteSequence("s", (sprite,), {})]


def _make_image(cfg, i, library, views):
    """A flat image with one 8x6 box at (i, i): the loop only has to stage it."""
    mask = np.zeros((cfg.height, cfg.width), bool)
    mask[i : i + 6, i : i + 8] = True
    image = np.full((cfg.height, cfg.width, 3), 40 * i, np.uint8)
    record = {"width": cfg.width, "height": cfg.height, "boxes": [[i, i, 8, 6]], "meta": {"i": i}}
    return image, [mask], record, None


def test_interrupted_run_resumes_and_writes_every_image(tmp_path):
    calls: list[int] = []

    def failing(cfg, i, library, views):
        if i == 2 and not calls.count(-1):
            calls.append(-1)
            raise KeyboardInterrupt
        calls.append(i)
        return _make_image(cfg, i, library, views)

    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        generate("method9", TinyConfig(), failing, _library(), out)
    assert calls == [0, 1, -1] and staging_dir(out).is_dir()
    generate("method9", TinyConfig(), failing, _library(), out)
    assert calls == [0, 1, -1, 2, 3]  # 0 and 1 were not made again
    ds = read_dataset(out).dataset
    assert len(ds.images) == 4 and {img.source for img in ds.images} == {"synth:method9"}
    assert sorted(tuple(a.bbox) for a in ds.annotations) == [(i, i, 8, 6) for i in range(4)]
    assert not staging_dir(out).exists()


def test_empty_library_is_refused(tmp_path):
    with pytest.raises(ValueError, match="flame library is empty"):
        generate("method9", TinyConfig(), _make_image, [], tmp_path / "out")
    with pytest.raises(ValueError, match="flame library is empty"):
        generate("method9", TinyConfig(), _make_image, [SpriteSequence("s", (), {})], tmp_path / "out")

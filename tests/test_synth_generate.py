"""The shared generation loop: every image staged once, an interrupted run resumes where it stopped, the
dataset is written with the method's source tag, an empty flame library is refused; several processes write the
same bytes as one, each environment's views stay in one block, and a failure in a process is raised and keeps
what was staged."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import ClassVar

import cv2
import numpy as np
import pytest
from factories import dataset_files

from ground.data.formats.registry import read_dataset
from synth.flames.sprites import Sprite, SpriteSequence
from synth.generate import BLOCK_VIEWS, Job, blocks, generate, image_maker
from synth.method_config import MethodConfig
from synth.staging import staging_dir


@dataclass(frozen=True)
class TinyConfig(MethodConfig):
    """A method of the tests' own: its images come from :func:`_make_image` (given to generate)."""

    method: ClassVar[str] = "method9"
    composited: ClassVar[bool] = False
    bringing_places: ClassVar[str] = "environments are"

    n: int = 4
    scenes: int | None = 1
    width: int = 32
    height: int = 24


def _library() -> list[SpriteSequence]:
    sprite = Sprite(np.full((4, 4, 4), 255, np.uint8), np.zeros((4, 4, 3), np.uint8), np.ones((4, 4), bool))
    return [SpriteSequence("s", (sprite,), {})]


def _make_image(cfg, i, library, views):
    """A flat image with one 8x6 box at (i, i): the loop only has to stage it."""
    mask = np.zeros((cfg.height, cfg.width), bool)
    mask[i : i + 6, i : i + 8] = True
    image = np.full((cfg.height, cfg.width, 3), 40 * i % 256, np.uint8)
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
        generate(TinyConfig(), _library(), out, make_image=failing)
    assert calls == [0, 1, -1] and staging_dir(out).is_dir()
    generate(TinyConfig(), _library(), out, make_image=failing)
    assert calls == [0, 1, -1, 2, 3]  # 0 and 1 were not made again
    ds = read_dataset(out).dataset
    assert len(ds.images) == 4 and {img.source for img in ds.images} == {"synth:method9"}
    assert sorted(tuple(a.bbox) for a in ds.annotations) == [(i, i, 8, 6) for i in range(4)]
    assert not staging_dir(out).exists()


def test_each_method_makes_its_own_images_and_another_config_brings_its_maker(tmp_path):
    from synth import method1, method2

    assert image_maker(method1.Method1Config()) is method1.make_image
    assert image_maker(method2.Method2Config()) is method2.make_image
    with pytest.raises(TypeError, match="no image maker for TinyConfig"):
        generate(TinyConfig(), _library(), tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_empty_library_is_refused(tmp_path):
    with pytest.raises(ValueError, match="flame library is empty"):
        generate(TinyConfig(), [], tmp_path / "out", make_image=_make_image)
    with pytest.raises(ValueError, match="flame library is empty"):
        generate(TinyConfig(), [SpriteSequence("s", (), {})], tmp_path / "out", make_image=_make_image)


def _panoramas(root: Path) -> Path:
    """Two 256x128 panoramas: sky above the middle row, textured ground below."""
    rng = np.random.default_rng(0)
    for k in range(2):
        img = np.empty((128, 256, 3), np.uint8)
        img[:64] = (230, 150, 60)  # BGR sky
        img[64:] = rng.integers(60, 200, (64, 256, 3), dtype=np.uint8)
        root.mkdir(parents=True, exist_ok=True)
        assert cv2.imwrite(str(root / f"p{k}.png"), img)
    return root


def _same_bytes_as_one_process(tmp_path: Path, library, **how) -> None:  # noqa: ANN001
    """Method 2 on procedural rooms and panoramas, Method 1 on procedural rooms: a run with ``how`` (workers or a
    cluster) writes every file of a one-process run with the same bytes."""
    from synth.method1 import Method1Config
    from synth.method2 import Method2Config

    m2 = Method2Config(n=40, seed=3, width=96, height=72, scenes=2, environments=(_panoramas(tmp_path / "pano"),),
                       images_per_view=2, negatives=0.0, min_box_px=2)  # fmt: skip
    m1 = Method1Config(n=6, seed=5, width=96, height=72, scenes=2, negatives=0.0, min_box_px=2)
    for cfg in (m2, m1):
        one, other = tmp_path / f"{cfg.n}-one", tmp_path / f"{cfg.n}-other"
        generate(cfg, library, one)
        generate(cfg, library, other, **how)
        assert dataset_files(one) == dataset_files(other) and len(dataset_files(one)) > cfg.n


def test_two_processes_write_the_bytes_of_one(tmp_path, library):
    _same_bytes_as_one_process(tmp_path, library, workers=2)


@pytest.mark.slow
def test_a_ray_cluster_writes_the_bytes_of_one_process(tmp_path, library, cluster):
    """The blocks as tasks on a real Ray head (2 workers)."""
    _same_bytes_as_one_process(tmp_path, library, cluster=cluster)


def test_blocks_keep_an_environment_in_one_process_and_cover_every_image():
    cfg = TinyConfig(n=40, scenes=0, environments=(Path("meshes"),), images_per_view=2)
    job = Job(cfg, _make_image, (), Path("x"), None, ("a", "b", "c"), (), (), ())
    todo = [i for i in range(40) if i % 7]  # some images staged already
    got = blocks(job, todo)  # type: ignore[arg-type]
    assert sorted(i for b in got for i in b) == todo and len(got) == 3
    views = [sorted({i // 2 * 3 // 20 for i in b}) for b in got]  # the environment of each block's views
    assert views == [[0], [1], [2]]
    free = blocks(replace(job, files=()), list(range(40)))
    assert [len(b) for b in free] == [2 * BLOCK_VIEWS, 2 * BLOCK_VIEWS, 40 - 4 * BLOCK_VIEWS]


def _fails_at_5(cfg, i, library, views):
    if i == 5:
        raise RuntimeError("image 5 cannot be made")
    return _make_image(cfg, i, library, views)


def test_a_failure_in_a_process_is_raised_and_keeps_the_staged_images(tmp_path):
    out = tmp_path / "out"
    cfg = TinyConfig(n=3 * BLOCK_VIEWS, width=48, height=32)
    with pytest.raises(RuntimeError, match="image 5 cannot be made"):
        generate(cfg, _library(), out, workers=2, make_image=_fails_at_5)
    staged = staging_dir(out)
    assert staged.is_dir() and not (staged / "records" / "000005.json").exists()
    generate(cfg, _library(), out, workers=2, make_image=_make_image)
    assert len(read_dataset(out).dataset.images) == cfg.n and not staged.exists()


def test_smoke_cutouts_among_the_flame_folders_are_method2_plumes_or_refused(tmp_path):
    """``synth cutouts --class smoke`` writes smoke sequences; given in ``flames.folders`` beside flames they are the
    plumes of a Method 2 run with ``smoke.source: cutouts``, never flames; a run that lays no plumes of them, or is
    left without flames, says so."""
    from dataclasses import replace

    from factories import tiny_flames

    from synth.flames.library import FlameLibraryConfig
    from synth.flames.sprites import is_smoke, save_sequence
    from synth.generate import run_library
    from synth.method1 import Method1Config
    from synth.method2 import Method2Config
    from synth.smoke.library import SmokeConfig
    from synth.smoke.plume import plume_library

    for seq in tiny_flames(1):
        save_sequence(tmp_path / "flames" / seq.name, seq)
    plume = plume_library(1, seed=0, frames=2)[0]
    save_sequence(tmp_path / "smoke" / plume.name, plume)
    both = FlameLibraryConfig(folders=(tmp_path / "flames", tmp_path / "smoke"))
    own = SmokeConfig(alone=0.5, source="cutouts")
    library = run_library(Method2Config(flames=both, smoke=own))
    assert [(s.name, is_smoke(s)) for s in library] == [("f0", False), (plume.name, True)]
    for cfg in (Method2Config(flames=both), Method2Config(flames=both, smoke=replace(own, source="simulated")),
                Method1Config(flames=both)):  # fmt: skip
        with pytest.raises(ValueError, match=rf"smoke cut-outs given \({plume.name}\) but the run lays no plumes"):
            run_library(cfg)
    alone = FlameLibraryConfig(folders=(tmp_path / "smoke",))
    with pytest.raises(ValueError, match="the flame folders hold smoke cut-outs only"):
        run_library(Method2Config(flames=alone, smoke=own))

"""Stand-in sets: noise-generator flames on packaged photos, exact boxes, splits, byte-identical reruns, labelled."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ground.data.boxes import mask_to_xywh
from ground.data.formats.registry import read_dataset
from synth.flames.colour import CHEMICAL_LINES
from synth.standin import (
    NOTICE,
    RARE_PALETTES,
    RARE_SHAPES,
    StandInConfig,
    jittered_crop,
    load_backgrounds,
    make_image,
    packaged_backgrounds,
    run_standin,
    split_of,
    standin_library,
)

TINY = {"width": 64, "height": 48, "sequences": 2, "frames": 48}


def test_config_is_checked() -> None:
    with pytest.raises(ValueError, match="kind"):
        StandInConfig(kind="exotic")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="splits"):
        StandInConfig(splits={"test": 0})
    with pytest.raises(ValueError, match="flame_height"):
        StandInConfig(flame_height=(0.5, 0.2))
    assert StandInConfig(splits={"train": 3, "test": 2}).n == 5


def test_splits_take_consecutive_ranges() -> None:
    cfg = StandInConfig(splits={"train": 2, "valid": 1, "test": 2})
    assert [split_of(cfg, i) for i in range(5)] == ["test", "test", "train", "train", "valid"]
    assert split_of(StandInConfig(splits={"valid": 1, "test": 2, "train": 2}), 2) == "train"  # order-free
    with pytest.raises(IndexError):
        split_of(cfg, 5)


def test_packaged_backgrounds_are_real_pictures() -> None:
    pictures = packaged_backgrounds()
    assert len(pictures) == 2 and all(p.dtype == np.uint8 and p.ndim == 3 and p.shape[2] == 3 for p in pictures)
    assert pictures[0].shape[:2] == (600, 512)  # grace_hopper.jpg, upright
    assert all(p.std() > 20 for p in pictures)  # textured, not flat


def test_user_backgrounds_and_empty_folder(tmp_path: Path) -> None:
    Image.fromarray(np.full((40, 50, 3), 90, np.uint8)).save(tmp_path / "wall.png")
    (tmp_path / "broken.jpg").write_bytes(b"not a jpeg")
    assert [p.shape for p in load_backgrounds(tmp_path)] == [(40, 50, 3)]
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no readable background"):
        load_backgrounds(tmp_path / "empty")


def test_crop_has_the_output_size_and_leaves_input_alone() -> None:
    picture = np.random.default_rng(0).integers(0, 255, (100, 140, 3), dtype=np.uint8)
    before = picture.copy()
    out = jittered_crop(picture, StandInConfig(**TINY), np.random.default_rng(1))
    assert out.shape == (48, 64, 3) and out.dtype == np.uint8 and np.array_equal(picture, before)


def test_libraries_use_the_noise_generator_and_rare_looks_unusual() -> None:
    common = standin_library(StandInConfig(kind="common", **TINY))
    rare = standin_library(StandInConfig(kind="rare", **{**TINY, "sequences": 6}))
    assert all(s.meta["generator"] == "noise" for s in common + rare)  # training sets simulate "fluid" flames
    assert all(s.meta["params"]["palette"] == "blackbody" for s in common)
    for s in rare:
        p = s.meta["params"]
        assert p["shape"] in RARE_SHAPES
        assert p["palette"] in CHEMICAL_LINES and p["palette"] in RARE_PALETTES or p["peak"] == 6.0


def test_boxes_are_the_visible_mask_boxes() -> None:
    cfg = StandInConfig(**TINY, negatives=0.0)
    library = standin_library(cfg)
    pictures = packaged_backgrounds()
    boxes = 0
    for i in range(4):
        image, masks, record = make_image(cfg, i, library, pictures)
        assert image.shape == (48, 64, 3)
        assert record["boxes"] == [mask_to_xywh(m).tolist() for m in masks]
        boxes += len(masks)
    assert boxes > 0


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("standin")
    cfg = StandInConfig(kind="rare", splits={"train": 4, "test": 3}, seed=3, **TINY)
    run_standin(cfg, root / "a")
    run_standin(cfg, root / "b")
    return root / "a", root / "b"


def test_written_set_has_splits_labels_and_notice(written: tuple[Path, Path]) -> None:
    a, _ = written
    ds = read_dataset(a).dataset
    assert [img.split for img in ds.images] == ["test"] * 3 + ["train"] * 4
    assert {img.source for img in ds.images} == {"standin:rare"}
    assert (a / "STAND-IN.txt").read_text().strip() == NOTICE and (a / "contact_sheet.png").is_file()
    manifest = json.loads((a / "manifest.json").read_text())
    assert "stand-in" in json.dumps(manifest).lower()
    assert all("source" not in entry for entry in manifest["images"])  # no pointers into the removed staging
    assert not any(p.name.endswith(".parts") for p in a.parent.iterdir())  # staging removed


def test_same_seed_gives_byte_identical_sets(written: tuple[Path, Path]) -> None:
    a, b = written
    assert (a / "annotations.json").read_bytes() == (b / "annotations.json").read_bytes()
    files = sorted(p.relative_to(a) for p in (a / "images").rglob("*.jpg"))
    assert len(files) == 7 and all((a / f).read_bytes() == (b / f).read_bytes() for f in files)

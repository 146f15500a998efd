"""R(m)_S(n) mixer: nested seeded draws, constant totals, clear errors, byte-identical outputs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from factories import tiny_pool

from curate.mix import (
    MixError,
    Mixture,
    build_mixture,
    paper_grid,
    parse_mixture,
    parse_mixtures,
    parse_seeds,
    real_subset,
    write_mixture,
)
from ground.data.dataset import Dataset
from ground.data.formats.coco import read_coco


@pytest.fixture(scope="module")
def pools(tmp_path_factory: pytest.TempPathFactory) -> tuple[Dataset, Dataset]:
    base = tmp_path_factory.mktemp("pools")
    return tiny_pool(base / "real", 40, "real:cams"), tiny_pool(base / "synth", 40, "synth:method2", "fire")


def _files(ds: Dataset, role: str) -> set[str]:
    return {img.file_name for img in ds.images if img.source.startswith(role)}


def test_parse_names_and_seeds() -> None:
    assert parse_mixture("R750_S250") == Mixture(750, 250)
    assert [m.name for m in parse_mixtures("R10_S0, R5_S5,R10_S0")] == ["R10_S0", "R5_S5"]
    assert parse_seeds("0-2,7") == [0, 1, 2, 7]
    for bad in ("R750S250", "r1_s1", "R0_S0", ""):
        with pytest.raises(MixError):
            parse_mixtures(bad)
    with pytest.raises(MixError):
        parse_seeds("a-b")


def test_paper_grid_has_the_three_strategies() -> None:
    names = [m.name for m in paper_grid()]
    assert names == [
        "R250_S0", "R500_S0", "R750_S0", "R1000_S0",
        "R750_S250", "R500_S500", "R250_S750",
        "R0_S250", "R0_S500", "R0_S750", "R0_S1000",
    ]  # fmt: skip


def test_nested_draws_and_constant_totals(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    real, synth = pools
    grid = [Mixture(40 - k, k) for k in range(0, 41, 10)]
    built = {m: build_mixture(real, synth, m, 3, tmp_path) for m in grid}
    for m, ds in built.items():
        assert len(ds.images) == 40 == m.total
        assert len(_files(ds, "real:")) == m.real and len(_files(ds, "synth:")) == m.synth
        assert {img.split for img in ds.images} == {"train"}
    for small, large in zip(grid[1:], grid[:-1]):  # fewer real images: a subset of the larger draw
        assert _files(built[small], "real:") <= _files(built[large], "real:")
        assert _files(built[large], "synth:") <= _files(built[small], "synth:")
    other_seed = build_mixture(real, synth, Mixture(20, 20), 4, tmp_path)
    assert _files(other_seed, "real:") != _files(built[Mixture(20, 20)], "real:")


def test_the_real_subset_is_what_the_mixture_trains_on(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    real, synth = pools
    for mix, seed in ((Mixture(15, 25), 3), (Mixture(15, 0), 3), (Mixture(30, 10), 4)):
        subset = real_subset(real, mix, seed)
        files = {real.image_path(img).resolve().as_posix() for img in subset.images}
        assert files == _files(build_mixture(real, synth, mix, seed, tmp_path), "real:")  # whatever the synthetic side
        assert len(subset.annotations) == sum(a.image_id in {i.id for i in subset.images} for a in real.annotations)
    assert real_subset(real, Mixture(0, 40), 3).images == ()


def test_draw_ignores_reader_order(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    real, synth = pools
    from dataclasses import replace

    shuffled = replace(real, images=tuple(reversed(real.images)))
    a = build_mixture(real, synth, Mixture(10, 5), 0, tmp_path)
    b = build_mixture(shuffled, synth, Mixture(10, 5), 0, tmp_path)
    assert _files(a, "real:") == _files(b, "real:")


def test_too_many_images_is_a_clear_error(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    real, synth = pools
    with pytest.raises(MixError, match=r"R41_S0: asks for 41 real images .* has only 40"):
        build_mixture(real, synth, Mixture(41, 0), 0, tmp_path)
    with pytest.raises(MixError, match="synthetic"):
        build_mixture(real, synth, Mixture(0, 50), 0, tmp_path)


def test_written_mixture_is_byte_identical_and_references_images(
    pools: tuple[Dataset, Dataset], tmp_path: Path
) -> None:
    real, synth = pools
    folders = [write_mixture(real, synth, Mixture(6, 4), 1, tmp_path / run) for run in ("a", "b")]
    for name in ("annotations.json", "mixture.json"):
        assert (folders[0] / name).read_bytes() == (folders[1] / name).read_bytes()
    labels = [sorted(p.read_bytes() for p in (f / "labels").rglob("*.txt")) for f in folders]
    assert labels[0] == labels[1] and len(labels[0]) == 10
    images = sorted((folders[0] / "images" / "train").iterdir())
    assert len(images) == 10 and all(p.is_symlink() for p in images)
    record = json.loads((folders[0] / "mixture.json").read_text())
    assert record["mixture"] == "R6_S4" and sum(e["source"].startswith("synth:") for e in record["images"]) == 4
    assert all(Path(e["from"]).is_file() for e in record["images"])
    back = read_coco(folders[0]).dataset
    assert len(back.images) == 10 and len(back.annotations) == 10


def test_data_yaml_val_names_a_yolo_validation_set(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    import yaml

    from ground.data.writer import write_dataset

    real, synth = pools
    default = write_mixture(real, synth, Mixture(4, 4), 0, tmp_path / "default")
    doc = yaml.safe_load((default / "data.yaml").read_text())
    assert doc["val"] == doc["train"] and "val = the training images" in (default / "data.yaml").read_text()
    write_dataset(real, tmp_path / "val", ("coco", "yolo"), "copy")
    val = read_coco(tmp_path / "val").dataset
    folder = write_mixture(real, synth, Mixture(4, 4), 0, tmp_path / "with-val", val=val)
    doc = yaml.safe_load((folder / "data.yaml").read_text())
    assert doc["val"] == str((tmp_path / "val" / "images").absolute()) and doc["train"] == "images/train"
    assert "training images" not in (folder / "data.yaml").read_text()


def test_unusable_validation_sets_are_refused(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    from ground.data.writer import write_dataset

    real, synth = pools
    with pytest.raises(MixError, match="no YOLO label files"):  # COCO only: ultralytics finds no labels
        write_mixture(real, synth, Mixture(4, 4), 0, tmp_path / "a", val=real)
    smoke = tiny_pool(tmp_path / "smoke-src", 3, "real:x", "smoke")
    write_dataset(smoke, tmp_path / "smoke", ("coco", "yolo"), "copy")
    with pytest.raises(MixError, match="would mix them up"):
        write_mixture(real, synth, Mixture(4, 4), 0, tmp_path / "b", val=read_coco(tmp_path / "smoke").dataset)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()

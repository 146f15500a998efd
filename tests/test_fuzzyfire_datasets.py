"""Dataset references and the experiment's datasets: each read from disk once, each split prepared once with the
experiment's classes in their order."""

from __future__ import annotations

from pathlib import Path

import pytest

import ground.data.formats.registry as registry
from fuzzyfire.datasets import DataRef, Datasets, load_data
from fuzzyfire.stages import folder_ref
from ground.data.load import SplitError


@pytest.fixture
def coco_reads(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The paths every COCO read of the registry is given, in order."""
    paths: list[str] = []
    real = registry.read_coco

    def counting(path, **kwargs):
        paths.append(Path(path).as_posix())
        return real(path, **kwargs)

    monkeypatch.setattr(registry, "read_coco", counting)
    return paths


def test_load_data_picks_the_split_and_fixes_classes(split_folder: Path) -> None:
    ref = folder_ref(split_folder, Path("/"), "auto", {}, ())
    train = load_data(ref.with_split("train"), ["fire"])
    assert len(train.images) == 6 and train.category_names == ["fire"]
    full = load_data(ref, ["fire", "smoke"])
    assert len(full.images) == 10 and len(full.annotations) > len(train.annotations)
    assert load_data(ref, ["smoke", "fire"]).category_names == ["smoke", "fire"]
    with pytest.raises(SplitError, match="no split 'valid' \\(splits: 'train', 'test'\\)"):
        load_data(ref.with_split("valid"), ["fire"])


def test_each_dataset_is_read_once_and_each_split_prepared_once(split_folder: Path, coco_reads: list[str]) -> None:
    ref = folder_ref(split_folder, Path("/"), "coco", {}, ())
    datasets = Datasets(["fire"])
    train, test = datasets.get(ref.with_split("train")), datasets.get(ref.with_split("test"))
    assert datasets.get(ref.with_split("train")) is train and datasets.read(ref) is datasets.read(ref.with_split("x"))
    assert len(train.images) + len(test.images) == 10 and test.category_names == ["fire"]
    assert len(coco_reads) == 1  # one read for both splits and the raw dataset
    dropped = Datasets(["fire", "smoke"]).get(DataRef(ref.path, ref.identity, "coco", None, drop=("smoke",)))
    assert dropped.category_names == ["fire", "smoke"] and {a.category_id for a in dropped.annotations} == {1}
    assert len(coco_reads) == 2  # another Datasets reads again: the cache is the experiment's, not global


def test_a_dataset_read_under_other_aliases_is_another_read(split_folder: Path, coco_reads: list[str]) -> None:
    datasets = Datasets(["fire", "smoke"])
    plain = folder_ref(split_folder, Path("/"), "coco", {}, ())
    renamed = folder_ref(split_folder, Path("/"), "coco", {"smoke": "fire"}, ())
    assert len(datasets.get(renamed).annotations) == len(datasets.get(plain).annotations)
    assert {a.category_id for a in datasets.get(renamed).annotations} == {1} and len(coco_reads) == 2


def test_a_holdout_share_keeps_exactly_the_held_out_photos(tmp_path: Path) -> None:
    from factories_experiment import fire_free_photos

    from ground.data.holdout import held_out, held_out_images

    folder = fire_free_photos(tmp_path / "photos", 10)
    ref = folder_ref(folder, tmp_path, "auto", {}, (), None, 0.5)
    assert ref.identity["holdout"] == 0.5 and "holdout" not in folder_ref(folder, tmp_path, "auto", {}, ()).identity
    with pytest.raises(FileNotFoundError, match=r"^tests\.night\.path: 'gone': dataset not found \(no /"):
        folder_ref(Path("gone"), tmp_path, "auto", {}, (), key="tests.night.path")  # the key, not only the folder
    assert ref.with_split(None).holdout == 0.5
    ds = Datasets(("fire",)).get(ref)
    expected = {p.name for p in folder.iterdir() if held_out(p, 0.5)}
    assert {Path(img.file_name).name for img in ds.images} == expected and 0 < len(expected) < 10
    assert ds.category_names == ["fire"] and not ds.annotations  # a negatives-only set with the experiment's class
    assert [img.file_name for img in load_data(ref, ("fire",)).images] == [img.file_name for img in ds.images]
    with pytest.raises(ValueError, match="none of its 10 images is held out at share 1e-09"):
        held_out_images(Datasets(("fire",)).get(folder_ref(folder, tmp_path, "auto", {}, ())), 1e-9, folder)


def test_the_shared_fire_free_photos_hold_out_68_at_a_quarter(shared_data: Path) -> None:
    ref = folder_ref(shared_data / "fire-free", shared_data, "auto", {}, (), None, 0.25)
    assert len(Datasets(("fire",)).get(ref).images) == 68  # of 295: the photos no pool with holdout 0.25 shows


def test_a_label_declares_a_folder_image_labelled_and_a_stand_in_is_read_at_the_image_level(tmp_path: Path) -> None:
    """``label`` enters the identity and the read; an undeclared folder is read as negatives only, and the
    reading says which; a stand-in with a label is its image-level view."""
    import json

    from factories import write_image
    from factories_experiment import fire_free_photos

    from ground.data.dataset import DatasetBuilder

    folder = fire_free_photos(tmp_path / "fires", 3)
    declared = folder_ref(folder, tmp_path, "auto", {}, (), label="fire")
    plain = folder_ref(folder, tmp_path, "auto", {}, ())
    assert declared.identity["label"] == "fire" and "label" not in plain.identity
    data = Datasets(("fire",))
    assert data.get(declared).labelled_ids() == {1, 2, 3} and data.get(plain).num_negatives() == 3
    assert data.reading(declared).startswith("3 images, each declared 'fire'")
    assert data.reading(plain) == "3 images, no label files: a negatives-only set"
    b = DatasetBuilder(tmp_path, ["fire"])
    b.add_box(b.add_image("a.png", 8, 8), "fire", (1, 1, 2, 2))
    b.add_image("b.png", 8, 8)
    for name in ("a.png", "b.png"):
        write_image(tmp_path / "standin" / name, 8, 8)
    (tmp_path / "standin" / "annotations.json").write_text(json.dumps(b.build().to_coco()))
    ref = DataRef(tmp_path / "standin", {"kind": "standin"}, "coco", standin=True, label="fire")
    ds = Datasets(("fire",)).get(ref)
    assert [i.labels for i in ds.images] == [("fire",), ()] and not ds.annotations
    assert Datasets(("fire",)).reading(ref) == "a stand-in read at the image level: 1 of 2 images hold fire"

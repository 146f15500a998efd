import os
from pathlib import Path

import pytest
import yaml
from factories import write_image, write_yolo_dataset

from ground.data.formats.yolo import read_yolo
from ground.data.formats.yolo_layout import LabelLocator, last_image_folder
from ground.data.load import SplitError, pick_split

ROW = "0 0.5 0.5 0.5 0.5\n"


def _dataset(root: Path, images: str, labels: str, n: int = 3) -> None:
    for k in range(n):
        write_image(root / images / f"i{k}.jpg", 20, 10, seed=k)
        (root / labels).mkdir(parents=True, exist_ok=True)
        (root / labels / f"i{k}.txt").write_text(ROW)


def _read(root: Path):
    result = read_yolo(root, names=["fire"])
    return result, {Path(i.file_name).name: i.split for i in result.dataset.images}


def test_singular_and_voc_style_folder_names(tmp_path):
    for images, labels in [("train/image", "train/label"), ("JPEGImages", "labels"), ("Images/val", "Labels/val")]:
        root = tmp_path / images.replace("/", "_")
        _dataset(root, images, labels)
        result, splits = _read(root)
        assert len(result.dataset.annotations) == 3, (images, [str(p) for p in result.problems])
        assert not [p for p in result.problems if p.level != "info"]
    assert splits == {"i0.jpg": "val", "i1.jpg": "val", "i2.jpg": "val"}


def test_symlinked_images_and_labels_folders(tmp_path):
    store = tmp_path / "store"
    _dataset(store, "imgs_somewhere", "txt_somewhere")
    root = tmp_path / "ds"
    (root / "train").mkdir(parents=True)
    os.symlink(store / "imgs_somewhere", root / "train" / "images")
    os.symlink(store / "txt_somewhere", root / "train" / "labels")
    result, splits = _read(root)
    assert splits == {"i0.jpg": "train", "i1.jpg": "train", "i2.jpg": "train"}
    assert len(result.dataset.annotations) == 3 and not result.problems


def test_unknown_label_folder_is_an_error_naming_both_folders(tmp_path):
    root = tmp_path / "odd"
    _dataset(root, "train/images", "train/annotations_txt", n=4)
    result, _ = _read(root)
    errors = [p for p in result.problems if p.level == "error"]
    assert len(errors) == 1 and errors[0].path == str(root / "train" / "annotations_txt")
    assert "4 label files (i0.txt, i1.txt, i2.txt, ...) match no image" in errors[0].reason
    assert "4 share their names with images that have no label file, in train/images" in errors[0].reason
    warnings = [p for p in result.problems if p.level == "warning"]
    assert len(warnings) == 1 and "none of its 4 images has a label file" in warnings[0].reason
    assert result.unlabelled == frozenset(i.id for i in result.dataset.images)


def test_data_yaml_list_valued_splits_and_image_lists(tmp_path):
    root = tmp_path / "y"
    _dataset(root, "images/part1", "labels/part1", n=2)
    _dataset(root, "images/part2", "labels/part2", n=1)
    write_image(root / "images" / "hold" / "h.jpg", 20, 10)
    (root / "labels" / "hold").mkdir()
    (root / "labels" / "hold" / "h.txt").write_text(ROW)
    (root / "val.txt").write_text("images/hold/h.jpg\n")
    doc = {"path": ".", "train": ["images/part1", "images/part2"], "val": "val.txt", "names": ["fire"]}
    (root / "data.yaml").write_text(yaml.safe_dump(doc))
    write_image(root / "images" / "extra" / "e.jpg", 20, 10)  # in no split of data.yaml
    result = read_yolo(root)
    splits = {i.file_name: i.split for i in result.dataset.images}
    assert splits == {
        "images/hold/h.jpg": "val",
        "images/part1/i0.jpg": "train",
        "images/part1/i1.jpg": "train",
        "images/part2/i0.jpg": "train",
    }
    assert len(result.dataset.annotations) == 4
    assert [p.reason for p in result.problems] == [
        f"1 images below {root} are in none of its splits (train:, val:) and are not read (e.g. images/extra/e.jpg)"
    ]


def test_locator_and_image_folder_names(tmp_path):
    assert last_image_folder(("a", "Images", "b", "x.jpg")) == 1
    assert last_image_folder(("images", "x.jpg")) == 0
    assert last_image_folder(("x.jpg",)) is None
    (tmp_path / "s" / "label").mkdir(parents=True)
    locator = LabelLocator(tmp_path)
    assert locator.locate(tmp_path / "s" / "image" / "a.b.jpg") == (tmp_path / "s" / "label" / "a.b.txt", "s")
    assert locator.locate(tmp_path / "flat" / "x.png") == (tmp_path / "flat" / "x.txt", "flat")


def test_data_yaml_entries_may_point_outside_the_folder(tmp_path):
    """As fuzzyfire mix writes them: val names the real set's validation images by absolute path."""
    _dataset(tmp_path / "real", "valid/images", "valid/labels", n=2)
    mix = tmp_path / "mix"
    _dataset(mix, "images/train", "labels/train", n=3)
    doc = {
        "path": str(mix),
        "train": "images/train",
        "val": str(tmp_path / "real" / "valid" / "images"),
        "names": ["fire"],
    }
    (mix / "data.yaml").write_text(yaml.safe_dump(doc))
    result = read_yolo(mix / "data.yaml")
    splits = {i.file_name: i.split for i in result.dataset.images}
    outside = (tmp_path / "real" / "valid" / "images").as_posix()
    assert splits == {
        "images/train/i0.jpg": "train",
        "images/train/i1.jpg": "train",
        "images/train/i2.jpg": "train",
        f"{outside}/i0.jpg": "val",
        f"{outside}/i1.jpg": "val",
    }
    assert len(result.dataset.annotations) == 5 and not result.problems
    assert result.dataset.image_path(result.dataset.images[-1]).is_file()


def test_a_split_entry_that_names_nothing_is_said_with_the_yaml_file_and_key(tmp_path):
    """The dataset file (any name, its path: elsewhere) and the key, not only the folder, in the reader's line and
    in the error of a command that asks for the split."""
    root = tmp_path / "ds"
    _dataset(root, "images/train", "labels/train", n=2)
    spec = tmp_path / "specs" / "fires.yaml"
    spec.parent.mkdir()
    spec.write_text(yaml.safe_dump({"path": "../ds", "train": "images/train", "val": "images/val", "names": ["fire"]}))
    result = read_yolo(spec)
    assert {i.split for i in result.dataset.images} == {"train"}
    [line] = [p for p in result.problems if p.code == "yaml-splits"]
    assert line.level == "warning" and line.path == str(spec)
    assert line.reason.startswith(f"val: 'images/val' (no {root / 'images' / 'val'}) is not a folder or image list")
    assert line.reason.endswith(f"layout of {root}, which has no 'val' split (splits: 'train')")
    with pytest.raises(SplitError) as err:
        pick_split(result.dataset, "val", root)
    assert f"{spec}: val: 'images/val' (no {root / 'images' / 'val'}) is not a folder or image list" in str(err.value)


def test_roboflow_entries_that_point_nowhere_are_one_info_line(tmp_path):
    write_yolo_dataset(tmp_path / "rf")
    result = read_yolo(tmp_path / "rf")
    [line] = [p for p in result.problems if p.code == "yaml-splits"]
    assert line.level == "info" and line.path == str(tmp_path / "rf" / "data.yaml")
    assert line.reason.startswith("train: '../train/images' (no ") and ", val: '../valid/images' (no " in line.reason
    assert "are not folders or image lists here: splits taken from the folder layout" in line.reason
    assert "split_notes" in result.dataset.info


def test_a_listed_image_that_does_not_exist_names_the_list_line_and_key(tmp_path):
    root = tmp_path / "y"
    _dataset(root, "images/a", "labels/a", n=2)
    (root / "val.txt").write_text("images/a/i0.jpg\nimages/a/gone.jpg\n")
    (root / "data.yaml").write_text(yaml.safe_dump({"train": "images/a", "val": "val.txt", "names": ["fire"]}))
    result = read_yolo(root)
    [error] = [p for p in result.problems if p.level == "error"]
    assert error.path == f"{root / 'val.txt'}:2"
    assert error.reason == f"listed image 'images/a/gone.jpg' does not exist (val: in {root / 'data.yaml'})"
    assert len(result.dataset.images) == 2


def test_class_names_messages_name_the_yaml_and_its_keys(tmp_path):
    root = tmp_path / "n"
    _dataset(root, "images", "labels", n=1)
    (root / "labels" / "i0.txt").write_text("0 0.5 0.5 0.5 0.5\n2 0.5 0.5 0.2 0.2\n")
    (root / "data.yaml").write_text("nc: 3\nnames: {0: fire, 2: sparks}\n")
    result = read_yolo(root)
    assert result.dataset.category_names == ["fire", "1", "sparks"]  # id 2 keeps its name; the gap is named
    reasons = [p.reason for p in result.problems if p.path == str(root / "data.yaml")]
    assert any(r.startswith("names: ids must be 0..1, got [0, 2]") for r in reasons), reasons
    assert any(r.startswith("names: class '1' is not a known class") for r in reasons), reasons
    assert any(r.startswith("names: class 'sparks' is not a known class") for r in reasons), reasons
    (root / "data.yaml").write_text("nc: 2\nnames: [fire]\n")
    [nc] = [p for p in read_yolo(root).problems if p.reason.startswith("nc:")]
    assert nc.path == str(root / "data.yaml") and nc.reason == "nc: 2 but names: lists 1 names (the names used)"

import os
from pathlib import Path

import yaml
from factories import write_image

from curate.core.formats.yolo import read_yolo
from curate.core.formats.yolo_layout import LabelLocator, last_image_folder

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
        f"1 images below {root} are in none of its splits and are not read (e.g. images/extra/e.jpg)"
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

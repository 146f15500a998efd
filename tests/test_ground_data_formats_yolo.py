from pathlib import Path

import numpy as np
import pytest
import yaml
from factories import write_image, write_yolo_dataset

from ground.data.dataset import Dataset
from ground.data.formats.yolo import read_dfire, read_yolo
from ground.data.writer import write_dataset


def _problems(result, level=None):
    return [str(p) for p in result.problems if level is None or p.level == level]


def test_reads_roboflow_layout_with_splits_and_negatives(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    result = read_yolo(tmp_path / "ds")
    ds = result.dataset
    assert ds.category_names == ["fire", "smoke"]
    assert sorted(img.file_name for img in ds.images) == [
        "train/images/a.jpg",
        "train/images/b.jpg",
        "valid/images/c.jpg",
        "valid/images/d.png",
    ]
    assert {img.file_name: img.split for img in ds.images}["valid/images/d.png"] == "valid"
    assert len(ds.annotations) == 3 and ds.num_negatives() == 2
    a = next(img for img in ds.images if img.file_name.endswith("a.jpg"))
    boxes = {ann.bbox for ann in ds.annotations if ann.image_id == a.id}
    assert (24.0, 12.0, 16.0, 24.0) in boxes  # 0.5 0.5 0.25 0.5 of 64x48
    assert all(img.source == "real:ds" for img in ds.images)
    # data.yaml's Roboflow entries (../train/images) point outside: the folder layout decides, said as info
    assert "splits taken from the folder layout" in result.problems[0].reason
    assert [p.level for p in result.problems[1:]] == ["info"]  # d.png has no label file
    assert "image without label file" in result.problems[1].reason


def test_ultralytics_layout_and_flat_layout(tmp_path):
    root = tmp_path / "u"
    write_image(root / "images" / "train" / "x.jpg", 20, 10)
    (root / "labels" / "train").mkdir(parents=True)
    (root / "labels" / "train" / "x.txt").write_text("0 0.5 0.5 1 1\n")
    ds = read_yolo(root, names=["Fire"]).dataset
    assert ds.images[0].split == "train" and ds.annotations[0].bbox == (0.0, 0.0, 20.0, 10.0)
    flat = tmp_path / "flat"
    write_image(flat / "y.png", 20, 10)
    (flat / "y.txt").write_text("0 0.5 0.5 0.5 0.5\n")
    (flat / "classes.txt").write_text("smoke\n")
    ds = read_yolo(flat).dataset
    assert ds.category_names == ["smoke"] and ds.annotations[0].bbox == (5.0, 2.5, 10.0, 5.0)


def test_data_yaml_dict_names_and_case_mapping(tmp_path):
    root = tmp_path / "d"
    write_image(root / "train" / "images" / "x.jpg", 10, 10)
    (root / "train" / "labels").mkdir(parents=True)
    (root / "train" / "labels" / "x.txt").write_text("1 0.5 0.5 0.2 0.2\n")
    (root / "data.yaml").write_text(yaml.safe_dump({"names": {0: "Smoke", 1: "FIRE"}, "nc": 2}))
    ds = read_yolo(root).dataset
    assert ds.category_names == ["smoke", "fire"]
    assert ds.categories[ds.annotations[0].category_id - 1].name == "fire"


def test_every_bad_label_is_reported(tmp_path):
    root = tmp_path / "bad"
    write_yolo_dataset(root)
    lab = root / "train" / "labels"
    (lab / "a.txt").write_text(
        "0 0.5 0.5 0.25 0.5\n"  # fine
        "7 0.5 0.5 0.1 0.1\n"  # class out of range
        "0 0.95 0.5 0.2 0.2\n"  # reaches outside -> clipped
        "0 0.5 0.5 0 0.2\n"  # zero area
        "0 nan 0.5 0.1 0.1\n"  # NaN
        "0 0.5 0.5\n"  # malformed
        "x 1 2 3 4\n"  # not numbers
    )
    (lab / "orphan.txt").write_text("0 0.5 0.5 0.1 0.1\n")  # label without image
    write_image(root / "train" / "images" / "b.png", 10, 10)  # duplicate stem with b.jpg
    (root / "train" / "images" / "broken.jpg").write_bytes(b"not a jpeg")
    result = read_yolo(root)
    text = "\n".join(_problems(result))
    for needle in [
        "a.txt:2: class id 7 out of range (classes 0..1)",
        "a.txt:3: box",
        "reaches outside the 64x48 image (clipped)",
        "a.txt:4: box",
        "zero or negative area",
        "a.txt:5: box [nan",
        "NaN",
        "a.txt:6: malformed label row: 3 values",
        "a.txt:7: malformed label row 'x 1 2 3 4' (not numbers)",
        "orphan.txt: label file without an image",
        "duplicate file stem: b.jpg and b.png share b.txt",
        "broken.jpg: unreadable image",
    ]:
        assert needle in text, needle
    a = next(img for img in result.dataset.images if img.file_name.endswith("a.jpg"))
    kept = sorted(ann.bbox for ann in result.dataset.annotations if ann.image_id == a.id)
    np.testing.assert_allclose(kept, [(24.0, 12.0, 16.0, 24.0), (54.4, 19.2, 9.6, 9.6)])  # 2nd one clipped
    clipped = [p for p in result.problems if "clipped" in p.reason]
    assert [p.level for p in clipped] == ["warning"]
    assert all(p.level == "error" for p in result.problems if "dropped" in p.reason or "without an image" in p.reason)


def test_yolo_coco_yolo_round_trip_exact(tmp_path):
    rows = write_yolo_dataset(tmp_path / "src")
    first = read_yolo(tmp_path / "src").dataset
    write_dataset(first, tmp_path / "coco", ["coco"])
    from ground.data.formats.coco import read_coco

    via_coco = read_coco(tmp_path / "coco").dataset
    write_dataset(via_coco, tmp_path / "yolo", ["yolo"])
    for stem, expected in rows.items():
        split = "valid" if stem == "c" else "train"
        text = (tmp_path / "yolo" / "labels" / split / f"{stem}.txt").read_text()
        got = [[float(v) for v in line.split()] for line in text.splitlines()]
        assert len(got) == len(expected)
        if expected:
            np.testing.assert_allclose(np.array(got), np.array(expected, dtype=float), atol=1e-6)
    again = read_yolo(tmp_path / "yolo").dataset
    _assert_same_boxes(first, again)


def _assert_same_boxes(a: Dataset, b: Dataset) -> None:
    def table(ds):
        names = {img.id: img.file_name.rsplit("/", 1)[-1] for img in ds.images}
        cats = {c.id: c.name for c in ds.categories}
        return sorted((names[x.image_id], cats[x.category_id], *np.round(x.bbox, 6)) for x in ds.annotations)

    assert table(a) == table(b)
    assert len(a.images) == len(b.images)


def test_written_data_yaml_is_ultralytics_shaped(tmp_path):
    write_yolo_dataset(tmp_path / "src")
    write_dataset(read_yolo(tmp_path / "src").dataset, tmp_path / "out", ["yolo"])
    doc = yaml.safe_load((tmp_path / "out" / "data.yaml").read_text())
    assert doc["train"] == "images/train" and doc["val"] == "images/valid"
    assert doc["names"] == {0: "fire", 1: "smoke"} and doc["nc"] == 2
    assert (tmp_path / "out" / "images" / "train" / "a.jpg").is_file()
    assert (tmp_path / "out" / "labels" / "valid" / "d.txt").read_text() == ""  # negatives get empty labels


def test_dfire_ids(tmp_path):
    root = tmp_path / "dfire"
    write_image(root / "train" / "images" / "f.jpg", 10, 10)
    (root / "train" / "labels").mkdir(parents=True)
    (root / "train" / "labels" / "f.txt").write_text("0 0.5 0.5 0.2 0.2\n1 0.5 0.5 0.4 0.4\n")
    ds = read_dfire(root).dataset
    names = [ds.categories[a.category_id - 1].name for a in ds.annotations]
    assert names == ["smoke", "fire"]


def test_missing_names_reported(tmp_path):
    root = tmp_path / "nonames"
    write_image(root / "images" / "x.jpg", 10, 10)
    (root / "labels").mkdir()
    (root / "labels" / "x.txt").write_text("0 0.5 0.5 0.2 0.2\n")
    result = read_yolo(root)
    assert result.dataset.category_names == ["0"]
    assert any("no data.yaml or classes.txt" in p.reason for p in result.problems)
    assert any("class '0' is not a known class" in p.reason for p in result.problems)


def test_not_a_folder():
    with pytest.raises(FileNotFoundError):
        read_yolo("/nonexistent/folder")


@pytest.mark.shared_data
def test_fire_smoke_608_keeps_every_image_and_row(shared_data, tmp_path):
    src = shared_data / "fire-smoke-608"
    rows = sum(len([ln for ln in p.read_text().splitlines() if ln.strip()]) for p in src.glob("*/labels/*.txt"))
    result = read_yolo(src)
    assert len(result.dataset.images) == 979
    assert len(result.dataset.annotations) == rows
    assert [p for p in result.problems if p.level == "error"] == []
    assert set(result.dataset.category_names) == {"fire", "default", "smoke"}
    assert set(result.dataset.splits) == {"train", "valid", "test"}


def test_ultralytics_label_path_replaces_the_last_images_folder():
    from ground.data.formats.yolo import ultralytics_label_path

    assert ultralytics_label_path(Path("/d/images/valid/images/a.b.jpg")) == Path("/d/images/valid/labels/a.b.txt")
    assert ultralytics_label_path(Path("/d/valid/images/x.png")) == Path("/d/valid/labels/x.txt")
    assert ultralytics_label_path(Path("/d/images.jpg")) is None


@pytest.mark.parametrize("path_entry", ["absolute", "relative", "none", "elsewhere"])
def test_a_data_yaml_file_means_its_dataset(tmp_path, path_entry):
    from ground.data.formats.registry import detect_format, read_dataset

    root = tmp_path / "datasets" / "fire"
    for split in ("train", "val"):
        write_image(root / "images" / split / f"{split}0.jpg", 20, 10)
        (root / "labels" / split).mkdir(parents=True)
        (root / "labels" / split / f"{split}0.txt").write_text("0 0.5 0.5 1 1\n")
    doc = {"train": "images/train", "val": ["images/val"], "names": {0: "fire"}}
    if path_entry == "none":
        yaml_file = root / "fire.yaml"
    else:
        yaml_file = tmp_path / "configs" / "fire.yaml"
        doc["path"] = {"absolute": str(root), "relative": "../datasets/fire", "elsewhere": "/nowhere/fire"}[path_entry]
    yaml_file.parent.mkdir(parents=True, exist_ok=True)
    yaml_file.write_text(yaml.safe_dump(doc))
    assert detect_format(yaml_file) == "yolo"
    result = read_dataset(yaml_file)
    if path_entry == "elsewhere":  # path: does not exist here: the file's folder is the root, said as a warning
        assert "not a folder here" in result.problems[0].reason and not result.dataset.images
        return
    ds = result.dataset
    assert {img.file_name: img.split for img in ds.images} == {
        "images/train/train0.jpg": "train",
        "images/val/val0.jpg": "val",
    }
    assert ds.category_names == ["fire"] and len(ds.annotations) == 2
    assert ds.root == root or ds.root.resolve() == root.resolve()

from pathlib import Path

import pytest

from ground.data.dataset import DatasetBuilder, merge


def _ds(root: Path, names, boxes):
    b = DatasetBuilder(root, names)
    img = b.add_image("a.jpg", 100, 50, source="real:x", split="train")
    b.add_image("neg.jpg", 10, 10, source="real:x", split="valid")
    for name, box in boxes:
        b.add_box(img, name, box)
    return b.build()


def test_builder_ids_start_at_one_and_negatives_kept(tmp_path):
    ds = _ds(tmp_path, ["fire"], [("fire", (1, 2, 3, 4)), ("smoke", (0, 0, 5, 5))])
    assert [i.id for i in ds.images] == [1, 2] and [a.id for a in ds.annotations] == [1, 2]
    assert ds.category_names == ["fire", "smoke"] and ds.num_negatives() == 1
    coco = ds.to_coco()
    assert coco["annotations"][0]["area"] == 12.0 and coco["images"][1]["split"] == "valid"
    assert ds.annotations_by_image()[2] == []


def test_merge_unites_categories_by_name_without_mutating(tmp_path):
    a = _ds(tmp_path / "a", ["smoke", "fire"], [("fire", (1, 1, 2, 2))])
    b = _ds(tmp_path / "b", ["fire"], [("fire", (3, 3, 2, 2)), ("smoke", (0, 0, 1, 1))])
    a_before = a.to_coco()
    m = merge([a, b], tmp_path / "m", ["fire", "smoke"])
    assert a.to_coco() == a_before
    assert m.category_names == ["fire", "smoke"] and len(m.images) == 4
    assert [x.id for x in m.annotations] == [1, 2, 3]
    names = [m.categories[x.category_id - 1].name for x in m.annotations]
    assert names == ["fire", "fire", "smoke"]
    assert m.images[0].file_name == (tmp_path / "a" / "a.jpg").resolve().as_posix()


def test_with_and_drop_categories(tmp_path):
    ds = _ds(tmp_path, ["fire", "smoke"], [("fire", (1, 1, 2, 2)), ("smoke", (1, 1, 3, 3))])
    swapped = ds.with_categories(["smoke", "fire", "steam"])
    assert swapped.category_names == ["smoke", "fire", "steam"]
    assert [swapped.categories[a.category_id - 1].name for a in swapped.annotations] == ["fire", "smoke"]
    dropped = ds.drop_categories(["smoke"])
    assert dropped.category_names == ["fire"] and len(dropped.annotations) == 1
    with pytest.raises(ValueError, match="not in the target list"):
        ds.with_categories(["fire"])


def test_select_split(tmp_path):
    ds = _ds(tmp_path, ["fire"], [("fire", (1, 1, 2, 2))])
    assert [i.file_name for i in ds.select_split("valid").images] == ["neg.jpg"]
    assert ds.select_split("valid").annotations == ()


def _labelled(root: Path):
    b = DatasetBuilder(root)
    b.add_image("f.jpg", 10, 10, labels=("fire",))
    b.add_image("s.jpg", 10, 10, labels=("smoke",))
    b.add_image("n.jpg", 10, 10)
    return b.build()


def test_image_level_labels_hold_classes_without_boxes(tmp_path):
    ds = _labelled(tmp_path)
    assert ds.category_names == ["fire", "smoke"] and ds.image_labelled and not ds.annotations
    assert ds.labelled_ids() == {1, 2} and ds.labelled_ids([1]) == {1} and ds.num_negatives() == 1
    dropped = ds.drop_categories(["smoke"])
    assert [i.labels for i in dropped.images] == [("fire",), (), ()] and dropped.category_names == ["fire"]
    assert [i.labels for i in ds.with_categories(["smoke", "fire"]).images] == [("fire",), ("smoke",), ()]
    merged = merge([ds, ds], tmp_path / "m")
    assert [i.labels for i in merged.images] == [("fire",), ("smoke",), ()] * 2
    assert ds.to_coco()["images"][0]["labels"] == ["fire"] and "labels" not in ds.to_coco()["images"][2]


def test_the_image_level_view_of_a_boxed_set(tmp_path):
    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    b.add_box(b.add_image("a.jpg", 10, 10), "fire", (1, 1, 2, 2))
    b.add_box(b.add_image("b.jpg", 10, 10), "smoke", (1, 1, 2, 2))
    b.add_box(b.add_image("c.jpg", 10, 10), "fire", (1, 1, 2, 2), iscrowd=1)
    view = b.build().at_image_level("fire")
    assert [i.labels for i in view.images] == [("fire",), (), ()]
    assert not view.annotations and view.category_names == ["fire"] and view.num_negatives() == 2
    with pytest.raises(KeyError):
        view.at_image_level("smoke")

"""One split with the wanted classes: split aliases, defaults, errors that name the splits, class order."""

from __future__ import annotations

from pathlib import Path

import pytest

from ground.data.dataset import Dataset, DatasetBuilder
from ground.data.load import SplitError, class_changes, data_classes, load_split, pick_split, with_classes


def test_pick_split_by_name_alias_or_default(split_folder: Path) -> None:
    ds = load_split(split_folder)
    assert len(pick_split(ds, "train").images) == 6 and len(pick_split(ds, "test").images) == 4
    assert pick_split(ds, None) is ds  # no default present: every image
    assert len(pick_split(ds, None, defaults=("valid", "test")).images) == 4
    with pytest.raises(SplitError, match=r"here: no split 'valid' \(splits: 'train', 'test'\)"):
        pick_split(ds, "valid", "here")
    renamed = ds.filter_images(lambda img: True)
    renamed = renamed.__class__(renamed.root, tuple(i.__class__(**{**i.__dict__, "split": "val"}) for i in ds.images),
                                ds.annotations, ds.categories)  # fmt: skip
    assert len(pick_split(renamed, "valid").images) == 10  # val, valid, validation: one split


def test_with_classes_orders_and_drops(split_folder: Path) -> None:
    ds = load_split(split_folder)
    assert ds.category_names == ["fire", "smoke"]
    only_fire = with_classes(ds, ["fire"])
    assert only_fire.category_names == ["fire"] and len(only_fire.images) == 10
    assert len(only_fire.annotations) == sum(1 for a in ds.annotations if a.category_id == 1)
    swapped = with_classes(ds, ["smoke", "fire"])
    names = {a.id: ds.categories[a.category_id - 1].name for a in ds.annotations}
    assert all(swapped.categories[a.category_id - 1].name == names[a.id] for a in swapped.annotations)
    no_smoke = with_classes(ds, ["fire", "smoke"], drop=["smoke"])
    assert no_smoke.category_names == ["fire", "smoke"] and {a.category_id for a in no_smoke.annotations} == {1}


def test_load_split_reads_one_split_with_classes(split_folder: Path) -> None:
    test = load_split(split_folder, "coco", "test", classes=["fire"])
    assert len(test.images) == 4 and test.category_names == ["fire"]
    assert load_split(split_folder, aliases={"smoke": "fire"}).category_names == ["fire"]
    with pytest.raises(SplitError, match="no split 'val'"):
        load_split(split_folder, split="val")


def test_prepare_is_load_split_on_a_dataset_already_read(split_folder: Path) -> None:
    from ground.data.load import prepare

    ds = load_split(split_folder)
    assert prepare(ds, "test", ["fire"]) == load_split(split_folder, split="test", classes=["fire"])
    with pytest.raises(SplitError, match="nowhere: no images"):
        prepare(ds.filter_images(lambda img: False), None, where="nowhere")


def test_an_alias_the_data_lacks_is_named(split_folder: Path) -> None:
    from ground.data.names import UnknownNameError

    assert load_split(split_folder, aliases={"Smoke": "fire"}).category_names == ["fire"]
    with pytest.raises(UnknownNameError, match=r"aliases 'flames': no such class \(classes: 'fire', 'smoke'\)"):
        load_split(split_folder, aliases={"flames": "fire"})


def test_a_drop_class_the_data_lacks_and_a_split_of_an_unsplit_set_are_named(split_folder: Path) -> None:
    from ground.data.load import prepare
    from ground.data.names import UnknownNameError

    ds = load_split(split_folder)
    assert prepare(ds, None, drop=["Smoke"]).category_names == ["fire"]  # any spelling of a class
    with pytest.raises(UnknownNameError, match=r"drop_classes 'smok': no such class \(classes: 'fire', 'smoke'\)"):
        prepare(ds, None, drop=["smok"])
    unsplit = ds.__class__(ds.root, tuple(i.__class__(**{**i.__dict__, "split": ""}) for i in ds.images),
                           ds.annotations, ds.categories)  # fmt: skip
    with pytest.raises(SplitError, match=r"no split 'val' \(no splits: its 10 images are one set\)"):
        pick_split(unsplit, "val")


def _fire_smoke() -> Dataset:
    """Five images: 1 fire, 2 fire + smoke, 3 smoke only, 4 smoke + default, 5 no box (a negative)."""
    b = DatasetBuilder(Path("/data"), ["smoke", "fire", "default"])
    for i in range(1, 6):
        b.add_image(f"{i}.jpg", 100, 100)
    for image, name in (
        (1, "fire"),
        (2, "fire"),
        (2, "smoke"),
        (3, "smoke"),
        (3, "smoke"),
        (4, "smoke"),
        (4, "default"),
    ):
        b.add_box(image, name, [10, 10, 20, 20])
    return b.build()


def test_an_image_whose_boxes_were_all_removed_leaves_unless_its_class_marks_a_negative() -> None:
    ds = _fire_smoke()
    fire = with_classes(ds, ["fire"])
    assert [img.file_name for img in fire.images] == ["1.jpg", "2.jpg", "5.jpg"]  # 3 and 4 had no fire: gone
    assert fire.num_negatives() == 1  # the image that never had a box stays a negative
    changes = class_changes(ds, ["fire"])
    assert changes.unstudied == {"smoke": 4, "default": 1} and changes.dropped == {} and changes.emptied == 2
    assert changes.text() == "smoke: 4 boxes not studied; default: 1 boxes not studied; 2 images had only such " \
        "boxes and left the set"  # fmt: skip
    marked = with_classes(ds, ["fire", "smoke"], negatives=["Default"])  # 4 keeps its smoke box
    assert len(marked.images) == 5 and marked.category_names == ["fire", "smoke"]
    only = ds.filter_images(lambda img: img.id != 4)
    b = DatasetBuilder(Path("/data"), ["default"])
    b.add_box(b.add_image("6.jpg", 100, 100), "default", [0, 0, 100, 100])
    from ground.data.dataset import merge

    both = merge([only, b.build()], Path("/data"), ["smoke", "fire", "default"])
    kept = with_classes(both, ["fire"], negatives=["default"])
    assert [Path(img.file_name).name for img in kept.images] == ["1.jpg", "2.jpg", "5.jpg", "6.jpg"]  # 6: negative
    assert kept.num_negatives() == 2
    counted = class_changes(both, ["fire"], negatives=["default"])
    assert (counted.negative, counted.negatives, counted.emptied) == ({"default": 1}, 1, 1)  # 3 left (smoke only)
    dropped = class_changes(ds, ["fire", "smoke"], drop=["Default"])
    assert dropped.dropped == {"default": 1} and dropped.emptied == 0  # image 4 keeps its smoke box
    assert not class_changes(ds, ["smoke", "fire", "default"])  # nothing removed


def test_the_data_classes_are_the_boxed_ones_known_first() -> None:
    ds = _fire_smoke()
    assert data_classes(ds) == ("fire", "smoke", "default")
    assert data_classes(ds, drop=["DEFAULT"]) == ("fire", "smoke")
    assert data_classes(ds.filter_images(lambda img: img.id == 5)) == ()  # no box, no class


def test_image_level_labels_follow_the_class_rules() -> None:
    """An image labelled only with a class not studied leaves the set (counted), one labelled with a negative class
    stays as a negative, an unlabelled one stays; the label classes count as the data's classes."""
    b = DatasetBuilder(Path("/x"))
    b.add_image("f.jpg", 10, 10, labels=("fire",))
    b.add_image("s.jpg", 10, 10, labels=("smoke",))
    b.add_image("d.jpg", 10, 10, labels=("default",))
    b.add_image("n.jpg", 10, 10)
    ds = b.build()
    out = with_classes(ds, ["fire"], negatives=["default"])
    assert [(i.file_name, i.labels) for i in out.images] == [("f.jpg", ("fire",)), ("d.jpg", ()), ("n.jpg", ())]
    changes = class_changes(ds, ["fire"], negatives=["default"])
    assert (changes.emptied, changes.negatives, dict(changes.unstudied)) == (1, 1, {"smoke": 1})
    assert data_classes(ds, drop=["default"]) == ("fire", "smoke")

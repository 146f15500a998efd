"""One split with the wanted classes: split aliases, defaults, errors that name the splits, class order."""

from __future__ import annotations

from pathlib import Path

import pytest

from curate.core.load import SplitError, load_split, pick_split, with_classes


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
    from curate.core.load import prepare

    ds = load_split(split_folder)
    assert prepare(ds, "test", ["fire"]) == load_split(split_folder, split="test", classes=["fire"])
    with pytest.raises(SplitError, match="nowhere: no images"):
        prepare(ds.filter_images(lambda img: False), None, where="nowhere")


def test_an_alias_the_data_lacks_is_named(split_folder: Path) -> None:
    from curate.core.names import UnknownNameError

    assert load_split(split_folder, aliases={"Smoke": "fire"}).category_names == ["fire"]
    with pytest.raises(UnknownNameError, match=r"aliases 'flames': no such class \(classes: 'fire', 'smoke'\)"):
        load_split(split_folder, aliases={"flames": "fire"})


def test_a_drop_class_the_data_lacks_and_a_split_of_an_unsplit_set_are_named(split_folder: Path) -> None:
    from curate.core.load import prepare
    from curate.core.names import UnknownNameError

    ds = load_split(split_folder)
    assert prepare(ds, None, drop=["Smoke"]).category_names == ["fire"]  # any spelling of a class
    with pytest.raises(UnknownNameError, match=r"drop_classes 'smok': no such class \(classes: 'fire', 'smoke'\)"):
        prepare(ds, None, drop=["smok"])
    unsplit = ds.__class__(ds.root, tuple(i.__class__(**{**i.__dict__, "split": ""}) for i in ds.images),
                           ds.annotations, ds.categories)  # fmt: skip
    with pytest.raises(SplitError, match=r"no split 'val' \(no splits: its 10 images are one set\)"):
        pick_split(unsplit, "val")

"""A classification layout (one sub-folder per class, optionally below split folders) read as an image-labelled
set: each image holds its folder's class, a negative folder's images none; auto-detection only when every
folder names a known class or a negative; what was read is said."""

from __future__ import annotations

from pathlib import Path

import pytest
from factories import write_image

from ground.data.formats.folders import folder_class, is_class_layout, read_folders
from ground.data.formats.images import IMAGE_LABELLED


def _layout(root: Path, folders: dict[str, int]) -> Path:
    for k, (folder, count) in enumerate(folders.items()):
        for i in range(count):
            write_image(root / folder / f"{i}.png", 32, 24, seed=10 * k + i)
    return root


def test_each_image_holds_its_folders_class_and_the_layout_is_said(tmp_path: Path) -> None:
    root = _layout(tmp_path / "set", {"fire": 3, "normal": 2})
    result = read_folders(root)
    ds = result.dataset
    assert ds.category_names == ["fire"] and not ds.annotations
    assert [(i.file_name, i.labels, i.split) for i in ds.images] == [
        ("fire/0.png", ("fire",), ""), ("fire/1.png", ("fire",), ""), ("fire/2.png", ("fire",), ""),
        ("normal/0.png", (), ""), ("normal/1.png", (), ""),
    ]  # fmt: skip
    assert ds.image_labelled and ds.num_negatives() == 2 and ds.labelled_ids() == {1, 2, 3}
    [note] = [p for p in result.problems if p.code == IMAGE_LABELLED]
    assert note.reason == ("classification layout: fire/ 3 images (fire), normal/ 2 images (no class): an "
                           "image-labelled set (image recall, no AP)")  # fmt: skip


def test_split_folders_and_kaggle_names(tmp_path: Path) -> None:
    root = _layout(tmp_path / "set", {"train/Fire_Images": 2, "test/fire_images": 1, "test/non_fire_images": 1})
    ds = read_folders(root).dataset
    assert [(i.split, i.labels) for i in ds.images] == [("test", ("fire",)), ("test", ()), *[("train", ("fire",))] * 2]
    assert folder_class("Flames") == "fire" and folder_class("no-fire") is None and folder_class("Smoke") == "smoke"


def test_auto_detection_needs_known_class_folders_and_no_loose_images(tmp_path: Path) -> None:
    assert is_class_layout(_layout(tmp_path / "a", {"fire": 1, "normal": 1}))
    assert is_class_layout(_layout(tmp_path / "b", {"valid/smoke": 1, "valid/nofire": 1}))
    assert not is_class_layout(_layout(tmp_path / "c", {"office": 1, "street": 1}))  # photos sorted by place
    assert not is_class_layout(_layout(tmp_path / "d", {"normal": 1, "empty": 1}))  # negatives only
    loose = _layout(tmp_path / "e", {"fire": 1})
    write_image(loose / "stray.png", 8, 8)
    assert not is_class_layout(loose)


def test_an_explicit_layout_takes_any_folder_name_and_names_loose_images(tmp_path: Path) -> None:
    root = _layout(tmp_path / "set", {"Brand": 1, "normal": 1})
    write_image(root / "stray.png", 8, 8)
    result = read_folders(root, aliases={"Brand": "fire"})
    assert [i.labels for i in result.dataset.images] == [("fire",), ()]
    assert any("1 images outside the class folders (skipped), e.g. stray.png" in p.reason for p in result.problems)
    assert read_folders(root).dataset.category_names == ["brand"]
    (tmp_path / "none" / "fire").mkdir(parents=True)
    with pytest.raises(ValueError, match="no class folders with images"):
        read_folders(tmp_path / "none")

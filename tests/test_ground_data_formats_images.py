"""A folder of images without labels read as a negatives-only set: every readable image a negative, the
unreadable ones named, the folder said to be what it is."""

from __future__ import annotations

from pathlib import Path

import pytest
from factories import write_image

from ground.data.formats.images import read_images


def test_every_readable_image_is_a_negative_and_the_set_is_named(tmp_path: Path) -> None:
    write_image(tmp_path / "photos" / "a.jpg", 40, 30, seed=1)
    write_image(tmp_path / "photos" / "sub" / "b.png", 20, 10, seed=2)
    (tmp_path / "photos" / "broken.jpg").write_bytes(b"not an image")
    result = read_images(tmp_path / "photos", source="real:office")
    ds = result.dataset
    assert [(i.file_name, i.width, i.height, i.source) for i in ds.images] == [
        ("a.jpg", 40, 30, "real:office"),
        ("sub/b.png", 20, 10, "real:office"),
    ]
    assert not ds.annotations and not ds.categories and result.unlabelled == {1, 2}
    assert [(p.level, p.reason) for p in result.problems][0] == (
        "info",
        "3 images, no label files: a negatives-only set",
    )
    assert result.problems[1].path.endswith("broken.jpg") and "unreadable image" in result.problems[1].reason


def test_a_folder_without_images_is_refused(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no images, labels or annotations found"):
        read_images(tmp_path / "empty")
    with pytest.raises(FileNotFoundError):
        read_images(tmp_path / "missing")


def test_a_declared_label_makes_every_image_hold_that_class(tmp_path: Path) -> None:
    write_image(tmp_path / "fires" / "a.jpg", 40, 30, seed=1)
    write_image(tmp_path / "fires" / "b.jpg", 40, 30, seed=2)
    result = read_images(tmp_path / "fires", label="Flames")
    ds = result.dataset
    assert ds.category_names == ["fire"] and [i.labels for i in ds.images] == [("fire",), ("fire",)]
    assert ds.num_negatives() == 0 and ds.image_labelled and not ds.annotations
    assert result.problems[0].code == "image-labelled"
    assert result.problems[0].reason == ("2 images, each declared 'fire' (label: fire): an image-labelled set "
                                         "(image recall, no AP)")  # fmt: skip

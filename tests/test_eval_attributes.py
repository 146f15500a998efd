"""Each computed attribute on images made to have it, and the user's CSV read with its errors named."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from eval.attributes import (
    AttributesError,
    dataset_attributes,
    fire_colour,
    image_attributes,
    merged,
    read_attributes_csv,
)
from ground.data.dataset import DatasetBuilder

NONE = np.zeros((0, 4))


def _flat(rgb: tuple[int, int, int], h: int = 120, w: int = 160) -> np.ndarray:
    return np.full((h, w, 3), rgb, dtype=np.uint8)


def _textured(level: int, rng: np.random.Generator, h: int = 120, w: int = 160) -> np.ndarray:
    """A room-like picture of mean ``level``: busy texture everywhere (no smooth sky)."""
    noise = rng.normal(0, 40, (h, w, 1)).repeat(3, axis=2)
    return np.clip(level + noise, 0, 255).astype(np.uint8)


def test_light_follows_the_scene_brightness() -> None:
    rng = np.random.default_rng(0)
    assert [image_attributes(_textured(v, rng), NONE)["light"] for v in (30, 90, 170)] == ["night", "dusk", "day"]


def test_sky_is_a_smooth_blue_top_and_not_a_busy_room() -> None:
    rng = np.random.default_rng(1)
    outdoor = _textured(120, rng)
    outdoor[:50] = (110, 160, 230)  # a clear sky over the upper 40 %
    assert image_attributes(outdoor, NONE)["sky"] == "sky"
    assert image_attributes(_textured(120, rng), NONE)["sky"] == "no sky"


def test_blur_separates_sharp_soft_and_blurred() -> None:
    rng = np.random.default_rng(2)
    sharp = _textured(120, rng)
    soft = cv2.GaussianBlur(sharp, (0, 0), 1.2)
    blurred = cv2.GaussianBlur(sharp, (0, 0), 4.0)
    assert [image_attributes(im, NONE)["blur"] for im in (sharp, soft, blurred)] == ["sharp", "soft", "blurred"]


def test_fire_colour_from_the_box_pixels() -> None:
    box = np.array([[40.0, 30.0, 60.0, 50.0]])
    cases = {"orange-red": (250, 70, 10), "yellow-white": (255, 250, 210), "chemical": (40, 220, 90)}
    for expected, rgb in cases.items():
        image = _flat((30, 30, 30))
        image[30:80, 40:100] = rgb
        assert fire_colour(image, box) == expected, expected
    blue = _flat((30, 30, 30))
    blue[30:80, 40:100] = (60, 110, 255)
    assert fire_colour(blue, box) == "chemical"


def test_size_and_count_of_the_fires_and_none_without_fire() -> None:
    image = _flat((90, 90, 90))
    small = np.array([[0.0, 0.0, 20.0, 20.0]])
    big = np.array([[0.0, 0.0, 100.0, 100.0], [0.0, 0.0, 10.0, 10.0], [5.0, 5.0, 8.0, 8.0], [1, 1, 4, 4]])
    a, b = image_attributes(image, small), image_attributes(image, big)
    assert (a["size"], a["size_fine"], a["fires"]) == ("small", "16-32", "1")
    assert (b["size"], b["size_fine"], b["fires"]) == ("large", "64-128", "4+")  # the largest box decides
    none = image_attributes(image, NONE)
    assert none["size"] is none["fires"] is none["colour"] is None and none["light"] is not None


def _dataset(tmp_path: Path) -> DatasetBuilder:
    b = DatasetBuilder(tmp_path, ["fire"])
    big = np.full((600, 800, 3), 200, np.uint8)  # bright, read at 256 px: its box scaled with it
    big[100:400, 200:500] = (250, 80, 10)
    cv2.imwrite(str(tmp_path / "a.jpg"), big[:, :, ::-1])
    cv2.imwrite(str(tmp_path / "sub_b.png"), np.full((100, 100, 3), 20, np.uint8))
    i = b.add_image("a.jpg", 800, 600, source="real:cams")
    b.add_box(i, "fire", [200, 100, 300, 300])
    b.add_image("sub_b.png", 100, 100)
    return b


def test_dataset_attributes_read_each_image_once_with_its_boxes(tmp_path: Path) -> None:
    ds = _dataset(tmp_path).build()
    attrs = dataset_attributes(ds, workers=2)
    first, second = attrs[ds.images[0].id], attrs[ds.images[1].id]
    assert (first["size"], first["colour"], first["light"], first["source"]) == (
        "large",
        "orange-red",
        "day",
        "real:cams",
    )
    assert (second["light"], second["size"], second["source"]) == ("night", None, "-")


def test_an_unreadable_image_is_named(tmp_path: Path) -> None:
    ds = _dataset(tmp_path).build()
    (tmp_path / "a.jpg").write_bytes(b"not a jpeg")
    with pytest.raises(ValueError, match="a.jpg: cannot read it"):
        dataset_attributes(ds)


def test_user_attributes_by_file_name_and_their_errors(tmp_path: Path) -> None:
    ds = _dataset(tmp_path).build()
    good = tmp_path / "mine.csv"
    good.write_text("image,attribute,value\na.jpg,camera,north\nsub_b.png,camera,south\n", encoding="utf-8")
    given = read_attributes_csv(good, ds)
    assert given == {ds.images[0].id: {"camera": "north"}, ds.images[1].id: {"camera": "south"}}
    both = merged({i.id: {"light": "day"} for i in ds.images}, {ds.images[0].id: {"camera": "north"}})
    assert both[ds.images[1].id] == {"light": "day", "camera": None}
    for text, match in (
        ("img,attribute,value\n", "header"),
        ("image,attribute,value\nzzz.jpg,camera,x\n", "mine.csv:2: no image 'zzz.jpg'"),
        ("image,attribute,value\na.jpg,light,x\n", "computed by fuzzyfire"),
        ("image,attribute,value\na.jpg,camera,x\na.jpg,camera,y\n", "camera twice"),
    ):
        good.write_text(text, encoding="utf-8")
        with pytest.raises(AttributesError, match=match):
            read_attributes_csv(good, ds)


def test_an_image_labelled_photo_gets_its_fire_colour_from_the_whole_image_and_no_size(tmp_path: Path) -> None:
    b = DatasetBuilder(tmp_path, ["fire"])
    cv2.imwrite(str(tmp_path / "blaze.png"), np.full((90, 120, 3), (10, 80, 250), np.uint8))  # BGR orange-red
    b.add_image("blaze.png", 120, 90, labels=("fire",))
    cv2.imwrite(str(tmp_path / "free.png"), np.full((90, 120, 3), (10, 80, 250), np.uint8))
    b.add_image("free.png", 120, 90)
    labelled, free = dataset_attributes(b.build()).values()
    assert labelled["colour"] == "orange-red" and labelled["size"] is labelled["fires"] is None
    assert free["colour"] is None  # no fire: no colour


def test_smoke_colour_and_density_from_the_smoke_boxes_and_fire_attributes_from_the_fire_boxes(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    scene = _textured(110, rng)
    white, black, faint = scene.copy(), scene.copy(), scene.copy()
    white[20:80, 40:120] = 235
    black[20:80, 40:120] = 30
    faint[20:80, 40:120] = np.clip(scene[20:80, 40:120].astype(int) + 4, 0, 255)  # barely there
    box = np.asarray([[40.0, 20.0, 80.0, 60.0]])
    assert image_attributes(white, NONE, smoke=box)[("smoke_colour")] == "white"
    assert (image_attributes(black, NONE, smoke=box)["smoke_colour"], image_attributes(black, NONE, smoke=box)[
        "smoke_density"]) == ("black", "dense")  # fmt: skip
    assert image_attributes(faint, NONE, smoke=box)["smoke_density"] == "thin"
    assert image_attributes(white, NONE)["smoke_colour"] is None  # no smoke box: no smoke attributes
    builder = DatasetBuilder(tmp_path, ["fire", "smoke"])
    cv2.imwrite(str(tmp_path / "s.png"), cv2.cvtColor(white, cv2.COLOR_RGB2BGR))
    image_id = builder.add_image("s.png", 160, 120)
    builder.add_box(image_id, "smoke", (40.0, 20.0, 80.0, 60.0))
    attrs = dataset_attributes(builder.build())[image_id]
    assert attrs["smoke_colour"] == "white" and attrs["size"] is None and attrs["colour"] is None  # smoke is no fire

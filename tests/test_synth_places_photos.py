"""Photo backgrounds: crops keep the aspect and carry the site along, photos are drawn by the seed without
repeats, broken photos are named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from factories import write_image

from synth.places.photos import PhotoBackgrounds, crop_to, list_photos


def test_crops_have_the_output_aspect_and_are_seeded() -> None:
    image = np.random.default_rng(0).integers(0, 256, (300, 200, 3), dtype=np.uint8)
    out, (x, y, w, h) = crop_to(image, 64, 48, np.random.default_rng(1))
    assert out.shape == (48, 64, 3) and abs(w / h - 64 / 48) < 0.02 and x + w <= 200 and y + h <= 300
    again, box = crop_to(image, 64, 48, np.random.default_rng(1))
    assert np.array_equal(out, again) and box == [x, y, w, h]


def test_broken_photos_are_skipped_and_named(tmp_path: Path) -> None:
    write_image(tmp_path / "a.jpg", 120, 90, seed=1)
    (tmp_path / "b.jpg").write_bytes(b"not a jpeg")
    photos = PhotoBackgrounds(list_photos([tmp_path]), 64, 48, seed=0)
    broken = next(v for v in range(2) if photos.photo(v).name == "b.jpg")
    rgb, depth, meta = photos.background(broken)  # the next photo in the order is used
    assert rgb.shape == (48, 64, 3) and depth.shape == (48, 64) and meta["photo"].endswith("a.jpg")
    assert list(photos.problems) == [str(tmp_path / "b.jpg")]
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no images"):
        list_photos([tmp_path / "empty"])


def test_a_photo_with_garbled_scan_data_is_skipped_and_named(tmp_path: Path) -> None:
    from factories import garbled_jpeg

    good = write_image(tmp_path / "a.jpg", 120, 90, seed=1)
    (tmp_path / "grey.jpg").write_bytes(garbled_jpeg())  # OpenCV decodes it mostly grey without an error
    photos = PhotoBackgrounds([tmp_path / "grey.jpg", good], 64, 48, seed=0)
    assert {photos.background(v)[2]["photo"] for v in range(4)} == {good.as_posix()}
    assert list(photos.problems) == [str(tmp_path / "grey.jpg")]
    assert "corrupt JPEG data" in photos.problems[str(tmp_path / "grey.jpg")]


def test_photo_fingerprints_name_and_hash_each_photo(tmp_path: Path) -> None:
    from synth.places.photos import photo_fingerprints

    for name in ("b.png", "a.jpg"):
        write_image(tmp_path / "x" / name, 32, 24)
    prints = photo_fingerprints([tmp_path / "x"])
    assert [p["name"] for p in prints] == ["a.jpg", "b.png"] and all(len(p["sha256"]) == 64 for p in prints)
    (tmp_path / "y").mkdir()
    for p in (tmp_path / "x").iterdir():
        (tmp_path / "y" / p.name).write_bytes(p.read_bytes())
    assert photo_fingerprints([tmp_path / "y"]) == prints


def test_every_photo_is_used_before_any_repeats_in_a_seeded_order(tmp_path: Path) -> None:
    for i in range(5):
        write_image(tmp_path / f"p{i}.jpg", 80, 60, seed=i)
    files = list_photos([tmp_path])
    orders = []
    for seed in (0, 1):
        photos = PhotoBackgrounds(files, 64, 48, seed=seed)
        first = [photos.photo(v).name for v in range(5)]
        assert sorted(first) == [f"p{i}.jpg" for i in range(5)]  # each once per cycle
        assert [photos.photo(v).name for v in range(5, 10)] == first
        orders.append(first)
    assert orders[0] != orders[1]  # the seed draws the order, not the alphabet


def test_a_crop_carries_the_sidecar_site_along(tmp_path: Path) -> None:
    """A fixed camera's floor polygon and horizon: flames may stand only on the floor, in every crop, and the
    pseudo depth grows towards the horizon."""
    write_image(tmp_path / "cam.jpg", 200, 150, seed=3)
    (tmp_path / "cam.yaml").write_text(
        "horizon: 0.4\ncamera_height: 3.0\nground: [[0.5, 0.4], [1.0, 0.4], [1.0, 1.0], [0.5, 1.0]]\n"
    )
    photos = PhotoBackgrounds(list_photos([tmp_path]), 64, 48, seed=0)
    for view in range(4):
        rgb, depth, meta = photos.background(view)
        x, y, w, h = meta["crop"]
        assert meta["site"] == "sidecar" and meta["people"] == []
        horizon_row = (0.4 * 150 - y) * 48 / h
        assert abs(meta["horizon"] * 48 - horizon_row) < 48 * 1e-4  # rounded to 4 decimals
        cols = (np.arange(64) + 0.5) * w / 64 + x  # photo x of each output column
        rows = (np.arange(48) + 0.5) * h / 48 + y
        on_floor = (cols[None, :] >= 100 + 2) & (rows[:, None] >= 60 + 20)  # 20 photo rows: nearer than 40 m
        off_floor = (cols[None, :] < 100 - 2) | (rows[:, None] < 60 - 2)
        assert on_floor.any() and (depth[on_floor] > 0).all() and (depth[off_floor] == 0).all()
        column = depth[:, -1][depth[:, -1] > 0]
        assert len(column) and (np.diff(column) <= 0).all()  # nearer towards the bottom


def test_photo_fingerprints_cover_site_sidecars(tmp_path: Path) -> None:
    from synth.places.photos import photo_fingerprints

    write_image(tmp_path / "a.jpg", 32, 24)
    plain = photo_fingerprints([tmp_path])
    (tmp_path / "_site.yaml").write_text("camera_height: 4\n")
    with_site = photo_fingerprints([tmp_path])
    assert "site" not in plain[0] and len(with_site[0]["site"]) == 64


def test_a_held_out_share_of_photos_is_chosen_by_content(tmp_path: Path) -> None:
    from ground.data.holdout import held_out
    from synth.places.photos import photo_fingerprints, pool_photos

    for i in range(40):
        write_image(tmp_path / "a" / f"p{i:02d}.png", 8, 8, seed=i)
    photos = list_photos([tmp_path / "a"])
    kept = pool_photos([tmp_path / "a"], 0.25)
    out = [p for p in photos if held_out(p, 0.25)]
    assert sorted(kept + out) == photos and 4 <= len(out) <= 18  # about a quarter
    assert pool_photos([tmp_path / "a"]) == photos and not any(held_out(p, 0.0) for p in photos)
    (tmp_path / "b").mkdir()
    for p in photos:  # renamed copies: the same photos are held out
        (tmp_path / "b" / f"x_{p.name}").write_bytes(p.read_bytes())
    assert [p.name[2:] for p in pool_photos([tmp_path / "b"], 0.25)] == [p.name for p in kept]
    assert [f["name"] for f in photo_fingerprints([tmp_path / "a"], 0.25)] == [p.name for p in kept]
    with pytest.raises(ValueError, match="held out"):
        pool_photos([tmp_path / "a"], 0.9999999)
    pano = np.full((512, 1024, 3), 90, np.uint8)  # a folder of panoramas holds no photos, and that is no error
    import cv2

    (tmp_path / "p").mkdir()
    cv2.imwrite(str(tmp_path / "p" / "h.jpg"), pano)
    assert pool_photos([tmp_path / "p"], 0.25) == [] and photo_fingerprints([tmp_path / "p"]) == []


def test_a_labelled_photo_carries_its_boxes_through_the_crop(tmp_path: Path) -> None:
    from synth.places.frames import crop_boxes

    a, b = write_image(tmp_path / "a.jpg", 160, 120, seed=1), write_image(tmp_path / "b.jpg", 160, 120, seed=2)
    boxes = [(40.0, 60.0, 30.0, 40.0)]
    smoke = [(10.0, 5.0, 100.0, 50.0)]
    photos = PhotoBackgrounds([a, b], 64, 48, seed=0, labels={a: {"fire": boxes, "smoke": smoke}})
    for view in range(4):
        _, _, meta = photos.background(view)
        if meta["photo"].endswith("a.jpg"):
            assert meta["frame_boxes"] == crop_boxes(boxes, meta["crop"], 64, 48)
            assert meta["frame_smoke_boxes"] == crop_boxes(smoke, meta["crop"], 64, 48)
        else:
            assert "frame_boxes" not in meta and "frame_smoke_boxes" not in meta  # an unlabelled photo's as before

"""Photo backgrounds: crops keep the aspect, pseudo depth puts near ground at the bottom, broken photos are named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from factories import write_image

from synth.photos import FAR_M, PhotoBackgrounds, crop_to, ground_depth, list_photos


def test_ground_depth_is_far_above_the_horizon_and_near_at_the_bottom() -> None:
    d = ground_depth(40, 100, 0.4)
    assert d.shape == (100, 40) and (d[:40] == FAR_M).all()
    column = d[40:, 0]
    assert (np.diff(column) <= 0).all() and (np.diff(column[column < FAR_M]) < 0).all()
    assert column[-1] == pytest.approx(1.6 * 50 / np.tan(np.pi / 6) / 59.5, rel=1e-4)  # 1.6 m x fy / rows below


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
    rgb, depth, meta = photos.background(1)  # photo 1 is broken: photo 0 is used
    assert rgb.shape == (48, 64, 3) and depth.shape == (48, 64) and meta["photo"].endswith("a.jpg")
    assert list(photos.problems) == [str(tmp_path / "b.jpg")]
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no images"):
        list_photos([tmp_path / "empty"])


def test_photo_fingerprints_name_and_hash_each_photo(tmp_path: Path) -> None:
    from synth.photos import photo_fingerprints

    for name in ("b.png", "a.jpg"):
        write_image(tmp_path / "x" / name, 32, 24)
    prints = photo_fingerprints([tmp_path / "x"])
    assert [p["name"] for p in prints] == ["a.jpg", "b.png"] and all(len(p["sha256"]) == 64 for p in prints)
    (tmp_path / "y").mkdir()
    for p in (tmp_path / "x").iterdir():
        (tmp_path / "y" / p.name).write_bytes(p.read_bytes())
    assert photo_fingerprints([tmp_path / "y"]) == prints

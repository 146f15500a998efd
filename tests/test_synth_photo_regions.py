"""Fire-like regions of fire-free photos: a warm coloured thing is found with its shape and soft edge; white,
grey, slivers, specks and whole walls are not; the same photos give the same regions; a broken photo is skipped."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from synth.photo_regions import MAX_AREA, SEARCH_SIDE, Region, photo_regions, regions_of, searched


def _room(h=240, w=320):
    """A grey room with a red-orange disc (a lamp shade, 30 px radius at (100, 120)) and a white window."""
    img = np.full((h, w, 3), 90, np.uint8)
    cv2.circle(img, (100, 120), 30, (230, 90, 30), -1)  # warm, saturated: a fire-like thing
    cv2.rectangle(img, (200, 30), (280, 110), (250, 250, 245), -1)  # white: passes the bright-core rule, not kept
    return img


def test_a_warm_thing_is_found_with_its_shape_and_a_soft_edge():
    regions = regions_of(_room(), "room.jpg")
    assert len(regions) == 1
    r = regions[0]
    assert isinstance(r, Region) and r.photo == "room.jpg"
    h, w = r.rgba.shape[:2]
    assert abs(h - 61) <= 2 and abs(w - 61) <= 2 and abs(r.height_share - h / 240) < 1e-9
    alpha = r.rgba[..., 3]
    assert alpha[h // 2, w // 2] == 255 and alpha[0, 0] == 0  # the disc, not its bounding box
    assert ((alpha > 0) & (alpha < 255)).any()  # softened edge
    assert np.array_equal(r.rgba[h // 2, w // 2, :3], [230, 90, 30])


def test_grey_white_slivers_specks_and_walls_are_not_regions():
    img = np.full((240, 320, 3), 90, np.uint8)
    img[:, :4] = (230, 90, 30)  # a sliver along the edge: fills its box but is 4 px wide...
    img[100:102, 50:300] = (230, 90, 30)  # ...a thin line: too small
    img[10:12, 10:12] = (230, 90, 30)  # a speck
    assert regions_of(img) == []
    wall = np.full((240, 320, 3), (220, 120, 60), np.uint8)  # a whole warm wall: a background, not a thing
    assert regions_of(wall) == []
    assert MAX_AREA < 1.0


def test_large_photos_are_searched_small_and_small_ones_as_they_are():
    big = np.zeros((1200, 1600, 3), np.uint8)
    assert max(searched(big).shape[:2]) == SEARCH_SIDE
    small = np.zeros((100, 80, 3), np.uint8)
    assert searched(small) is small
    scaled = cv2.resize(_room(), (1280, 960), interpolation=cv2.INTER_NEAREST)
    share = regions_of(scaled)[0].height_share
    assert abs(share - regions_of(_room())[0].height_share) < 0.02  # the same share of the photo at any size


def test_the_same_photos_give_the_same_regions_and_a_broken_one_is_skipped(tmp_path: Path):
    good = tmp_path / "room.png"
    cv2.imwrite(str(good), _room()[..., ::-1])
    broken = tmp_path / "broken.jpg"
    broken.write_bytes(b"not a jpeg")
    one, two = photo_regions([good, broken]), photo_regions([good])
    assert len(one) == len(two) == 1 and np.array_equal(one[0].rgba, two[0].rgba)
    assert photo_regions([broken]) == ()

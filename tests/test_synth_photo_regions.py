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


def _lamp_room(h=240, w=320, warm=True, glow=True):
    """A dim room with a blown-out lamp shade (a 24 x 30 px white core at (150, 100)) in its warm glow (a
    Gaussian of orange light around it, or none) on a brown or blue wall."""
    wall = (70, 50, 35) if warm else (35, 50, 80)
    img = np.empty((h, w, 3), np.float32)
    img[:] = wall
    if glow:
        y, x = np.mgrid[0:h, 0:w]
        g = np.exp(-0.5 * (((x - 162) / 30.0) ** 2 + ((y - 115) / 30.0) ** 2))[..., None]
        img += g * np.array([180, 110, 40], np.float32)
    img[100:130, 150:174] = 255
    return np.clip(img, 0, 255).astype(np.uint8)


def test_a_blown_out_lamp_is_a_light_cut_with_its_glow():
    from synth.photo_regions import LIGHT_MARGIN, lights_of

    img = _lamp_room()
    lights = lights_of(img, "lamp.jpg")
    assert len(lights) == 1
    r = lights[0]
    assert r.kind == "lights" and r.photo == "lamp.jpg"
    h, w = r.rgba.shape[:2]
    m = round(LIGHT_MARGIN * 30)
    assert (h, w) == (30 + 2 * m, 24 + 2 * m) and abs(r.height_share - h / 240) < 1e-9  # the core and its glow
    alpha = r.rgba[..., 3]
    assert alpha[h // 2, w // 2] == 255 and alpha[0, 0] < 32  # opaque core, glow fading out before the edge


def test_white_without_a_warm_glow_is_not_a_light():
    from synth.photo_regions import lights_of

    assert lights_of(_lamp_room(glow=False)) == []  # white paper on a brown desk: no light fading outwards
    assert lights_of(_lamp_room(warm=False, glow=False)) == []  # a white sign on a blue wall
    sky = np.full((240, 320, 3), 255, np.uint8)  # a blown-out sky: too large to be a light source
    assert lights_of(sky) == []


def test_the_rules_are_chosen_and_the_photo_rule_is_the_same_with_or_without_lights(tmp_path: Path):
    import pytest

    from synth.photo_regions import RULES

    room, lamp = tmp_path / "room.png", tmp_path / "lamp.png"
    cv2.imwrite(str(room), _room()[..., ::-1])
    cv2.imwrite(str(lamp), _lamp_room()[..., ::-1])
    both = photo_regions([room, lamp], RULES)
    photo = photo_regions([room, lamp])
    assert {r.kind for r in both} == set(RULES)
    kept = [r for r in both if r.kind == "photo"]
    assert len(kept) == len(photo) and all(np.array_equal(a.rgba, b.rgba) for a, b in zip(kept, photo, strict=True))
    with pytest.raises(ValueError, match="unknown region rules"):
        photo_regions([room], ("photo", "moon"))

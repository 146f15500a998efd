"""Places by kind: meshes, panoramas and photos are told apart; a view's kind is drawn by the weights."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from factories import write_image, write_textured_room

from synth.places.kinds import PHOTO_PANORAMA_WIDTH, kind_of_view, kind_weights, split_places


def _panorama(path: Path, width: int = 128) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), np.full((width // 2, width, 3), 90, np.uint8))
    return path


def test_environments_and_backgrounds_are_sorted_by_kind(tmp_path: Path) -> None:
    room = write_textured_room(tmp_path / "rooms" / "room.glb")
    pano = _panorama(tmp_path / "panos" / "hall.jpg", 1024)
    write_image(tmp_path / "panos" / "not_a_panorama.jpg", 64, 48)  # skipped in a folder of panoramas
    photo = write_image(tmp_path / "photos" / "office.jpg", 64, 48)
    street = _panorama(tmp_path / "photos" / "street360.png", 1024)  # a panorama among photos is a place
    places = split_places([tmp_path / "rooms", tmp_path / "panos"], [tmp_path / "photos"])
    assert places.meshes == (tmp_path / "rooms",) and places.photos == (photo,)
    assert set(places.panoramas) == {pano.absolute(), street}
    assert split_places([room, pano]).meshes == (room,) and split_places([room, pano]).panoramas == (pano,)
    (tmp_path / "panos" / "panoramas.yaml").write_text("camera_height: [1.5, 2.0]\n")  # a panorama sidecar
    assert split_places([tmp_path / "panos"]).meshes == ()  # is not a mesh environment
    only_panoramas = split_places((), [tmp_path / "panos"])
    assert only_panoramas.photos == (tmp_path / "panos" / "not_a_panorama.jpg",)
    with pytest.raises(FileNotFoundError, match="no such environment"):
        split_places([tmp_path / "missing"])


def _unreadable(folder: Path) -> dict[str, str]:
    """A truncated JPEG and a text file named .jpg in ``folder``: {file name: the reason each must be named by}."""
    whole = write_image(folder / "whole.jpg", 64, 48).read_bytes()
    (folder / "cut.jpg").write_bytes(whole[: len(whole) // 2])
    (folder / "notes.jpg").write_text("not an image at all\n")
    return {"cut.jpg": "truncated JPEG", "notes.jpg": "not a"}


def test_unreadable_backgrounds_and_panoramas_are_skipped_and_named(tmp_path: Path) -> None:
    photo = write_image(tmp_path / "photos" / "office.jpg", 64, 48)
    expected = _unreadable(tmp_path / "photos")
    places = split_places((), [tmp_path / "photos"])
    assert set(places.photos) == {photo, tmp_path / "photos" / "whole.jpg"} and places.panoramas == ()
    assert {Path(p.path).name for p in places.problems} == set(expected)
    assert all(expected[Path(p.path).name] in p.reason for p in places.problems)
    pano = _panorama(tmp_path / "panos" / "hall.jpg")
    _unreadable(tmp_path / "panos")  # a folder of panoramas with broken files in it
    rooms = split_places([tmp_path / "panos"])
    assert rooms.panoramas == (pano.absolute(),) and {Path(p.path).name for p in rooms.problems} == set(expected)
    with pytest.raises(ValueError, match="notes.jpg: not a"):  # an environment named by the user is an error
        split_places([tmp_path / "panos" / "notes.jpg"])
    for name in ("office.jpg", "whole.jpg"):
        (tmp_path / "photos" / name).unlink()
    with pytest.raises(ValueError, match="none of the 2 background images can be used"):
        split_places((), [tmp_path / "photos"])


def test_a_2_to_1_background_is_a_panorama_only_when_large_enough_and_an_environment_always(tmp_path: Path) -> None:
    room = _panorama(tmp_path / "photos" / "conference.jpg", 448)  # a wide photo that happens to be 2:1
    street = _panorama(tmp_path / "photos" / "street360.jpg", PHOTO_PANORAMA_WIDTH)
    photo = write_image(tmp_path / "photos" / "office.jpg", 64, 48)
    places = split_places((), [tmp_path / "photos"])
    assert set(places.photos) == {room, photo} and places.panoramas == places.taken == (street,)
    assert places.panorama_note() == (
        f"took 1 of 3 backgrounds as 360° panoramas (2:1, >= {PHOTO_PANORAMA_WIDTH} px wide): street360.jpg"
    )
    assert split_places([room]).panoramas == (room,)  # named in environments: the plain 2:1 rule
    assert split_places([tmp_path / "photos"]).panoramas == (room, street)  # a folder of environments too
    assert split_places([room]).panorama_note() is None and split_places((), [photo]).panorama_note() is None


def test_kind_weights_and_draws() -> None:
    assert kind_weights(["render"], {"render": 0.0}) == {"render": 1.0}
    assert kind_weights(["photo", "render"], {"photo": 0.25, "render": 0.75, "panorama": 1}) == {
        "photo": 0.25,
        "render": 0.75,
    }
    assert kind_weights(["photo", "panorama", "render"], {"photo": 0.5, "panorama": 0.5, "render": 0.5}) == {
        "photo": pytest.approx(1 / 3),
        "panorama": pytest.approx(1 / 3),
        "render": pytest.approx(1 / 3),
    }
    weights = kind_weights(["photo", "render"], {"photo": 0.3, "render": 0.7})
    draws = [kind_of_view(5, v, weights) for v in range(400)]
    # the rule photo pools were made with: a photo when default_rng([seed, 6, v]).random() < photo_share
    assert draws == ["photo" if np.random.default_rng([5, 6, v]).random() < 0.3 else "render" for v in range(400)]
    three = kind_weights(["photo", "panorama", "render"], {"photo": 1, "panorama": 1, "render": 1})
    counts = {k: [kind_of_view(0, v, three) for v in range(900)].count(k) for k in three}
    assert all(250 < n < 350 for n in counts.values())

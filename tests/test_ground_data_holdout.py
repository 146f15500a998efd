"""Held-out images by content: nested shares, names do not matter, boxes travel with their images."""

from __future__ import annotations

from pathlib import Path

import pytest
from factories import write_image

from ground.data.dataset import DatasetBuilder
from ground.data.holdout import content_fraction, held_out, held_out_images


def photos(folder: Path, n: int = 40) -> list[Path]:
    return [write_image(folder / f"p{i:02d}.png", 8, 8, seed=i) for i in range(n)]


def test_shares_are_nested_chosen_by_content_and_span_none_to_all(tmp_path: Path) -> None:
    files = photos(tmp_path / "a")
    by_share = {s: {p.name for p in files if held_out(p, s)} for s in (0.0, 0.1, 0.25, 0.5, 1.0)}
    assert by_share[0.25] == {p.name for p in files if content_fraction(p) >= 0.75}
    assert by_share[0.0] == set() and by_share[1.0] == {p.name for p in files}
    assert by_share[0.1] <= by_share[0.25] <= by_share[0.5] and 4 <= len(by_share[0.25]) <= 18
    for p in files:  # a renamed copy is the same photo
        copy = tmp_path / "b" / f"renamed_{p.name}"
        copy.parent.mkdir(exist_ok=True)
        copy.write_bytes(p.read_bytes())
        assert held_out(copy, 0.25) == held_out(p, 0.25)


def test_held_out_images_keep_their_boxes_and_none_held_out_is_an_error(tmp_path: Path) -> None:
    files = photos(tmp_path, 12)
    b = DatasetBuilder(tmp_path, ["fire"])
    for p in files:
        b.add_box(b.add_image(p.name, 8, 8), "fire", (1.0, 1.0, 4.0, 4.0))
    ds = b.build()
    kept = held_out_images(ds, 0.5)
    names = {img.file_name for img in kept.images}
    assert names == {p.name for p in files if held_out(p, 0.5)} and 0 < len(names) < 12
    assert len(kept.annotations) == len(names) and kept.category_names == ["fire"]
    with pytest.raises(ValueError, match=r"photos: none of its 12 images is held out at share 1e-09"):
        held_out_images(ds, 1e-9, "photos")
    for share in (-0.1, 1.5):
        with pytest.raises(ValueError, match=r"a held-out share is in 0\.\.1, got"):
            held_out_images(ds, share, "photos")

"""Decoding one file: its pixel hash sees pixels not bytes, its sharpness orders focus, and a batch gives facts
and two-view vectors for readable files and a named problem for the others, in input order."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from curate_helpers import save, scene, use_session_cache

from curate.decode import embed_batch, pixel_hash, sharpness
from curate.embed import load_embedder
from ground.data.problems import Problem


def test_pixel_hash_sees_pixels_not_bytes() -> None:
    img = scene(3)
    assert pixel_hash(img) == pixel_hash(img.copy())
    assert pixel_hash(img) != pixel_hash(img[:, ::-1])
    assert pixel_hash(img) != pixel_hash(img.reshape(img.shape[1], img.shape[0], 3))


def test_a_blurred_picture_is_less_sharp() -> None:
    img = scene(4)
    assert sharpness(cv2.GaussianBlur(img, (0, 0), 2.0)) < sharpness(img)


def test_a_batch_keeps_input_order_and_names_the_unreadable(
    tmp_path: Path, tmp_path_factory: pytest.TempPathFactory
) -> None:
    use_session_cache(tmp_path_factory)
    embedder = load_embedder()
    good = [save(scene(i), tmp_path / f"s{i}.png") for i in range(3)]
    broken = tmp_path / "broken.jpg"
    broken.write_bytes(b"\xff\xd8\xff\xe0 not really a jpeg")
    out = embed_batch([good[0], broken, good[1], good[2]], embedder)
    assert [p for p, _ in out] == [good[0], broken, good[1], good[2]]
    assert isinstance(out[1][1], Problem) and out[1][1].path == broken.as_posix()
    facts, vector = out[0][1]  # type: ignore[misc]
    assert (facts.width, facts.height) == (160, 120) and facts.pixel_hash == pixel_hash(scene(0))
    assert vector.shape == (2 * 320,) and np.isfinite(vector).all()
    alone = embed_batch([good[0]], embedder)[0][1][1]  # type: ignore[index]
    assert np.allclose(alone, vector, atol=1e-5)  # a file's vector does not depend on its batch


def test_a_jpeg_with_extraneous_header_bytes_is_named_and_keeps_its_content_hash(tmp_path: Path, caplog) -> None:
    """dedup's decoding threads: libjpeg's nameless warning becomes a line naming the file; the facts are those
    of the file as it is (content hash) and of the pixels libjpeg decodes (pixel hash)."""
    import hashlib
    import logging

    from factories import extraneous_jpeg

    from curate.decode import decode_facts

    clean, bad = extraneous_jpeg()
    (tmp_path / "clean.jpg").write_bytes(clean)
    (tmp_path / "bad.jpg").write_bytes(bad)
    with caplog.at_level(logging.WARNING, logger="ground.image.imageio"):
        facts = {name: decode_facts(tmp_path / name, None) for name in ("clean.jpg", "bad.jpg")}
    assert [r.getMessage() for r in caplog.records] == [
        f"{tmp_path / 'bad.jpg'}: corrupt JPEG data (1 extraneous bytes before marker 0xdb)"
    ]
    good, worse = facts["clean.jpg"][0], facts["bad.jpg"][0]  # type: ignore[index]
    assert worse.sha256 == hashlib.sha256(bad).hexdigest() and worse.pixel_hash == good.pixel_hash

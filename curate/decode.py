"""One file's facts and model inputs: its content hash (read whole, checked complete); one decode for its
decoded-pixel hash, size, sharpness and the two views the embedder takes; and a batch of files decoded and
embedded in one onnxruntime call (what a scan thread or a Ray task does: :mod:`curate.scan`,
:mod:`curate.embedremote`).
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.embed import OnnxEmbedder, Preprocess
from curate.embedcache import FileFacts
from ground.data.problems import Problem
from ground.image.imageio import ImageError, check_complete, decode_sized


def hash_image_file(path: Path) -> tuple[int, str] | Problem:
    """``(bytes, sha256 hex)`` of a file, or a Problem when it cannot be read or its bytes are truncated or
    garbled (:func:`~ground.image.imageio.check_complete`: checked here too, so a file cached by a reader that
    did not check it is not taken from the cache)."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        return Problem(path.as_posix(), f"cannot read ({exc.strerror or exc})")
    if not data:
        return Problem(path.as_posix(), "empty file (0 bytes)")
    try:
        check_complete(data, path)
    except ImageError as exc:
        return Problem(path.as_posix(), exc.reason)
    return len(data), hashlib.sha256(data).hexdigest()


def pixel_hash(image: NDArray[np.uint8]) -> str:
    """Hash of decoded pixels and shape: equal for the same picture saved losslessly in any format."""
    digest = hashlib.blake2b(digest_size=16)
    digest.update(np.asarray(image.shape, np.int64).tobytes())
    digest.update(np.ascontiguousarray(image).data)
    return digest.hexdigest()


def sharpness(image: NDArray[np.uint8]) -> float:
    """Variance of the Laplacian of the grey (H, W, 3) RGB image (a focus measure; higher = sharper)."""
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    return float(cv2.Laplacian(grey, cv2.CV_32F).var())


def decode_facts(path: Path, preprocess: Preprocess | None) -> tuple[FileFacts, NDArray[np.uint8] | None] | Problem:
    """Decode one file: its facts and the (2, S, S, 3) model inputs of its two views (None without ``preprocess``).

    With ``preprocess`` a large JPEG is decoded at reduced size, its short side at least
    :meth:`~curate.embed.Preprocess.decode_min_side` (:func:`ground.image.imageio.decode_image`); width and height
    are the full size, the pixel hash and sharpness are of the decoded image (the same decode for the same file, so equal
    pictures still hash equal)."""
    try:
        data = path.read_bytes()
        image, (width, height) = decode_sized(data, path, preprocess.decode_min_side() if preprocess else 0)
    except ImageError as exc:
        return Problem(path.as_posix(), exc.reason)
    except OSError as exc:
        return Problem(path.as_posix(), f"cannot read ({exc.strerror or exc})")
    facts = FileFacts(
        hashlib.sha256(data).hexdigest(),
        len(data),
        width,
        height,
        pixel_hash(image),
        sharpness(image),
    )
    return facts, (preprocess.views(image) if preprocess is not None else None)


def embed_batch(
    paths: Sequence[Path], embedder: OnnxEmbedder
) -> list[tuple[Path, tuple[FileFacts, NDArray[np.float32]] | Problem]]:
    """Decode ``paths`` and embed both views of the readable ones in one onnxruntime call; (path, (facts, raw
    [whole, centre] vector (2 D,)) or Problem) in input order. Runs in a worker thread (onnxruntime and OpenCV
    release the GIL)."""
    decoded = [(p, decode_facts(p, embedder.preprocess)) for p in paths]
    good = [(p, d) for p, d in decoded if not isinstance(d, Problem)]
    out: dict[Path, tuple[FileFacts, NDArray[np.float32]] | Problem] = {
        p: d for p, d in decoded if isinstance(d, Problem)
    }
    if good:
        views = np.concatenate([d[1] for _, d in good])  # type: ignore[misc]  # (2 B, S, S, 3)
        vectors = embedder.embed(views).reshape(len(good), -1)  # (B, 2 D): whole view then centre view
        for (p, d), v in zip(good, vectors):
            out[p] = (d[0], v)  # type: ignore[index]
    return [(p, out[p]) for p in paths]

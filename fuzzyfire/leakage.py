"""Test images that a synthetic pool composites on: refused before anything is trained.

A Method 2 pool with ``backgrounds`` composites flames on photographs; a test set holding one of those photos
(the same bytes, by sha256) would score a detector on a picture it trained on. Every test set of an experiment
(common, rare and the named ones) is checked against the background photos of every pool the grid uses; the
shares a pool holds out (``background_holdout``, :func:`curate.core.holdout.held_out`) are no part of it, so a test set
with the same ``holdout`` share is disjoint by construction.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from curate.core.dataset import Dataset


class LeakageError(ValueError):
    """A test set holds photos a pool composites on (one line: the count and one example)."""


def pool_photos(synth: object, methods: Sequence[str], base: Path) -> dict[str, list[Path]]:
    """The background photos of the pools ``methods`` of ``synth`` (an experiment's
    :class:`fuzzyfire.experiment_config.SynthConfig`), each as its pool takes them
    (:func:`synth.places.photos.pool_photos`: without the held-out share and without panoramas); ``backgrounds``
    resolve against ``base``; the images of labelled ``frames`` (:mod:`synth.places.frames`) count too. Pools without
    photos are left out."""
    from synth.places.frames import load_frames
    from synth.places.photos import pool_photos as photos_of

    out = {}
    for method in methods:
        cfg = getattr(synth, method)
        folders = [p if Path(p).is_absolute() else base / p for p in getattr(cfg, "backgrounds", ())]
        frames = [p if Path(p).is_absolute() else base / p for p in getattr(cfg, "frames", ())]
        photos = [*(photos_of(folders, cfg.background_holdout) if folders else []), *load_frames(frames)]
        if photos:
            out[method] = photos
    return out


def check_leakage(pools: Mapping[str, Sequence[Path]], tests: Mapping[str, Dataset]) -> None:
    """Raise :class:`LeakageError` when an image of a test set (``tests``: datasets by label) has the bytes of
    a photo of a pool (``pools``: photo paths by method). Hashes nothing when no pool has photos."""
    from curate.core.manifest import file_sha256

    if not any(pools.values()):
        return
    owner = {file_sha256(p): (method, p) for method, photos in pools.items() for p in photos}
    for name, ds in tests.items():
        hits = [(ds.image_path(img), owner[h]) for img in ds.images if (h := file_sha256(ds.image_path(img))) in owner]
        if hits:
            image, (method, photo) = hits[0]
            raise LeakageError(
                f"leakage: {len(hits)} images of test set {name!r} are background photos of the {method} pool "
                f"(e.g. {image} = {photo}): hold them out of the pool (background_holdout) and give the test set "
                "the same holdout share"
            )

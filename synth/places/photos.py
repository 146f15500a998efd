"""Photographs as Method 2 backgrounds: a user's fire-free pictures (e.g. the negatives of a real dataset, or the
fire-free frames of their own cameras) as *sites* where flames stand on the ground (:mod:`synth.places.sites`: a
sidecar's floor polygon and horizon, or the estimated ground below the horizon, off sky, water and people),
sized by a ground-plane pseudo depth, in random crops that carry the site along.

Photos are used in an order drawn by the seed, every photo once before any repeats: view ``v`` shows photo
``perm[v % n]`` with ``perm = default_rng([seed, 8]).permutation(n)``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.scan import list_image_files
from ground.data.holdout import held_out
from ground.image.imageio import ImageError, read_image
from synth.places.frames import FrameLabels, crop_boxes
from synth.places.sites import Site, estimate_site, read_site_sidecar, sidecar_files


def list_photos(paths: Iterable[Path | str]) -> list[Path]:
    """Image files under ``paths`` (files or folders, recursive), sorted."""
    photos = list_image_files(paths)
    if not photos:
        raise ValueError(f"no images in {', '.join(map(str, paths))}")
    return photos


def pool_photos(paths: Iterable[Path | str], holdout: float = 0.0) -> list[Path]:
    """:func:`list_photos` without the :func:`held_out` ones and without 2:1 panoramas (places of their own,
    :mod:`synth.places.kinds`); see :func:`keep_in_pool`."""
    from synth.places.kinds import split_places

    list_photos(paths)  # a folder without images is an error of its own
    return keep_in_pool(split_places((), paths).photos, holdout)


def keep_in_pool(photos: Sequence[Path], holdout: float) -> list[Path]:
    """``photos`` without the :func:`held_out` ones; ValueError when there were photos and every one is held out."""
    kept = [p for p in photos if not held_out(p, holdout)]
    if photos and not kept:
        raise ValueError(f"every one of the {len(photos)} background photos is held out (holdout {holdout:g})")
    return kept


def photo_fingerprints(paths: Iterable[Path | str], holdout: float = 0.0) -> list[dict[str, str]]:
    """The pool's photos under ``paths`` (:func:`pool_photos` order) as name and sha256 of their bytes (and of
    their site sidecar, if any): what a pool composited on them is made of, wherever the folder lies."""
    from ground.data.manifest import file_sha256

    out = []
    for photo in pool_photos(paths, holdout):
        entry = {"name": photo.name, "sha256": file_sha256(photo)}
        for sidecar in sidecar_files(photo):
            entry["site"] = file_sha256(sidecar)
        out.append(entry)
    return out


def crop_to(image: NDArray[np.uint8], width: int, height: int, rng: np.random.Generator) -> tuple[NDArray, list]:
    """A random crop of ``image`` (H, W, 3) with the output's aspect, 70-100 % of the largest such crop, resized
    to ``height`` x ``width``; and the crop as [x, y, w, h] pixels of the photo."""
    h, w = image.shape[:2]
    aspect = width / height
    cw, ch = (w, int(round(w / aspect))) if w / h < aspect else (int(round(h * aspect)), h)
    scale = rng.uniform(0.7, 1.0)
    cw, ch = max(int(cw * scale), 1), max(int(ch * scale), 1)
    x, y = int(rng.integers(0, w - cw + 1)), int(rng.integers(0, h - ch + 1))
    interp = cv2.INTER_AREA if cw > width else cv2.INTER_LINEAR
    return cv2.resize(image[y : y + ch, x : x + cw], (width, height), interpolation=interp), [x, y, cw, ch]


class PhotoBackgrounds:
    """Background ``v`` is photo ``perm[v % n]`` (module docstring) cropped by ``default_rng([seed, 5, v])``;
    unreadable photos are skipped (the next one in the order is used) and named in :attr:`problems`. ``labels``:
    the boxes [x, y, w, h] px by class of the photos that are labelled frames (:mod:`synth.places.frames`), carried
    into each view's ``frame_boxes`` (fire) and ``frame_smoke_boxes`` (smoke, when the labels have that class)."""

    def __init__(
        self,
        photos: Sequence[Path],
        width: int,
        height: int,
        seed: int,
        labels: Mapping[Path, FrameLabels] | None = None,
    ) -> None:
        if not photos:
            raise ValueError("no background photos")
        self.photos, self.width, self.height, self.seed = list(photos), width, height, seed
        self.labels = dict(labels or {})
        self.order = np.random.default_rng([seed, 8]).permutation(len(self.photos))
        self.problems: dict[str, str] = {}

    def photo(self, view_index: int) -> Path:
        return self.photos[int(self.order[view_index % len(self.photos)])]

    def background(self, view_index: int) -> tuple[NDArray[np.uint8], NDArray[np.float32], dict]:
        """((H, W, 3) uint8 RGB, (H, W) float32 pseudo depth in metres, 0 off the ground, metadata) of
        background ``view_index``."""
        rng = np.random.default_rng([self.seed, 5, view_index])
        for k in range(len(self.photos)):
            path = self.photo(view_index + k)
            try:
                image = read_image(path)
            except ImageError as exc:
                self.problems[str(path)] = str(exc)
                continue
            site = estimate_site(image, rng, read_site_sidecar(path))
            return self._view(image, site, path, rng)
        raise ValueError(f"none of the {len(self.photos)} background photos can be read")

    def _view(self, image: NDArray[np.uint8], site: Site, path: Path, rng: np.random.Generator):
        """A random crop of ``image`` with its site carried along: horizon, ground and focal length."""
        rgb, (x, y, cw, ch) = crop_to(image, self.width, self.height, rng)
        zoom = self.height / ch
        fy = image.shape[0] / 2 / np.tan(site.yfov / 2) * zoom
        horizon = (site.horizon - y) * zoom
        ground = cv2.resize(
            site.ground[y : y + ch, x : x + cw].astype(np.uint8),
            (self.width, self.height),
            interpolation=cv2.INTER_NEAREST,
        ).astype(bool)
        depth = site.depth(self.height, fy, horizon, ground)
        people = [[round((px - x) * self.width / cw), round((py - y) * zoom), round(pw * self.width / cw), round(ph * zoom)]
                  for px, py, pw, ph in site.people]  # fmt: skip
        meta = {
            "photo": path.as_posix(),
            "crop": [x, y, cw, ch],
            "horizon": round(horizon / self.height, 4),
            "camera": {"yfov": float(2 * np.arctan(self.height / 2 / fy))},
            "site": site.source,
            "people": people,
        }
        if path in self.labels:  # a labelled frame: its own fires are labels, and no flame stands on them
            labels = self.labels[path]
            meta["frame_boxes"] = crop_boxes(labels["fire"], [x, y, cw, ch], self.width, self.height)
            if "smoke" in labels:
                meta["frame_smoke_boxes"] = crop_boxes(labels["smoke"], [x, y, cw, ch], self.width, self.height)
        return rgb, depth, meta

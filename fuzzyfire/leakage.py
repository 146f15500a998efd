"""Test sets that are what they claim: no test image may be a training image, checked before anything is trained.

Two checks. A test image that is a copy or a near duplicate of a real training image (:func:`find_test_leaks`:
the dedup's embedding search, :mod:`curate.leakage`, against the real train and validation splits and, for every
test set but the real set's own split, every image of the folders the real set was curated from) is dropped
from its test set (``leakage.action: drop``, recorded in ``leakage.json`` and the report) or refuses the study
(``refuse``). And a test image that a synthetic pool composites on is always refused:

A Method 2 pool with ``backgrounds`` composites flames on photographs; a test set holding one of those photos
(the same bytes, by sha256) would score a detector on a picture it trained on. Every test set of an experiment
(common, rare and the named ones) is checked against the background photos of every pool the grid uses; the
share a pool holds out (:func:`ground.data.holdout.held_out`) is no part of it. In an experiment that share is the
``holdout`` of the test set on the same folder (:meth:`fuzzyfire.experiment_config.ExperimentConfig.resolved`), so
such a test set is disjoint from the pool by construction.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from ground.data.dataset import Dataset

if TYPE_CHECKING:
    from curate.scan import ScanResult
    from fuzzyfire.experiment_config import SynthConfig


class LeakageError(ValueError):
    """A test set holds photos a pool composites on, or training images under ``leakage.action: refuse`` (one
    line: the count and one example)."""


def pool_photos(synth: SynthConfig, methods: Sequence[str], base: Path) -> dict[str, list[Path]]:
    """The background photos of the pools ``methods`` of ``synth`` (an experiment's pools), each as its pool takes
    them (:func:`synth.places.photos.pool_photos`: without the held-out share and without panoramas);
    ``backgrounds`` resolve against ``base``; the images of ``labelled_frames`` (:mod:`synth.places.frames`) count
    too. Pools without photos are left out."""
    from synth.places.frames import load_frames
    from synth.places.photos import pool_photos as photos_of

    out = {}
    for method in methods:
        cfg = synth.section(method)
        places = cfg.with_paths(lambda p: p if p.is_absolute() else base / p).places() if cfg is not None else None
        if places is None:
            continue
        photos = [*(photos_of(places.backgrounds, places.background_holdout) if places.backgrounds else []),
                  *load_frames(places.labelled_frames)]  # fmt: skip
        if photos:
            out[method] = photos
    return out


def check_leakage(pools: Mapping[str, Sequence[Path]], tests: Mapping[str, Dataset]) -> None:
    """Raise :class:`LeakageError` when an image of a test set (``tests``: datasets by label) has the bytes of
    a photo of a pool (``pools``: photo paths by method). Hashes nothing when no pool has photos."""
    from ground.data.manifest import file_sha256

    if not any(pools.values()):
        return
    owner = {file_sha256(p): (method, p) for method, photos in pools.items() for p in photos}
    for name, ds in tests.items():
        hits = [(ds.image_path(img), owner[h]) for img in ds.images if (h := file_sha256(ds.image_path(img))) in owner]
        if hits:
            image, (method, photo) = hits[0]
            raise LeakageError(
                f"leakage: {len(hits)} images of test set {name!r} are background photos of the {method} pool "
                f"(e.g. {image} = {photo}): give the test set the pool's backgrounds folder with a holdout share "
                "(the pool then never composites on the photos held out)"
            )


LEAKS_FILE = "leakage.json"  # in the experiment folder: every test set's images found in the training data
EXAMPLES = 5  # closest (test image, training image) pairs kept per test set


@dataclass(frozen=True)
class TestLeaks:
    """A test set checked against the training data: of its ``images``, those in ``leaked`` (their ``file_name``,
    sorted) are copies or near duplicates of a training image; ``examples``: the closest pairs (test image path,
    training image path, distance in unit-embedding space), closest first, at most :data:`EXAMPLES`."""

    name: str
    images: int
    reference: int  # training images checked against
    leaked: tuple[str, ...]
    examples: tuple[tuple[str, str, float], ...]

    def line(self, action: str) -> str:
        """One line for the console and the report."""
        if not self.leaked:
            return f"{self.name}: none of its {self.images} images is in the training data ({self.reference} images)"
        what = "dropped" if action == "drop" else "refused"
        a, b, d = self.examples[0]
        return (f"{self.name}: {len(self.leaked)} of its {self.images} images are copies or near duplicates of "
                f"training images ({self.reference} checked), {what} (e.g. {Path(a).name} ~ {Path(b).name}, "
                f"distance {d:.3f})")  # fmt: skip


def reference_images(trained: Sequence[Dataset], sources: Sequence[Path]) -> list[Path]:
    """The training data a test set is checked against: every image of the ``trained`` datasets (the real train
    and validation splits) and of the ``sources`` folders the real set was curated from (none for the real set's
    own test split, whose images are among those sources), each once, links resolved."""
    from curate.scan import list_image_files

    paths = [ds.image_path(img) for ds in trained for img in ds.images] + list_image_files(sources)
    return sorted({Path(p).resolve() for p in paths})


def find_test_leaks(
    tests: Mapping[str, tuple[Dataset, Sequence[Path]]],
    threshold: float,
    embed: Callable[[Sequence[Path]], ScanResult],
) -> dict[str, TestLeaks]:
    """Each test set (``tests``: label -> (dataset, the training images it is checked against)) against its
    training images, by :func:`curate.leakage.find_leaks` at ``threshold`` (exact copies and near duplicates);
    ``embed`` scans a list of files (:func:`curate.scan.scan_images` with the experiment's embedder and cache).
    Every file is scanned once, in one call."""
    from curate.leakage import find_leaks

    own = {name: {ds.image_path(img).resolve(): img.file_name for img in ds.images} for name, (ds, _) in tests.items()}
    every = sorted({p for name, (_, ref) in tests.items() for p in [*own[name], *ref]})
    scan = embed(every)
    at = {Path(im.path): i for i, im in enumerate(scan.images)}
    out = {}
    for name, (ds, ref) in tests.items():
        test_scan, ref_scan = _subset(scan, at, own[name]), _subset(scan, at, ref)
        leaks = find_leaks(test_scan, ref_scan, threshold)
        leaked = sorted({own[name][Path(x.a)] for x in leaks})
        examples = tuple((x.a, x.b, round(x.distance, 4)) for x in leaks[:EXAMPLES])
        out[name] = TestLeaks(name, len(ds.images), len(ref), tuple(leaked), examples)
    return out


def _subset(scan: ScanResult, at: Mapping[Path, int], paths: Iterable[Path]) -> ScanResult:
    """The part of ``scan`` (``at``: its row of each path) that holds ``paths`` (unreadable ones left out)."""
    rows = [at[p] for p in paths if p in at]
    return replace(scan, images=[scan.images[i] for i in rows], vectors=scan.vectors[rows], crops=scan.crops[rows])


def write_leaks(path: Path, leaks: Mapping[str, TestLeaks], threshold: float, action: str) -> None:
    """``path`` (:data:`LEAKS_FILE`): the check's threshold and action and every test set's leaked images."""
    doc = {"threshold": threshold, "action": action,
           "sets": {n: {"images": t.images, "reference": t.reference, "leaked": list(t.leaked),
                        "examples": [list(e) for e in t.examples]} for n, t in leaks.items()}}  # fmt: skip
    path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")

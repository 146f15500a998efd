"""R(m)_S(n) training mixtures: ``m`` real plus ``n`` synthetic images drawn with a seed.

Draws are *nested*: for one seed, each source is shuffled once and a mixture takes the first ``m`` (or ``n``)
images of that order, so the 250 real images of ``R250_S750`` are inside the 500 of ``R500_S500``. The real
and synthetic orders come from independent child streams of the seed, so adding synthetic images never
changes which real images are drawn. Images are sorted by resolved path before shuffling, so the draw does
not depend on the order a reader listed them in.

Mixture names follow the paper: ``R750_S250`` = 750 real + 250 synthetic images.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal, Optional

import numpy as np

from ground.data.dataset import Dataset, ImageRecord, merge
from ground.data.formats.registry import DatasetFormat
from ground.data.formats.yolo import ultralytics_val_folders
from ground.data.writer import plan_image_names, write_dataset

_NAME = re.compile(r"^R(\d+)_S(\d+)$")
#: Folder per seed inside the output: ``OUT/seed<S>/R<m>_S<n>``.
SEED_DIR = "seed{seed}"
MIXTURE_FILE = "mixture.json"


class MixError(ValueError):
    """A mixture that cannot be drawn (bad name, more images asked than a source has)."""


@dataclass(frozen=True)
class MixConfig:
    """``fuzzyfire mix``: which mixtures are drawn, with which seeds, from which split of each set, written how."""

    mixtures: tuple[str, ...] = ()  # R<m>_S<n> names (m real + n synthetic images), e.g. [R1000_S0, R500_S500];
    # empty: paper_grid
    paper_grid: bool = False  # the paper's strategies instead: R<step>..R<total>_S0, the constant-total mixtures,
    # R0_S<step>..R0_S<total>
    total: int = 1000  # paper_grid: images per mixture
    step: int = 250  # paper_grid: step between sizes
    seeds: tuple[int, ...] = (0,)  # one folder per seed and mixture (flag: 0, 0-4 or 0,3,7)
    split: Optional[str] = None  # split drawn from in both sets unless real_split / synth_split say otherwise;
    # null: train when present, else every image
    real_split: Optional[str] = None  # split of the real set; null: split
    synth_split: Optional[str] = None  # split of the synthetic set; null: split
    real_format: DatasetFormat = "auto"  # format of the real set (auto: detect)
    synth_format: DatasetFormat = "auto"  # format of the synthetic set (auto: detect)
    val_split: Optional[str] = None  # split of the validation set (--val); null: val or valid when present, else all
    val_format: DatasetFormat = "auto"  # format of the validation set (auto: detect)
    classes: tuple[str, ...] = ()  # class names in YOLO id order; empty: the real set's classes, then the synthetic's
    images: Literal["symlink", "hardlink", "copy"] = "symlink"  # how images reach a mixture (symlink: referenced,
    # not copied)


@dataclass(frozen=True)
class Mixture:
    """``real`` real images plus ``synth`` synthetic images."""

    real: int
    synth: int

    @property
    def name(self) -> str:
        return f"R{self.real}_S{self.synth}"

    @property
    def total(self) -> int:
        return self.real + self.synth


def parse_mixture(name: str) -> Mixture:
    """``"R750_S250"`` -> ``Mixture(750, 250)``; raises :class:`MixError` on any other spelling."""
    match = _NAME.match(name.strip())
    if not match:
        raise MixError(f"mixture {name!r}: expected R<real>_S<synthetic>, e.g. R750_S250")
    mix = Mixture(int(match.group(1)), int(match.group(2)))
    if mix.total == 0:
        raise MixError(f"mixture {name!r} has no images")
    return mix


def parse_mixtures(text: str) -> list[Mixture]:
    """A comma-separated list of mixture names, duplicates removed, order kept."""
    names = [n for n in (s.strip() for s in text.split(",")) if n]
    if not names:
        raise MixError("no mixtures given")
    return list(dict.fromkeys(parse_mixture(n) for n in names))


def paper_grid(total: int = 1000, step: int = 250) -> list[Mixture]:
    """The paper's three strategies: real only (R250_S0 ... R1000_S0), constant-total mixtures
    (R750_S250, R500_S500, R250_S750) and synthetic only (R0_S250 ... R0_S1000)."""
    if total <= 0 or step <= 0 or total % step:
        raise MixError(f"total {total} must be a positive multiple of step {step}")
    sizes = range(step, total + 1, step)
    real_only = [Mixture(k, 0) for k in sizes]
    mixed = [Mixture(total - k, k) for k in range(step, total, step)]
    synth_only = [Mixture(0, k) for k in sizes]
    return real_only + mixed + synth_only


def parse_seeds(text: str) -> list[int]:
    """``"3"`` -> [3]; ``"0-4"`` -> [0, 1, 2, 3, 4]; ``"0,2,5"`` -> [0, 2, 5]."""
    seeds: list[int] = []
    for part in (p.strip() for p in text.split(",")):
        lo, dash, hi = part.partition("-")
        if not lo.isdigit() or (dash and not hi.isdigit()):
            raise MixError(f"seeds {text!r}: expected N, A-B or a comma list of those")
        seeds.extend(range(int(lo), int(hi) + 1) if dash else [int(lo)])
    return list(dict.fromkeys(seeds))


def draw_order(ds: Dataset, rng: np.random.Generator) -> list[ImageRecord]:
    """The images of ``ds`` in a seeded random order (from a path-sorted list, so reader order is irrelevant)."""
    images = sorted(ds.images, key=lambda img: ds.image_path(img).resolve().as_posix())
    return [images[i] for i in rng.permutation(len(images))]


def _source_rngs(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """The generators of the real and the synthetic order for ``seed`` (independent child streams)."""
    real_seq, synth_seq = np.random.SeedSequence(seed).spawn(2)
    return np.random.default_rng(real_seq), np.random.default_rng(synth_seq)


def real_subset(real: Dataset, mix: Mixture, seed: int) -> Dataset:
    """The real images ``mix`` trains on for ``seed`` (the first ``mix.real`` of the seed's real order, which
    does not depend on the synthetic pool), as a dataset of ``real``'s images, splits and boxes."""
    ids = {img.id for img in draw_order(real, _source_rngs(seed)[0])[: mix.real]}
    return real.filter_images(lambda img: img.id in ids)


def _tagged(ds: Dataset, role: str, default: str) -> Dataset:
    """Every image's ``source`` starts with ``role:`` (``real:``/``synth:``); others get ``role:default``."""
    images = tuple(
        img if img.source.startswith(f"{role}:") else replace(img, source=f"{role}:{default}") for img in ds.images
    )
    return replace(ds, images=images)


def check_available(real: Dataset, synth: Dataset, mixtures: Sequence[Mixture]) -> None:
    """Raise :class:`MixError` naming the first mixture that asks for more images than a source has."""
    for mix in mixtures:
        for role, pool, want in (("real", real, mix.real), ("synthetic", synth, mix.synth)):
            if want > len(pool.images):
                where = pool.info.get("source_file") or pool.info.get("source_root") or pool.root
                raise MixError(f"{mix.name}: asks for {want} {role} images but {where} has only {len(pool.images)}")


def build_mixture(
    real: Dataset,
    synth: Dataset,
    mix: Mixture,
    seed: int,
    root: Path,
    category_names: Sequence[str] = (),
) -> Dataset:
    """The dataset of ``mix`` for ``seed``: the first ``mix.real`` / ``mix.synth`` images of each seeded order.

    Every image gets split ``train``; file names are absolute (resolved against each source's root).
    Raises :class:`MixError` when a source has fewer images than asked.
    """
    check_available(real, synth, [mix])
    synth_ids = {img.id for img in draw_order(synth, _source_rngs(seed)[1])[: mix.synth]}
    parts = [
        _tagged(real_subset(real, mix, seed), "real", real.root.name),
        _tagged(synth.filter_images(lambda img: img.id in synth_ids), "synth", synth.root.name),
    ]
    names = list(category_names) or list(dict.fromkeys(real.category_names + synth.category_names))
    mixed = merge(parts, root, names)
    return replace(mixed, images=tuple(replace(img, split="train") for img in mixed.images))


def mixture_dir(out: Path, mix: Mixture, seed: int) -> Path:
    """Where the dataset of ``mix`` for ``seed`` lives: ``out/seed<S>/R<m>_S<n>``."""
    return Path(out) / SEED_DIR.format(seed=seed) / mix.name


def mixture_record(ds: Dataset, mix: Mixture, seed: int) -> dict[str, Any]:
    """``mixture.json``: the mixture, its seed and, per image, its output file, source tag and source file."""
    plan = plan_image_names(ds)
    return {
        "mixture": mix.name,
        "real": mix.real,
        "synthetic": mix.synth,
        "seed": seed,
        "images": [
            {"file_name": plan[img.id], "source": img.source, "from": img.file_name}
            for img in sorted(ds.images, key=lambda img: img.id)
        ],
    }


def write_mixture(
    real: Dataset,
    synth: Dataset,
    mix: Mixture,
    seed: int,
    out: Path,
    images: str = "symlink",
    category_names: Sequence[str] = (),
    command_args: dict[str, Any] | None = None,
    overwrite: bool = False,
    val: Dataset | None = None,
) -> Path:
    """Write one mixture folder (COCO + YOLO + data.yaml + manifest + ``mixture.json``); returns its path.

    ``images="symlink"`` references the source files instead of copying them. ``val``: a YOLO validation set
    whose image folders become the ``val`` entry of ``data.yaml`` (default: the training images); raises
    :class:`MixError` when ultralytics could not use it (no label files where it looks, other class ids).
    """
    folder = mixture_dir(out, mix, seed)
    ds = build_mixture(real, synth, mix, seed, folder, category_names)
    try:
        val_folders = ultralytics_val_folders(val, ds.category_names) if val is not None else []
    except ValueError as exc:
        raise MixError(f"validation set: {exc}") from None
    args = {**(command_args or {}), "mixture": mix.name, "seed": seed}
    write_dataset(
        ds, folder, ("coco", "yolo"), images, command="mix", args=args, overwrite=overwrite, yolo_val=val_folders
    )
    record = mixture_record(ds, mix, seed)
    (folder / MIXTURE_FILE).write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return folder

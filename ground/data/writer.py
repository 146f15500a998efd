"""Write a self-describing dataset folder: ``images/``, ``annotations.json`` (COCO), ``labels/`` +
``data.yaml`` (YOLO) and ``manifest.json``. Never writes into, or over, the folder the images come from."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Final

from ground.data.dataset import Dataset, source_roots
from ground.data.formats.coco import write_coco
from ground.data.formats.yolo import write_data_yaml, write_yolo_labels
from ground.data.manifest import build_manifest, hash_files, write_manifest
from ground.data.problems import Problem
from ground.run.progress import progress

IMAGE_MODES: tuple[str, ...] = ("copy", "hardlink", "symlink", "reference")
#: How images reach a written dataset unless told: copies (the output stands alone).
DEFAULT_IMAGE_MODE: Final = "copy"
OUTPUT_FORMATS: tuple[str, ...] = ("coco", "yolo")


class OutputError(Exception):
    """The output folder cannot be written safely."""


@dataclass
class WriteResult:
    out: Path
    files: dict[str, str] = field(default_factory=dict)
    problems: list[Problem] = field(default_factory=list)


def plan_image_names(ds: Dataset) -> dict[int, str]:
    """image id -> ``images/<split>/<name>``; names made unique per folder by stem (labels share stems)."""
    taken: set[tuple[str, str]] = set()
    plan: dict[int, str] = {}
    for img in ds.images:
        folder = f"images/{img.split}" if img.split else "images"
        src = Path(img.file_name)
        stem, suffix = src.stem, src.suffix.lower()
        candidate, n = stem, 1
        while (folder, candidate.lower()) in taken:
            n += 1
            candidate = f"{stem}_{n}"
        taken.add((folder, candidate.lower()))
        plan[img.id] = f"{folder}/{candidate}{suffix}"
    return plan


def check_output_folder(out: Path, ds: Dataset, overwrite: bool) -> None:
    """Raise :class:`OutputError` when writing ``out`` could touch the source images or a user's files."""
    out_r = out.resolve()
    for root in source_roots(ds):
        if out_r.is_relative_to(Path(root)):
            raise OutputError(f"{out}: the output must not be inside the source folder {root}")
    for img in ds.images:
        if ds.image_path(img).resolve().is_relative_to(out_r):
            raise OutputError(f"{out}: source image {img.file_name} lies inside the output folder")
    check_output_target(out, overwrite)


def check_output_target(out: Path, overwrite: bool) -> None:
    """Raise :class:`OutputError` when ``out`` holds a user's files, or a fuzzyfire dataset and not
    ``overwrite``: the check a command makes before its work, when what it will write is not known yet."""
    if out.exists() and not out.is_dir():
        raise OutputError(f"{out}: is a file, not a folder; choose another --out")
    if out.exists() and any(out.iterdir()):
        if not (out / "manifest.json").is_file():
            raise OutputError(f"{out}: folder is not empty and is not a fuzzyfire dataset; choose another --out")
        if not overwrite:
            raise OutputError(f"{out}: a fuzzyfire dataset is already there; pass --overwrite to replace it")


def _clear_previous(out: Path) -> None:
    for name in ("images", "labels"):
        if (out / name).is_dir():
            shutil.rmtree(out / name)
    for name in ("annotations.json", "data.yaml", "manifest.json"):
        (out / name).unlink(missing_ok=True)


def _place(src: Path, dst: Path, mode: str) -> None:
    dst.parent.mkdir(parents=True, exist_ok=True)
    if mode == "symlink":
        os.symlink(src.resolve(), dst)
        return
    if mode == "hardlink":
        try:
            os.link(src, dst)
            return
        except OSError:
            pass  # other device or no link support: fall through to a copy
    shutil.copyfile(src, dst)


def materialize_images(ds: Dataset, out: Path, mode: str) -> Dataset:
    """Place every image under ``out/images`` (or reference it by absolute path); returns the dataset
    re-rooted at ``out`` with the new file names."""
    if mode not in IMAGE_MODES:
        raise ValueError(f"unknown image mode {mode!r}; choose one of {', '.join(IMAGE_MODES)}")
    if mode == "reference":
        return replace(ds.with_absolute_paths(), root=out)
    plan = plan_image_names(ds)
    jobs = [(ds.image_path(img), out / plan[img.id]) for img in ds.images]
    with ThreadPoolExecutor(max_workers=8) as pool:
        done = pool.map(lambda job: _place(job[0], job[1], mode), jobs)
        for _ in progress(done, total=len(jobs), desc=f"{mode} images"):
            pass
    images = tuple(replace(img, file_name=plan[img.id]) for img in ds.images)
    return replace(ds, root=out, images=images)


def write_dataset(
    ds: Dataset,
    out: Path | str,
    formats: Sequence[str] = OUTPUT_FORMATS,
    images: str = DEFAULT_IMAGE_MODE,
    command: str = "",
    args: Mapping[str, Any] | None = None,
    sources: Iterable[Path] = (),
    overwrite: bool = False,
    generated: bool = False,
    yolo_val: Sequence[Path] = (),
) -> WriteResult:
    """Write ``ds`` to the folder ``out`` in the given formats, with a manifest.

    The manifest hashes ``sources`` (configs, input files) and lists every image as ``{"file": output name,
    "sha256", "bytes", "source": original path}``. ``generated=True`` says the images were made by fuzzyfire
    in a temporary place: ``source`` is left out, so the manifest never points at files that are gone.
    ``yolo_val``: absolute image folders of a validation set for ``data.yaml``'s ``val`` (see
    :func:`ground.data.formats.yolo.write_data_yaml`).
    """
    out = Path(out)
    unknown = [f for f in formats if f not in OUTPUT_FORMATS]
    if unknown or not formats:
        raise ValueError(f"unknown output format(s) {unknown}; choose from {', '.join(OUTPUT_FORMATS)}")
    if "yolo" in formats and images == "reference":
        raise ValueError("YOLO needs labels beside the images: use --images copy, hardlink or symlink")
    if "yolo" in formats and ds.image_labelled:
        raise ValueError("the images hold classes per image, without boxes: YOLO has no form for that (its images "
                         "would read as negatives); write coco (--to coco), which keeps them")  # fmt: skip
    check_output_folder(out, ds, overwrite)
    _clear_previous(out)
    out.mkdir(parents=True, exist_ok=True)
    source_images = [ds.image_path(img) for img in ds.images]
    placed = materialize_images(ds, out, images)
    result = WriteResult(out)
    if "coco" in formats:
        result.files["coco"] = write_coco(placed, out).name
    if "yolo" in formats:
        result.problems += write_yolo_labels(placed, out)
        result.files["yolo"] = write_data_yaml(placed, out, yolo_val).name
    extra = {
        "images_mode": images,
        "counts": _counts(placed),
        "images": _image_entries(placed, source_images, generated),
    }
    manifest = build_manifest(command, dict(args or {}), sources, outputs=result.files, extra=extra)
    result.files["manifest"] = write_manifest(out, manifest).name
    return result


def _image_entries(placed: Dataset, source_images: Sequence[Path], generated: bool) -> list[dict[str, Any]]:
    """One entry per image in dataset order: output file name, content hash, size and (real data) source."""
    hashes = hash_files(source_images)
    entries = []
    for img, src, (sha, size) in zip(placed.images, source_images, hashes):
        entry: dict[str, Any] = {"file": img.file_name, "sha256": sha, "bytes": size}
        if not generated:
            entry["source"] = src.resolve().as_posix()
        entries.append(entry)
    return entries


def _counts(ds: Dataset) -> dict[str, Any]:
    return {
        "images": len(ds.images),
        "boxes": len(ds.annotations),
        "negatives": ds.num_negatives(),
        "categories": ds.category_names,
    }

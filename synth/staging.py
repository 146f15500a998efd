"""Staging, resume and final writing of a synthetic dataset (shared by Method 1 and Method 2).

Each image ``i`` is staged in ``<out>/../.<out name>.parts/`` as ``images/NNNNNN.jpg``, ``masks/NNNNNN.png``
(uint8 instance map: value k = the k-th fire box of the image, 0 = none; ``NNNNNN.smoke.png`` likewise for the
smoke boxes when smoke is a class) and ``records/NNNNNN.json`` (written
last, so its presence marks the image complete: an interrupted run resumes there). :func:`finish` writes the
dataset with ``ground.data.writer.write_dataset`` (COCO + YOLO + manifest with per-image metadata), copies the masks
to ``<out>/masks/`` beside the image names and draws a contact sheet.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.data.boxes import mask_to_xywh
from ground.data.dataset import Dataset, DatasetBuilder
from ground.data.writer import WriteResult, plan_image_names, write_dataset

CATEGORIES: tuple[str, ...] = ("fire", "smoke")


def instance_map(shape: tuple[int, int], masks: Sequence[NDArray[np.bool_]]) -> NDArray[np.uint8]:
    """(H, W) uint8 map: value k where the k-th (1-based) of the disjoint (H, W) bool ``masks`` is set, else 0."""
    if len(masks) > 255:
        raise ValueError("at most 255 instances per image")
    labels = np.zeros(shape, np.uint8)
    for k, m in enumerate(masks, start=1):
        labels[m] = k
    return labels


def boxes_from_masks(
    masks: Sequence[NDArray[np.bool_]], min_box_px: int
) -> tuple[list[NDArray[np.bool_]], list[list[float]], list[int]]:
    """The (H, W) bool masks whose box is at least ``min_box_px`` on both sides: (kept masks, their xywh boxes,
    their indices in ``masks``)."""
    kept, boxes, index = [], [], []
    for i, m in enumerate(masks):
        box = mask_to_xywh(m)
        if min(box[2], box[3]) >= min_box_px:
            kept.append(m)
            boxes.append(box.tolist())
            index.append(i)
    return kept, boxes, index


def staging_dir(out: Path) -> Path:
    return out.resolve().parent / f".{out.resolve().name}.parts"


RUN_FILE = "run.json"


class Staging:
    """The staging folder of ``out``. ``options`` (JSON), when given, say what the images are made with
    (``run.json``): images staged with other options are discarded (and said so), images staged with the same
    ones, or by a run that did not say, are resumed from."""

    def __init__(self, out: Path, options: Mapping[str, Any] | None = None) -> None:
        self.root = staging_dir(out)
        run_file = self.root / RUN_FILE
        stamp = None if options is None else json.dumps(dict(options), sort_keys=True)
        if stamp is not None and run_file.is_file() and run_file.read_text(encoding="utf-8") != stamp:
            print(f"{self.root}: discarding {self.count()} images staged with other options", file=sys.stderr)
            shutil.rmtree(self.root)
        for sub in ("images", "masks", "records"):
            (self.root / sub).mkdir(parents=True, exist_ok=True)
        if stamp is not None:
            run_file.write_text(stamp, encoding="utf-8")

    def count(self) -> int:
        """How many images are complete."""
        return len(list((self.root / "records").glob("*.json")))

    def abandon(self, n: int) -> None:
        """After a failed or interrupted run: remove the folder when no image is complete, else say on stderr
        how many are kept for the next run of the same command."""
        done = self.count() if self.root.is_dir() else 0
        if done == 0:
            shutil.rmtree(self.root, ignore_errors=True)
        else:
            print(
                f"{done} of {n} images are kept in {self.root}: run the same command again to resume from them "
                "(or delete that folder)",
                file=sys.stderr,
            )

    def record_path(self, i: int) -> Path:
        return self.root / "records" / f"{i:06d}.json"

    def done(self, i: int) -> bool:
        return self.record_path(i).is_file()

    def save(
        self,
        i: int,
        image: NDArray[np.uint8],
        masks: Sequence[NDArray[np.bool_]],
        record: Mapping,
        smoke_masks: Sequence[NDArray[np.bool_]] | None = None,
    ) -> None:
        """Stage image ``i``: (H, W, 3) RGB, its fire masks in box order, its record (boxes, metadata) and, when
        smoke is a class, its smoke masks in smoke-box order (``masks/NNNNNN.smoke.png``)."""
        name = f"{i:06d}"
        bgr = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
        if not cv2.imwrite(str(self.root / "images" / f"{name}.jpg"), bgr, [cv2.IMWRITE_JPEG_QUALITY, 95]):
            raise OSError(f"{self.root}: cannot write image {name}")
        cv2.imwrite(str(self.root / "masks" / f"{name}.png"), instance_map(image.shape[:2], masks))
        if smoke_masks is not None:
            cv2.imwrite(str(self.root / "masks" / f"{name}.smoke.png"), instance_map(image.shape[:2], smoke_masks))
        tmp = self.record_path(i).with_suffix(".tmp")
        tmp.write_text(json.dumps(dict(record), sort_keys=True) + "\n", encoding="utf-8")
        os.replace(tmp, self.record_path(i))

    def load(self, i: int) -> dict[str, Any]:
        return json.loads(self.record_path(i).read_text(encoding="utf-8"))


def build_dataset(staging: Staging, n: int, source: str, smoke: bool) -> tuple[Dataset, list[dict]]:
    """The staged images 0..n-1 as a Dataset (rooted at the staging folder) and their records."""
    builder = DatasetBuilder(staging.root, CATEGORIES if smoke else CATEGORIES[:1])
    records = []
    for i in range(n):
        rec = staging.load(i)
        image_id = builder.add_image(f"images/{i:06d}.jpg", rec["width"], rec["height"], source=source)
        for box in rec["boxes"]:
            builder.add_box(image_id, "fire", box)
        for box in rec.get("smoke_boxes", []) if smoke else []:
            builder.add_box(image_id, "smoke", box)
        records.append(rec)
    return builder.build(info={"description": f"fuzzyfire {source}"}), records


def _draw(pic: NDArray[np.uint8], box: Sequence[float], colour: tuple[int, int, int], width: int) -> None:
    x, y, w, h = (int(round(v)) for v in box)
    cv2.rectangle(pic, (x, y), (x + w - 1, y + h - 1), colour, width)


def contact_sheet(
    ds: Dataset,
    out: Path,
    other_boxes: Mapping[str, Sequence] | None = None,
    count: int = 16,
    cols: int = 4,
    thumb: int = 320,
) -> Path:
    """A PNG grid of the first ``count`` images with their boxes drawn (fire red, smoke grey) over
    ``other_boxes`` (file name -> xywh boxes or None, e.g. Method 1's paper boxes; yellow)."""
    tiles = []
    by_image = ds.annotations_by_image()
    for img in ds.images[:count]:
        pic = cv2.imread(str(ds.image_path(img)))
        scale = thumb / img.width
        width = max(1, int(round(1.5 / scale)))
        for box in (other_boxes or {}).get(img.file_name, []):
            if box is not None:
                _draw(pic, box, (0, 220, 255), width)
        for ann in by_image[img.id]:
            _draw(pic, ann.bbox, (0, 0, 255) if ann.category_id == 1 else (160, 160, 160), width)
        tiles.append(cv2.resize(pic, (thumb, int(round(img.height * scale))), interpolation=cv2.INTER_AREA))
    while len(tiles) % cols:
        tiles.append(np.zeros_like(tiles[0]))
    sheet = np.vstack([np.hstack(tiles[r : r + cols]) for r in range(0, len(tiles), cols)])
    path = out / "contact_sheet.png"
    cv2.imwrite(str(path), sheet)
    return path


def finish(
    staging: Staging,
    out: Path,
    n: int,
    source: str,
    command: str,
    args: Mapping[str, Any],
    smoke: bool,
    overwrite: bool,
) -> WriteResult:
    """Write the dataset, its masks (``masks/<image stem>.png``) and a contact sheet; remove the staging."""
    ds, records = build_dataset(staging, n, source, smoke)
    per_image = [rec["meta"] for rec in records]
    result = write_dataset(
        ds, out, ("coco", "yolo"), "copy", command, {**args, "per_image": per_image}, (), overwrite, generated=True
    )
    plan = plan_image_names(ds)
    extra = {}
    for img in ds.images:
        dst = out / "masks" / Path(plan[img.id]).relative_to("images").with_suffix(".png")
        dst.parent.mkdir(parents=True, exist_ok=True)
        stem = Path(img.file_name).stem
        shutil.copyfile(staging.root / "masks" / f"{stem}.png", dst)
        if (staging.root / "masks" / f"{stem}.smoke.png").is_file():
            shutil.copyfile(staging.root / "masks" / f"{stem}.smoke.png", dst.with_suffix(".smoke.png"))
        rec = records[img.id - 1]
        if rec.get("box_modes"):
            extra[plan[img.id]] = rec["box_modes"]
    if extra:
        (out / "masks" / "box_modes.json").write_text(json.dumps(extra, sort_keys=True) + "\n", encoding="utf-8")
    written = replace(ds, root=out, images=tuple(replace(img, file_name=plan[img.id]) for img in ds.images))
    others = {name: [b for boxes in modes.values() for b in boxes] for name, modes in extra.items()}
    result.files["contact_sheet"] = contact_sheet(written, out, others).name
    shutil.rmtree(staging.root)
    return result

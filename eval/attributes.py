"""What each test image shows, computed from the image and its boxes: the attributes the slices of
:mod:`eval.slices` are cut by ("on which fires does the pool help?").

Each image gets one value per attribute (None where it has none, e.g. the fire colour of a fire-free image):

- ``size``: COCO's bucket of its largest fire box (side = square root of the area in pixels: small < 32 <=
  medium < 96 <= large); ``size_fine``: the finer buckets of :data:`eval.found.SIZES`.
- ``fires``: how many fire boxes it holds (``1``, ``2-3``, ``4+``).
- ``light``: scene brightness, the mean luma (Rec. 601, 0..255) of the whole image: ``night`` < 70 <= ``dusk``
  < 110 <= ``day``.
- ``colour``: the colour of its fire, read from the brightest third of the pixels inside its fire boxes (hue
  in degrees, saturation 0..1 of OpenCV's HSV): ``chemical`` when most of them are neither red, orange nor yellow
  (hue 60-330 deg with saturation > 0.25: blue, green, violet flames), else ``yellow-white`` when they are pale or
  yellow (median saturation < 0.35 or median hue >= 35 deg), else ``orange-red``. An image labelled at the image
  level (no boxes: :attr:`ground.data.dataset.ImageRecord.labels`) is read over the whole image; its ``size``
  and ``fires`` stay None.
- ``sky``: ``sky`` when the sky (:func:`ground.image.sky.sky_mask`, at 160 px) covers at least 5 % of the image, else
  ``no sky`` (rooms, close-ups, streets between walls).
- ``blur``: the variance of the Laplacian of the grey image at 256 px on the long side (:func:`curate.scan.
  sharpness`): ``blurred`` < 50 <= ``soft`` < 200 <= ``sharp``.
- ``source``: the image's ``source`` field (its dataset, when merged from several; ``-`` when unset).
- ``smoke_colour`` and ``smoke_density``, for an image with smoke boxes (class ``smoke``; the attributes above
  read its ``fire`` boxes, or every box of a set without a ``fire`` class): the median luma (Rec. 601, 0..255) of
  the pixels inside its smoke boxes, ``black`` < 80 <= ``grey`` < 170 <= ``white``; and how its smoke stands out,
  the median CIE76 ΔE*ab of those pixels against the median colour of a ring around each box (15 % of the box's
  longer side, at least 2 px): ``thin`` < 15 <= ``dense`` (15 is about the 25th percentile of fire-smoke-608's
  labelled smoke: ``experiments/smoke_contrast.py``); None where no ring is left (a box filling the image).

Images are read at 256 px on the long side (boxes scaled with them), so the attributes of a set cost a fraction
of its scoring. A user's own attributes come from a CSV (:func:`read_attributes_csv`).
"""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from curate.decode import sharpness
from curate.stats import LARGE_AREA, SMALL_AREA
from eval.found import SIZES, bucket
from ground.data.dataset import Annotation, Dataset
from ground.image.imageio import ImageError, read_image
from ground.image.sky import sky_mask
from ground.run.progress import progress

#: The computed attributes and their values in order (ordinal ones from low to high).
ATTRIBUTES: dict[str, tuple[str, ...]] = {
    "size": ("small", "medium", "large"),
    "size_fine": tuple(name for name, _, _ in SIZES),
    "fires": ("1", "2-3", "4+"),
    "light": ("night", "dusk", "day"),
    "colour": ("orange-red", "yellow-white", "chemical"),
    "sky": ("no sky", "sky"),
    "blur": ("blurred", "soft", "sharp"),
    "source": (),
    "smoke_colour": ("white", "grey", "black"),
    "smoke_density": ("thin", "dense"),
}
SMOKE_LUMA = (80.0, 170.0)  # median luma (0..255) inside smoke boxes: black below, white from the second up
DENSE_DELTA_E = 15.0  # median ΔE*ab of a smoke box's pixels against its ring from which its smoke is dense
WORK_SIDE = 256  # long side, pixels, the attributes are computed at
COCO_SIZES = (("small", 0.0, SMALL_AREA**0.5), ("medium", SMALL_AREA**0.5, LARGE_AREA**0.5),
              ("large", LARGE_AREA**0.5, float("inf")))  # box sides of COCO's area ranges  # fmt: skip
NIGHT, DAY = 70.0, 110.0  # mean luma (0..255) below which a scene is night, at or above which it is day
SKY_SHARE = 0.05  # share of the image the sky must cover
SKY_SIDE = 160  # long side, pixels, the sky is found at (as the photo-site estimate of Method 2 finds it)
BLURRED, SOFT = 50.0, 200.0  # Laplacian variance below which an image is blurred, soft
BLUR = (("blurred", 0.0, BLURRED), ("soft", BLURRED, SOFT), ("sharp", SOFT, float("inf")))
CHEMICAL_SHARE = 0.5  # share of the bright fire pixels that must be non-warm for a chemical flame
PALE_SAT, YELLOW_HUE = 0.35, 35.0  # median saturation under which / median hue (deg) from which a fire is yellow-white

Attributes = dict[int, dict[str, str | None]]  # image id -> attribute -> value


def image_attributes(
    image: NDArray[np.uint8],
    boxes: NDArray[np.float64],
    source: str = "",
    scale: float = 1.0,
    smoke: NDArray[np.float64] | None = None,
) -> dict[str, str | None]:
    """The attributes (module docstring) of one (H, W, 3) uint8 RGB image with its fire ``boxes`` (N, 4)
    [x, y, w, h] in pixels of that image and its ``smoke`` boxes (M, 4) likewise; ``scale``: its pixels per pixel
    of the original image (a picture read smaller), so the sizes are the original's."""
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    mean = float(grey.mean())
    out: dict[str, str | None] = {
        "light": "night" if mean < NIGHT else "dusk" if mean < DAY else "day",
        "sky": "sky" if float(sky_mask(_small(image, SKY_SIDE)).mean()) >= SKY_SHARE else "no sky",
        "blur": bucket(BLUR, sharpness(image)),
        "source": source or "-",
        "size": None, "size_fine": None, "fires": None, "colour": None, "smoke_colour": None, "smoke_density": None,
    }  # fmt: skip
    if smoke is not None and len(smoke):
        out["smoke_colour"], out["smoke_density"] = smoke_look(image, smoke)
    if len(boxes):
        side = float(np.sqrt((boxes[:, 2] * boxes[:, 3]).max())) / scale
        out["size"] = bucket(COCO_SIZES, side)
        out["size_fine"] = bucket(SIZES, side)
        out["fires"] = "1" if len(boxes) == 1 else "2-3" if len(boxes) <= 3 else "4+"
        out["colour"] = fire_colour(image, boxes)
    return out


def fire_colour(image: NDArray[np.uint8], boxes: NDArray[np.float64]) -> str | None:
    """``orange-red``, ``yellow-white`` or ``chemical`` (module docstring) of the pixels inside ``boxes`` (N, 4)
    [x, y, w, h] px of the (H, W, 3) uint8 RGB ``image``; None when the boxes hold no pixel."""
    h, w = image.shape[:2]
    xyxy = np.column_stack([boxes[:, 0], boxes[:, 1], boxes[:, 0] + boxes[:, 2], boxes[:, 1] + boxes[:, 3]])
    x0, y0 = (int(max(np.floor(v), 0)) for v in xyxy[:, :2].min(axis=0))
    x1, y1 = int(min(np.ceil(xyxy[:, 2].max()), w)), int(min(np.ceil(xyxy[:, 3].max()), h))
    if x1 <= x0 or y1 <= y0:
        return None
    crop = image[y0:y1, x0:x1]  # the boxes' union: only its pixels are converted
    inside = np.zeros(crop.shape[:2], dtype=bool)
    for bx0, by0, bx1, by1 in xyxy - [x0, y0, x0, y0]:
        inside[int(max(np.floor(by0), 0)) : int(np.ceil(by1)), int(max(np.floor(bx0), 0)) : int(np.ceil(bx1))] = True
    if not inside.any():
        return None
    hsv = cv2.cvtColor(crop, cv2.COLOR_RGB2HSV)[inside].astype(np.float64)
    hue, sat, val = hsv[:, 0] * 2.0, hsv[:, 1] / 255.0, hsv[:, 2]
    bright = val >= np.quantile(val, 2 / 3)
    hue, sat = hue[bright], sat[bright]
    cold = (hue >= 60) & (hue <= 330) & (sat > 0.25)
    if cold.mean() > CHEMICAL_SHARE:
        return "chemical"
    warm_hue = np.where(hue > 330, hue - 360, hue)[~cold]  # reds just below 360 deg count as 0
    if np.median(sat[~cold]) < PALE_SAT or np.median(warm_hue) >= YELLOW_HUE:
        return "yellow-white"
    return "orange-red"


def smoke_look(image: NDArray[np.uint8], boxes: NDArray[np.float64]) -> tuple[str | None, str | None]:
    """(``smoke_colour``, ``smoke_density``) (module docstring) of the smoke ``boxes`` (M, 4) [x, y, w, h] px of the
    (H, W, 3) uint8 RGB ``image``; None for what its boxes cannot tell."""
    h, w = image.shape[:2]
    lab = cv2.cvtColor(image.astype(np.float32) / 255.0, cv2.COLOR_RGB2Lab)
    luma = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    inside = np.zeros((h, w), bool)
    contrasts = []
    for x, y, bw, bh in boxes:
        x0, y0 = int(max(np.floor(x), 0)), int(max(np.floor(y), 0))
        x1, y1 = int(min(np.ceil(x + bw), w)), int(min(np.ceil(y + bh), h))
        if x1 <= x0 or y1 <= y0:
            continue
        inside[y0:y1, x0:x1] = True
        pad = max(2, int(0.15 * max(x1 - x0, y1 - y0)))
        rx0, ry0, rx1, ry1 = max(x0 - pad, 0), max(y0 - pad, 0), min(x1 + pad, w), min(y1 + pad, h)
        ring = np.ones((ry1 - ry0, rx1 - rx0), bool)
        ring[y0 - ry0 : y1 - ry0, x0 - rx0 : x1 - rx0] = False
        if ring.sum() >= 8:
            median = np.median(lab[ry0:ry1, rx0:rx1][ring], axis=0)
            contrasts.append(float(np.median(np.sqrt(((lab[y0:y1, x0:x1] - median) ** 2).sum(-1)))))
    if not inside.any():
        return None, None
    level = float(np.median(luma[inside]))
    colour = "black" if level < SMOKE_LUMA[0] else "grey" if level < SMOKE_LUMA[1] else "white"
    density = None if not contrasts else "dense" if np.median(contrasts) >= DENSE_DELTA_E else "thin"
    return colour, density


def _small(image: NDArray[np.uint8], side: int) -> NDArray[np.uint8]:
    """``image`` (H, W, 3) shrunk to ``side`` px on its long side (as it is when already smaller). Bilinear: a
    JPEG is decoded at most 2x larger (:func:`ground.image.imageio.read_image` ``min_side``), where it matches area
    averaging closely at a fraction of its cost."""
    h, w = image.shape[:2]
    scale = side / max(h, w)
    if scale >= 1:
        return image
    return cv2.resize(image, (max(round(w * scale), 1), max(round(h * scale), 1)), interpolation=cv2.INTER_LINEAR)


def dataset_attributes(ds: Dataset, workers: int = 0) -> Attributes:
    """:func:`image_attributes` of every image of ``ds`` (its ``fire`` boxes are its fires, or every box of a set
    without a ``fire`` class; its ``smoke`` boxes its smoke), read at :data:`WORK_SIDE` px; an image that cannot be
    read raises ValueError naming it."""
    by_image = ds.annotations_by_image()
    names = {c.id: c.name for c in ds.categories}
    fire_ids = {i for i, n in names.items() if n == "fire"} or set(names)
    smoke_ids = {i for i, n in names.items() if n == "smoke"} - fire_ids

    def one(img) -> dict[str, str | None]:
        path = ds.image_path(img)
        try:
            pixels = read_image(path, min_side=WORK_SIDE)
        except ImageError as exc:
            raise ValueError(f"{path}: cannot read it for its attributes ({exc})") from None
        pixels = _small(pixels, WORK_SIDE)
        scale = pixels.shape[1] / img.width
        anns = by_image.get(img.id, [])
        fires = _boxes([a for a in anns if a.category_id in fire_ids], scale)
        smoke = _boxes([a for a in anns if a.category_id in smoke_ids], scale)
        out = image_attributes(pixels, fires, img.source, scale, smoke)
        if img.labels and out["colour"] is None:  # no box: the fire's colour is read over the whole image
            out["colour"] = fire_colour(pixels, np.asarray([[0, 0, pixels.shape[1], pixels.shape[0]]], np.float64))
        return out

    with ThreadPoolExecutor(max_workers=workers or None) as pool:
        values = list(progress(pool.map(one, ds.images), total=len(ds.images), desc="attributes"))
    return {img.id: v for img, v in zip(ds.images, values)}


def _boxes(anns: Sequence[Annotation], scale: float) -> NDArray[np.float64]:
    """(N, 4) [x, y, w, h] of the non-crowd ``anns``, times ``scale``."""
    kept = [a.bbox for a in anns if not a.iscrowd]
    return np.asarray(kept, dtype=np.float64).reshape(-1, 4) * scale


class AttributesError(ValueError):
    """A user's attributes CSV that cannot be read (the file and line in the message)."""


def read_attributes_csv(path: Path, ds: Dataset) -> Attributes:
    """A user's attributes of ``ds``'s images from the CSV ``path`` with the header ``image,attribute,value``
    (``image``: the image's ``file_name`` or file name; one row per image and attribute). Raises
    :class:`AttributesError` on a missing column, an image the set lacks, an attribute that shadows a computed one
    or an image given twice the same attribute."""
    by_name: dict[str, int] = {}
    for img in ds.images:
        by_name[img.file_name] = img.id
        by_name.setdefault(Path(img.file_name).name, img.id)
    out: Attributes = {}
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames is None or not {"image", "attribute", "value"} <= set(reader.fieldnames):
            raise AttributesError(f"{path}: the header must be image,attribute,value (got {reader.fieldnames})")
        for line, row in enumerate(reader, start=2):
            image, key, value = (row["image"] or "").strip(), (row["attribute"] or "").strip(), (row["value"] or "")
            if image not in by_name:
                raise AttributesError(f"{path}:{line}: no image {image!r} in the test set")
            if not key or key in ATTRIBUTES:
                raise AttributesError(f"{path}:{line}: attribute {key!r} is empty or computed by fuzzyfire "
                                      f"({', '.join(ATTRIBUTES)}): name yours otherwise")  # fmt: skip
            values = out.setdefault(by_name[image], {})
            if key in values:
                raise AttributesError(f"{path}:{line}: {image} has {key} twice")
            values[key] = value.strip() or None
    return out


def merged(computed: Attributes, given: Mapping[int, Mapping[str, str | None]]) -> Attributes:
    """The computed attributes of every image with the user's (``given``) added; a user attribute an image lacks
    is None for it."""
    keys = sorted({k for v in given.values() for k in v})
    return {i: {**a, **{k: given.get(i, {}).get(k) for k in keys}} for i, a in computed.items()}

"""The COCO-canonical in-memory dataset every part of fuzzyfire reads and writes.

- Images carry ``width``/``height`` (after EXIF orientation), a ``source`` tag (``real:<name>``,
  ``synth:method1``, ...) and a ``split`` (``train``/``valid``/``test`` or ``""``). Images without boxes
  (negatives) are kept.
- Annotations carry ids >= 1 and ``bbox = (x, y, w, h)`` in pixels; ``area`` is ``w * h``.
- Categories are identified by *name*; their ids are 1..K in list order (YOLO id = COCO id - 1).
- An image may instead hold classes at the *image level* (``labels``: class names, no boxes): an image-labelled
  test set (a classification layout, a folder declared ``label: fire``) is judged by image recall, never by AP.

Instances are immutable: every transformation returns a new dataset.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

#: Split names that mean the same split, tried in this order.
SPLIT_ALIASES: tuple[tuple[str, ...], ...] = (("val", "valid", "validation"),)


@dataclass(frozen=True)
class ImageRecord:
    """One image. ``file_name`` is a POSIX path relative to :attr:`Dataset.root`, or absolute. ``labels``: the
    category names the whole image holds without boxes (an image-labelled set; empty for a boxed one)."""

    id: int
    file_name: str
    width: int
    height: int
    source: str = ""
    split: str = ""
    labels: tuple[str, ...] = ()


@dataclass(frozen=True)
class Annotation:
    """One box: ``bbox`` is ``(x, y, w, h)`` in pixels of its image. ``iscrowd=1`` marks an ignore region."""

    id: int
    image_id: int
    category_id: int
    bbox: tuple[float, float, float, float]
    iscrowd: int = 0

    @property
    def area(self) -> float:
        return float(self.bbox[2] * self.bbox[3])


@dataclass(frozen=True)
class Category:
    id: int
    name: str


@dataclass(frozen=True)
class Dataset:
    """A set of images, boxes and named categories. ``root`` is where relative ``file_name`` s resolve."""

    root: Path
    images: tuple[ImageRecord, ...] = ()
    annotations: tuple[Annotation, ...] = ()
    categories: tuple[Category, ...] = ()
    info: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        ids = [c.id for c in self.categories]
        assert ids == list(range(1, len(ids) + 1)), f"category ids must be 1..K in order, got {ids}"

    # -- lookups ---------------------------------------------------------------------------------------
    @property
    def category_names(self) -> list[str]:
        return [c.name for c in self.categories]

    def category_id(self, name: str) -> int:
        """COCO id (1-based) of the category called ``name``; KeyError when absent."""
        for c in self.categories:
            if c.name == name:
                return c.id
        raise KeyError(f"no category {name!r} in {self.category_names}")

    def image_path(self, image: ImageRecord) -> Path:
        path = Path(image.file_name)
        return path if path.is_absolute() else self.root / path

    def annotations_by_image(self) -> dict[int, list[Annotation]]:
        """image id -> its annotations (every image present, negatives with an empty list)."""
        by_image: dict[int, list[Annotation]] = {img.id: [] for img in self.images}
        for ann in self.annotations:
            by_image[ann.image_id].append(ann)
        return by_image

    @property
    def splits(self) -> list[str]:
        """Split names in first-seen order."""
        return list(dict.fromkeys(img.split for img in self.images))

    def num_negatives(self) -> int:
        """Images that hold no class: no box and no image-level label."""
        holding = {a.image_id for a in self.annotations} | self.labelled_ids()
        return sum(1 for img in self.images if img.id not in holding)

    @property
    def image_labelled(self) -> bool:
        """True when some image holds a class at the image level (``labels``): an image-labelled set."""
        return any(img.labels for img in self.images)

    def labelled_ids(self, cat_ids: Iterable[int] | None = None) -> set[int]:
        """Ids of the images labelled (at the image level) with a category of ``cat_ids`` (None = any)."""
        names = None if cat_ids is None else {self.categories[c - 1].name for c in cat_ids}
        return {img.id for img in self.images if img.labels and (names is None or names & set(img.labels))}

    # -- transformations -------------------------------------------------------------------------------
    def resolve_split(self, name: str) -> str | None:
        """This dataset's split called ``name``, where ``val``, ``valid`` and ``validation`` name the same split
        (ultralytics says val, Roboflow valid); None when it has none."""
        if name in self.splits:
            return name
        group = next((g for g in SPLIT_ALIASES if name in g), ())
        return next((s for s in group if s in self.splits), None)

    def select_split(self, split: str) -> Dataset:
        """A dataset of the images of one split (ids kept; aliases as in :meth:`resolve_split`; empty when there
        is no such split)."""
        name = self.resolve_split(split)
        return self.filter_images(lambda img: name is not None and img.split == name)

    def filter_images(self, keep: Any) -> Dataset:
        """A dataset of the images for which ``keep(image)`` is true, with their annotations (ids kept)."""
        images = tuple(img for img in self.images if keep(img))
        ids = {img.id for img in images}
        anns = tuple(a for a in self.annotations if a.image_id in ids)
        return replace(self, images=images, annotations=anns)

    def with_categories(self, names: Sequence[str]) -> Dataset:
        """Re-number categories to ``names`` (order = new ids). Every current name must be in ``names``."""
        missing = [n for n in self.category_names if n not in names]
        if missing:
            raise ValueError(f"categories {missing} are not in the target list {list(names)}")
        new_id = {c.id: list(names).index(c.name) + 1 for c in self.categories}
        anns = tuple(replace(a, category_id=new_id[a.category_id]) for a in self.annotations)
        cats = tuple(Category(i + 1, n) for i, n in enumerate(names))
        return replace(self, annotations=anns, categories=cats)

    def drop_categories(self, names: Iterable[str]) -> Dataset:
        """Remove the boxes and image-level labels of the named categories (their images stay, possibly as
        negatives)."""
        drop = set(names)
        keep_names = [n for n in self.category_names if n not in drop]
        kept = replace(
            self,
            images=tuple(
                replace(i, labels=tuple(n for n in i.labels if n not in drop)) if drop & set(i.labels) else i
                for i in self.images
            ),  # fmt: skip
            annotations=tuple(a for a in self.annotations if self.categories[a.category_id - 1].name not in drop),
        )
        return _renumber_categories(kept, keep_names)

    def at_image_level(self, name: str) -> Dataset:
        """The image-level view of a boxed set: each image holding a box of category ``name`` is labelled
        ``name`` (the others hold nothing), every box set aside; categories ``[name]``. KeyError when absent."""
        cat = self.category_id(name)
        holding = {a.image_id for a in self.annotations if a.category_id == cat and not a.iscrowd}
        images = tuple(replace(i, labels=(name,) if i.id in holding else ()) for i in self.images)
        return replace(self, images=images, annotations=(), categories=(Category(1, name),))

    def with_absolute_paths(self) -> Dataset:
        """Same dataset with every ``file_name`` absolute, so it can be written or merged anywhere."""
        images = tuple(replace(img, file_name=self.image_path(img).resolve().as_posix()) for img in self.images)
        return replace(self, images=images)

    # -- COCO ------------------------------------------------------------------------------------------
    def to_coco(self) -> dict[str, Any]:
        """A COCO dict that pycocotools loads: ids >= 1, negatives kept, ``source``/``split`` per image."""
        return {
            "info": dict(self.info),
            "licenses": [],
            "images": [
                {
                    "id": img.id,
                    "file_name": img.file_name,
                    "width": img.width,
                    "height": img.height,
                    "source": img.source,
                    "split": img.split,
                    **({"labels": list(img.labels)} if img.labels else {}),
                }
                for img in self.images
            ],
            "annotations": [
                {
                    "id": a.id,
                    "image_id": a.image_id,
                    "category_id": a.category_id,
                    "bbox": [float(v) for v in a.bbox],
                    "area": a.area,
                    "iscrowd": int(a.iscrowd),
                }
                for a in self.annotations
            ],
            "categories": [{"id": c.id, "name": c.name, "supercategory": "fuzzy"} for c in self.categories],
        }


def _renumber_categories(ds: Dataset, names: Sequence[str]) -> Dataset:
    old_name = {c.id: c.name for c in ds.categories}
    new_id = {n: i + 1 for i, n in enumerate(names)}
    anns = tuple(replace(a, category_id=new_id[old_name[a.category_id]]) for a in ds.annotations)
    cats = tuple(Category(i + 1, n) for i, n in enumerate(names))
    return replace(ds, annotations=anns, categories=cats)


class DatasetBuilder:
    """Accumulates images and boxes with fresh ids (images and annotations from 1, categories by name)."""

    def __init__(self, root: Path, category_names: Sequence[str] = ()) -> None:
        self.root = Path(root)
        self._images: list[ImageRecord] = []
        self._anns: list[Annotation] = []
        self._cats: dict[str, int] = {}
        for name in category_names:
            self.category(name)

    def category(self, name: str) -> int:
        """Id of category ``name``, created (next id) when new."""
        if name not in self._cats:
            self._cats[name] = len(self._cats) + 1
        return self._cats[name]

    def add_image(
        self, file_name: str, width: int, height: int, source: str = "", split: str = "", labels: Sequence[str] = ()
    ) -> int:
        """A new image (``labels``: category names it holds at the image level, created when new); its id."""
        image_id = len(self._images) + 1
        for name in labels:
            self.category(name)
        self._images.append(ImageRecord(image_id, file_name, int(width), int(height), source, split, tuple(labels)))
        return image_id

    def add_box(self, image_id: int, category: str, bbox_xywh: Sequence[float], iscrowd: int = 0) -> int:
        ann_id = len(self._anns) + 1
        x, y, w, h = (float(v) for v in bbox_xywh)
        self._anns.append(Annotation(ann_id, image_id, self.category(category), (x, y, w, h), int(iscrowd)))
        return ann_id

    def build(self, info: Mapping[str, Any] | None = None) -> Dataset:
        cats = tuple(Category(i, n) for n, i in sorted(self._cats.items(), key=lambda kv: kv[1]))
        return Dataset(self.root, tuple(self._images), tuple(self._anns), cats, dict(info or {}))


def merge(datasets: Sequence[Dataset], root: Path, category_names: Sequence[str] = ()) -> Dataset:
    """One dataset holding copies of all images and boxes, ids re-numbered, categories united by name.

    File names become absolute (each input resolved against its own root); ``info["source_roots"]`` lists
    the inputs' roots (so writers can refuse to write into them). Inputs are not modified.
    """
    builder = DatasetBuilder(root, category_names)
    for ds in datasets:
        names = {c.id: c.name for c in ds.categories}
        anns = defaultdict(list)
        for a in ds.annotations:
            anns[a.image_id].append(a)
        for img in ds.images:
            new_id = builder.add_image(
                ds.image_path(img).resolve().as_posix(), img.width, img.height, img.source, img.split, img.labels
            )
            for a in anns[img.id]:
                builder.add_box(new_id, names[a.category_id], a.bbox, a.iscrowd)
    roots = list(dict.fromkeys(r for ds in datasets for r in source_roots(ds)))
    return builder.build({"source_roots": roots})


def source_roots(ds: Dataset) -> list[str]:
    """Folders the images of ``ds`` come from: its recorded ``source_roots``, else its own root."""
    return list(ds.info.get("source_roots") or [str(ds.root.resolve())])

"""Pick a reader by name or by looking at the folder; unknown names raise, nothing falls back silently."""

from __future__ import annotations

import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Literal

from ground.data.formats.coco import ANNOTATIONS_FILE, read_coco
from ground.data.formats.common import ReadResult
from ground.data.formats.folders import is_class_layout, read_folders
from ground.data.formats.images import read_images
from ground.data.formats.voc import read_voc
from ground.data.formats.yolo import read_dfire, read_yolo
from ground.data.walk import walk
from ground.image.imageio import is_image_file

#: A reader's name as a settings key holds it: ``auto`` (detect the format) or one of :data:`FORMATS`.
DatasetFormat = Literal["auto", "coco", "yolo", "voc", "dfire", "images", "folders"]
#: The readers by name. ``images``: a folder of images without labels, read as a negatives-only set, or every image
#: holding the class a ``label`` declares (:mod:`~ground.data.formats.images`); ``folders``: a classification
#: layout, one sub-folder per class (:mod:`~ground.data.formats.folders`).
FORMATS: tuple[str, ...] = typing.get_args(DatasetFormat)[1:]


def detect_format(path: Path | str) -> str:
    """``coco`` for a .json file or a folder with ``annotations.json``; ``voc`` for ``Annotations/`` or XML files;
    ``yolo`` for a dataset YAML file or a folder with ``data.yaml``, a ``label(s)`` folder or ``.txt`` files;
    ``folders`` for a classification layout (:func:`ground.data.formats.folders.is_class_layout`: ``fire/``,
    ``normal/``); ``images`` for a folder of images and none of these (a negatives-only set). Raises ValueError
    otherwise."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file or folder")
    if path.is_file():
        if path.suffix.lower() == ".json":
            return "coco"
        if path.suffix.lower() in (".yaml", ".yml"):
            return "yolo"
        raise ValueError(f"{path}: a single file must be a COCO .json or an ultralytics data.yaml")
    if (path / ANNOTATIONS_FILE).is_file():
        return "coco"
    if (path / "Annotations").is_dir() or next(path.glob("*.xml"), None) is not None:
        return "voc"
    if (path / "data.yaml").is_file():
        return "yolo"
    xml = images = False
    for _, dirs, files in walk(path):  # one lazy walk: the first label folder or .txt file decides
        if any(d.lower() in ("labels", "label") for d in dirs) or any(f.lower().endswith(".txt") for f in files):
            return "yolo"
        xml = xml or any(f.lower().endswith(".xml") for f in files)
        images = images or any(is_image_file(f) for f in files)
    if xml:
        return "voc"
    if images:
        return "folders" if is_class_layout(path) else "images"
    raise ValueError(f"{path}: no images, labels or annotations found; pass --from {'|'.join(FORMATS)}")


def read_dataset(
    path: Path | str,
    fmt: str | None = None,
    *,
    names: Sequence[str] | None = None,
    source: str | None = None,
    aliases: Mapping[str, str] | None = None,
    alias_option: str = "aliases",
    label: str | None = None,
) -> ReadResult:
    """Read a dataset of format ``fmt`` (``auto`` or None detects it). ``names`` only applies to YOLO. An alias of a
    class the source does not have is an :class:`~ground.data.names.UnknownNameError` naming ``alias_option``
    (the option or key that gave it: :meth:`~ground.data.formats.common.ReadResult.check_aliases`). ``label``
    declares a folder of images without label files image-labelled (every image holds that class); a source
    of any other format raises ValueError (its own labels say what its images hold)."""
    fmt = detect_format(path) if fmt in (None, "auto") else fmt
    if label is not None and fmt != "images":
        raise ValueError(f"{path}: label: {label} declares a folder of images without label files, but it reads as "
                         f"{fmt!r}{' (its folders name the classes)' if fmt == 'folders' else ' (it has labels)'}")  # fmt: skip
    readers: dict[str, Callable[[], ReadResult]] = {
        "coco": lambda: read_coco(path, source=source, aliases=aliases),
        "yolo": lambda: read_yolo(path, names=names, source=source, aliases=aliases),
        "voc": lambda: read_voc(path, source=source, aliases=aliases),
        "dfire": lambda: read_dfire(path, source=source),
        "images": lambda: read_images(path, source=source, label=label),
        "folders": lambda: read_folders(path, source=source, aliases=aliases),
    }
    if fmt not in readers:
        raise ValueError(f"unknown format {fmt!r}; choose one of {', '.join(FORMATS)}")
    return readers[fmt]().check_aliases(aliases, alias_option)

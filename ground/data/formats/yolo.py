"""YOLO txt datasets (ultralytics, Roboflow exports, D-Fire): read into a :class:`Dataset`, write back.

Layouts read: see :mod:`ground.data.formats.yolo_layout` (Roboflow, ultralytics, singular ``image``/``label``,
``JPEGImages``/``labels``, flat folders, ``data.yaml`` split entries; linked folders followed).

A label row is ``class cx cy w h`` normalised to [0, 1] (a polygon ``class x1 y1 x2 y2 ...`` becomes its
bounding box). Label files may start with a UTF-8 BOM and end lines with CRLF. Class names come from
``data.yaml`` (or another ``*.yaml`` with ``names``), ``classes.txt``, or the caller.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ground.data import boxes
from ground.data.classes import DFIRE_NAMES
from ground.data.dataset import Dataset, DatasetBuilder
from ground.data.formats.common import ClassResolver, ReadResult, probe_sizes, sanitize_box, source_tag
from ground.data.formats.images import NEGATIVES_ONLY, negatives_only_note
from ground.data.formats.yolo_layout import (
    Pair,
    dataset_root,
    missing_label_problems,
    pair_images,
    unmet_split_entries,
    unmet_text,
)
from ground.data.problems import Problem
from ground.image.imageio import ImageError


def read_yolo(
    root: Path | str,
    names: Sequence[str] | None = None,
    source: str | None = None,
    aliases: Mapping[str, str] | None = None,
) -> ReadResult:
    """Read a YOLO dataset (all splits): a folder, or an ultralytics dataset file (``data.yaml``, any name)
    whose ``path:`` (absolute, or relative to the file's folder; the file's folder when absent or missing here)
    is the dataset folder. ``names`` overrides the class names found on disk."""
    problems: list[Problem] = []
    root, doc, yaml_path = dataset_root(Path(root), problems)
    names_from, key = root, ""  # where the class names come from: the caller, or the file and key below
    if names is None and doc and "names" in doc:
        names, names_from, key = _names_from_yaml(doc, yaml_path, problems), yaml_path, "names"
    elif names is None:
        names, names_from = find_class_names(root, problems)
    resolver = ClassResolver(str(names_from), aliases, key)
    class_names = [resolver.resolve(n, problems) for n in names] if names else None
    pairs = pair_images(root, doc, problems, yaml_path)
    sizes = probe_sizes([p.image for p in pairs])
    builder = DatasetBuilder(root, class_names or ())
    tag = source_tag(root, source)
    unlabelled: set[int] = set()
    readable: list[Pair] = []
    for pair, size in zip(pairs, sizes):
        if isinstance(size, ImageError):
            problems.append(Problem(str(pair.image), f"unreadable image: {size.reason} (skipped)"))
            continue
        readable.append(pair)
        width, height = size
        name = pair.image.relative_to(root).as_posix() if pair.image.is_relative_to(root) else pair.image.as_posix()
        image_id = builder.add_image(name, width, height, tag, pair.split)
        if not pair.labelled:
            unlabelled.add(image_id)
            continue
        for category, xywh in _parse_label_file(pair.label, width, height, class_names, problems):
            builder.add_box(image_id, category if class_names else resolver.resolve(category, problems), xywh)
    problems += missing_label_problems(root, readable)
    if readable and not any(p.labelled for p in readable):
        problems = _negatives_only(root, len(readable), problems)
    info: dict[str, Any] = {"format": "yolo", "source_root": str(root.resolve())}
    unmet = unmet_split_entries(root, doc) if doc else {}
    if unmet:  # quoted when a split is missing (ground.data.load.splits_found)
        info["split_notes"] = [unmet_text(yaml_path, unmet)]
    dataset = builder.build(info)
    return ReadResult(dataset, problems, frozenset(unlabelled), tuple(resolver.seen))


def _negatives_only(root: Path, count: int, problems: list[Problem]) -> list[Problem]:
    """The problems of a dataset none of whose images has a label file: when no label file lies anywhere
    either (none matching no image), it is a negatives-only set, said once instead of "no class names" and
    "no label file" warnings."""
    if any(p.code == "orphan-labels" for p in problems):
        return problems
    kept = [p for p in problems if p.code not in ("no-class-names", "no-labels")]
    return [*kept, Problem(str(root), negatives_only_note(count), "info", code=NEGATIVES_ONLY)]


def read_dfire(root: Path | str, source: str | None = None) -> ReadResult:
    """Read D-Fire (YOLO layout, class 0 = smoke, 1 = fire)."""
    return read_yolo(root, names=DFIRE_NAMES, source=source)


def find_class_names(root: Path, problems: list[Problem]) -> tuple[list[str] | None, Path]:
    """(class names, the file they come from) from ``data.yaml`` (or another ``*.yaml`` with ``names``) or
    ``classes.txt`` in ``root``; (None, ``root``) when none has them."""
    candidates = [root / "data.yaml", *sorted(p for p in root.glob("*.yaml") if p.name != "data.yaml")]
    for path in candidates:
        if not path.is_file():
            continue
        try:
            doc = yaml.safe_load(path.read_text(encoding="utf-8-sig"))
        except (yaml.YAMLError, UnicodeDecodeError) as exc:
            if path.name != "data.yaml":  # data.yaml's is reported once by _data_yaml
                problems.append(Problem(str(path), f"unreadable YAML ({exc.__class__.__name__})"))
            continue
        if isinstance(doc, dict) and "names" in doc:
            return _names_from_yaml(doc, path, problems), path
    classes_txt = root / "classes.txt"
    if classes_txt.is_file():
        lines = classes_txt.read_text(encoding="utf-8-sig").splitlines()
        return [line.strip() for line in lines if line.strip()], classes_txt
    problems.append(
        Problem(
            str(root),
            "no data.yaml or classes.txt: class ids are kept as names ('0', '1', ...); "
            "pass --names fire,smoke or --from dfire",
            "warning",
            code="no-class-names",
        )
    )
    return None, root


def _names_from_yaml(doc: dict[str, Any], path: Path, problems: list[Problem]) -> list[str]:
    """Class names of the dataset YAML ``doc`` read from ``path``: its ``names`` (a list, or an id -> name
    mapping with ids 0..n-1; a missing id is reported and named by its number, so later ids keep their
    meaning), checked against ``nc``."""
    raw = doc["names"]
    if isinstance(raw, dict):
        try:
            by_id = {int(k): str(v) for k, v in raw.items()}
        except (TypeError, ValueError):
            problems.append(Problem(str(path), f"names: keys must be class ids 0, 1, ..., got {list(raw)} (the "
                                               "names taken in the file's order)"))  # fmt: skip
            by_id = dict(enumerate(str(v) for v in raw.values()))
        gaps = [i for i in range(max(by_id, default=-1) + 1) if i not in by_id]
        if gaps or min(by_id, default=0) < 0:
            problems.append(Problem(str(path), f"names: ids must be 0..{len(by_id) - 1}, got {sorted(by_id)} "
                                               "(a missing id is named by its number)"))  # fmt: skip
        names = [by_id.get(i, str(i)) for i in range(max(by_id, default=-1) + 1)]
    elif isinstance(raw, list):
        names = [str(n) for n in raw]
    else:
        problems.append(Problem(str(path), f"names: expected a list or an id -> name mapping, got {raw!r} (ignored)"))
        return []
    nc = doc.get("nc")
    if nc is not None and str(nc).strip() not in (str(len(names)), f"{len(names)}.0"):
        problems.append(Problem(str(path), f"nc: {nc} but names: lists {len(names)} names (the names used)", "warning"))
    return names


def _parse_label_file(
    path: Path, width: int, height: int, class_names: Sequence[str] | None, problems: list[Problem]
) -> list[tuple[str, tuple[float, float, float, float]]]:
    try:
        text = path.read_text(encoding="utf-8-sig")  # a BOM (Windows editors) is not part of the first row
    except (OSError, UnicodeDecodeError) as exc:
        problems.append(Problem(str(path), f"unreadable label file ({exc.__class__.__name__})"))
        return []
    out = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if not tokens:
            continue
        where = f"{path}:{lineno}"
        parsed = _parse_row(tokens, where, class_names, problems)
        if parsed is None:
            continue
        category, cxcywhn = parsed
        xywh = boxes.cxcywhn_to_xywh(cxcywhn, width, height)
        box = sanitize_box(xywh, width, height, where, problems)
        if box is not None:
            out.append((category, box))
    return out


def _parse_row(
    tokens: list[str], where: str, class_names: Sequence[str] | None, problems: list[Problem]
) -> tuple[str, np.ndarray] | None:
    try:
        values = [float(t) for t in tokens]
    except ValueError:
        problems.append(Problem(where, f"malformed label row {' '.join(tokens)!r} (not numbers)"))
        return None
    cls = values[0]
    if not cls.is_integer() or cls < 0 or (class_names is not None and cls >= len(class_names)):
        bound = f" (classes 0..{len(class_names) - 1})" if class_names else ""
        problems.append(Problem(where, f"class id {tokens[0]} out of range{bound} (box dropped)"))
        return None
    if len(values) == 5:
        cxcywhn = np.array(values[1:], dtype=np.float64)
    elif len(values) >= 7 and len(values) % 2 == 1:
        xy = np.array(values[1:], dtype=np.float64).reshape(-1, 2)
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        cxcywhn = np.concatenate([(lo + hi) / 2.0, hi - lo])
    else:
        problems.append(Problem(where, f"malformed label row: {len(values)} values, expected 5 (class cx cy w h)"))
        return None
    category = class_names[int(cls)] if class_names is not None else str(int(cls))
    return category, cxcywhn


def write_yolo_labels(ds: Dataset, out: Path) -> list[Problem]:
    """Write ``labels/...`` beside ``images/...`` for every image of ``ds`` (file names relative to ``out``).

    Negatives get an empty label file (ultralytics counts them as background). Crowd/ignore boxes have
    no YOLO form: they are left out and reported.
    """
    problems: list[Problem] = []
    by_image = ds.annotations_by_image()
    for img in ds.images:
        rel = Path(img.file_name)
        parts = rel.parts
        assert parts[0] == "images", f"image {img.file_name} must live under images/"
        label = out.joinpath("labels", *parts[1:]).with_suffix(".txt")
        label.parent.mkdir(parents=True, exist_ok=True)
        rows = []
        for ann in by_image[img.id]:
            if ann.iscrowd:
                problems.append(
                    Problem(img.file_name, f"crowd/ignore box {list(ann.bbox)} has no YOLO form (left out)", "info")
                )
                continue
            cx, cy, w, h = boxes.xywh_to_cxcywhn(ann.bbox, img.width, img.height)
            rows.append(f"{ann.category_id - 1} {cx:.10g} {cy:.10g} {w:.10g} {h:.10g}\n")
        label.write_text("".join(rows), encoding="utf-8")
    return problems


def ultralytics_label_path(image: Path) -> Path | None:
    """Where ultralytics looks for the label file of ``image``: the last ``images`` folder of the path replaced by
    ``labels``, suffix ``.txt``; None when no folder of the path is called ``images`` (ultralytics finds none)."""
    parts = image.parts
    i = next((k for k in range(len(parts) - 2, -1, -1) if parts[k] == "images"), None)  # case-sensitive, as there
    return None if i is None else Path(*parts[:i], "labels", *parts[i + 1 :]).with_suffix(".txt")


def ultralytics_val_folders(ds: Dataset, class_names: Sequence[str]) -> list[Path]:
    """The absolute folders holding the images of ``ds``, sorted: a ``data.yaml`` ``val`` entry for a dataset
    trained with ``class_names`` (YOLO id order).

    Raises ValueError unless ultralytics can use them as they are: the label files it looks for exist (for at
    least one image; negatives may have none) and ``ds``'s classes, in id order, are ``class_names``.
    """
    images = [(ds.root / img.file_name).absolute() for img in ds.images]
    if not images:
        raise ValueError(f"{ds.root}: no validation images")
    labels = [ultralytics_label_path(p) for p in images]
    if not any(label is not None and label.is_file() for label in labels):
        raise ValueError(
            f"{ds.root}: no YOLO label files where ultralytics looks for them (images/ -> labels/, .txt); "
            "write the set with `fuzzyfire convert --to yolo` first"
        )
    if list(ds.category_names) != list(class_names):
        raise ValueError(
            f"{ds.root}: its label files number the classes {list(ds.category_names)}, the training set "
            f"{list(class_names)}; ultralytics would mix them up"
        )
    return sorted({p.parent for p in images})


def write_data_yaml(ds: Dataset, out: Path, val: Sequence[Path] = ()) -> Path:
    """An ultralytics ``data.yaml``: ``path`` is the folder itself, splits map to ``images/<split>``.

    ``val``: absolute image folders of a validation set (:func:`ultralytics_val_folders`); by default the
    ``val``/``valid`` split, else the training images (the file's header then says so).
    """
    splits = [s for s in ds.splits]
    doc: dict[str, Any] = {"path": str(out.resolve())}
    if splits == [""]:
        doc["train"] = "images"
        doc["val"] = "images"
    else:
        named = {s: f"images/{s}" for s in splits}
        doc["train"] = named.get("train", next(iter(named.values())))
        doc["val"] = named.get("val", named.get("valid", doc["train"]))
        if "test" in named:
            doc["test"] = named["test"]
    if val:
        doc["val"] = [str(p) for p in val] if len(val) > 1 else str(val[0])
    doc["nc"] = len(ds.categories)
    doc["names"] = {c.id - 1: c.name for c in ds.categories}
    path = out / "data.yaml"
    header = "# ultralytics dataset file written by fuzzyfire; class ids are 0-based.\n"
    if doc["val"] == doc["train"]:
        header += "# val = the training images: no validation set was given (fuzzyfire mix --val).\n"
    path.write_text(header + yaml.safe_dump(doc, sort_keys=False, allow_unicode=True), encoding="utf-8")
    return path

"""COCO JSON: read any detection file (ids from 0, missing fields and foreign categories tolerated,
each oddity reported) into a :class:`Dataset`; write the canonical form pycocotools expects."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ground.data.classes import canonical_class
from ground.data.dataset import Dataset, DatasetBuilder
from ground.data.formats.common import ClassResolver, ReadResult, probe_sizes, sanitize_box, source_tag
from ground.data.problems import Problem
from ground.image.imageio import ImageError

ANNOTATIONS_FILE = "annotations.json"


def find_coco_file(path: Path) -> Path:
    """``path`` itself when it is a JSON file, else ``path/annotations.json``."""
    if path.is_file():
        return path
    candidate = path / ANNOTATIONS_FILE
    if candidate.is_file():
        return candidate
    raise FileNotFoundError(f"{path}: no COCO file (expected a .json file or a folder with {ANNOTATIONS_FILE})")


def read_coco(
    path: Path | str,
    image_root: Path | str | None = None,
    source: str | None = None,
    aliases: Mapping[str, str] | None = None,
) -> ReadResult:
    """Read a COCO JSON file (or a folder holding ``annotations.json``).

    Image files resolve against ``image_root``, else the JSON's folder, else its ``images/`` subfolder.
    Sizes are read from the image headers (a mismatch with the JSON is reported); ids are renumbered from 1.
    """
    json_path = find_coco_file(Path(path))
    problems: list[Problem] = []
    try:
        doc = json.loads(json_path.read_text(encoding="utf-8-sig"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{json_path}: not valid JSON ({exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("images"), list):
        raise ValueError(f"{json_path}: not a COCO detection file (no 'images' list)")
    root = Path(image_root) if image_root else json_path.parent
    resolver = ClassResolver(str(json_path), aliases, "categories")
    categories = _read_categories(doc, json_path, resolver, problems)
    builder = DatasetBuilder(root, list(dict.fromkeys(categories.values())))
    default_source = source_tag(json_path.parent, source)
    new_ids = _read_images(doc["images"], root, json_path, builder, default_source, source is not None, problems)
    _read_annotations(doc.get("annotations") or [], json_path, builder, categories, new_ids, problems)
    info = {"format": "coco", "source_file": str(json_path.resolve())}
    return ReadResult(builder.build(info), problems, source_classes=tuple(resolver.seen))


def id_key(value: Any) -> Any:
    """A COCO id as a lookup key: ``3``, ``"3"`` and ``3.0`` are the same id (exports write either); any other
    value is kept as it is (ids are renumbered from 1 anyway)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)) and float(value).is_integer():
        return int(value)
    if isinstance(value, str) and value.strip().lstrip("-").isdigit():
        return int(value.strip())
    return value


def _read_categories(
    doc: dict[str, Any], where: Path, resolver: ClassResolver, problems: list[Problem]
) -> dict[Any, str]:
    categories: dict[Any, str] = {}
    for cat in doc.get("categories") or []:
        if not isinstance(cat, dict) or "id" not in cat or "name" not in cat:
            problems.append(Problem(str(where), f"category entry {cat!r} lacks id or name (ignored)"))
            continue
        categories[id_key(cat["id"])] = resolver.resolve(str(cat["name"]), problems)
    return categories


def _resolve_image(root: Path, file_name: str) -> Path:
    for candidate in (root / file_name, root / "images" / file_name):
        if candidate.is_file():
            return candidate
    return root / file_name


def _read_images(
    entries: list[Any],
    root: Path,
    where: Path,
    builder: DatasetBuilder,
    default_source: str,
    force_source: bool,
    problems: list[Problem],
) -> dict[Any, tuple[int, int, int]]:
    """Adds the readable images; returns old id -> (new id, width, height)."""
    valid = [e for e in entries if isinstance(e, dict) and "id" in e and "file_name" in e]
    if len(valid) < len(entries):
        problems.append(
            Problem(str(where), f"{len(entries) - len(valid)} image entries lack id or file_name (ignored)")
        )
    paths = [_resolve_image(root, str(e["file_name"])) for e in valid]
    sizes = probe_sizes(paths)
    new_ids: dict[Any, tuple[int, int, int]] = {}
    seen: set[Any] = set()
    for entry, path, size in zip(valid, paths, sizes):
        key = id_key(entry["id"])
        if key in seen:
            problems.append(Problem(str(where), f"duplicate image id {entry['id']} (second entry ignored)"))
            continue
        seen.add(key)
        named = f"file_name {entry['file_name']!r} of image id {entry['id']} in {where}"
        if isinstance(size, ImageError):
            problems.append(Problem(str(path), f"unreadable image: {size.reason} ({named}; skipped with its boxes)"))
            continue
        width, height = size
        declared = (entry.get("width"), entry.get("height"))
        if declared != (None, None) and tuple(declared) != (width, height):
            problems.append(
                Problem(
                    str(path),
                    f"width x height {declared[0]}x{declared[1]} of image id {entry['id']} in {where}, but the "
                    f"image is {width}x{height} (image used)",
                    "warning",
                )
            )
        rel = path.relative_to(root).as_posix() if path.is_relative_to(root) else path.resolve().as_posix()
        source = default_source if force_source else str(entry.get("source") or default_source)
        labels = entry.get("labels") if isinstance(entry.get("labels"), list) else []  # image-level classes
        new_id = builder.add_image(
            rel, width, height, source, str(entry.get("split") or ""), [canonical_class(str(n)) for n in labels]
        )
        new_ids[key] = (new_id, width, height)
    return new_ids


def _read_annotations(
    entries: list[Any],
    where: Path,
    builder: DatasetBuilder,
    categories: dict[Any, str],
    new_ids: dict[Any, tuple[int, int, int]],
    problems: list[Problem],
) -> None:
    for ann in entries:
        label = f"{where} annotation id={ann.get('id') if isinstance(ann, dict) else '?'}"
        if not isinstance(ann, dict) or not isinstance(ann.get("bbox"), (list, tuple)) or len(ann["bbox"]) != 4:
            problems.append(Problem(label, "annotation without a 4-number bbox (dropped)"))
            continue
        image_key, category_key = id_key(ann.get("image_id")), id_key(ann.get("category_id"))
        if image_key not in new_ids:
            problems.append(
                Problem(label, f"annotation for unknown or unreadable image id {ann.get('image_id')} (dropped)")
            )
            continue
        if category_key not in categories:
            problems.append(Problem(label, f"category id {ann.get('category_id')} out of range (dropped)"))
            continue
        image_id, width, height = new_ids[image_key]
        try:
            raw = [float(v) for v in ann["bbox"]]
        except (TypeError, ValueError):
            problems.append(Problem(label, f"bbox {ann['bbox']!r} is not numeric (dropped)"))
            continue
        box = sanitize_box(raw, width, height, label, problems)
        if box is not None:
            builder.add_box(image_id, categories[category_key], box, int(bool(ann.get("iscrowd", 0))))


def write_coco(ds: Dataset, out: Path) -> Path:
    """Write ``out/annotations.json`` (file names as in ``ds``, relative to ``out``)."""
    path = out / ANNOTATIONS_FILE
    path.write_text(json.dumps(ds.to_coco(), indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path

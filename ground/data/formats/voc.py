"""Pascal VOC XML (labelImg, CVAT, VOC itself): one XML per image, 1-based inclusive pixel boxes.

Layouts read: ``Annotations/*.xml`` + ``JPEGImages/`` (+ ``ImageSets/Main/{train,val,test}.txt`` for
splits), or XML files beside their images. ``difficult`` objects become ``iscrowd=1`` (COCO's ignore
region, which is how VOC's own metric treats them).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path

from ground.data import boxes
from ground.data.dataset import DatasetBuilder
from ground.data.formats.common import ClassResolver, ReadResult, list_images, probe_sizes, sanitize_box, source_tag
from ground.data.problems import Problem
from ground.data.walk import walk_files
from ground.image.imageio import ImageError

_SPLITS = ("train", "val", "test")


def read_voc(root: Path | str, source: str | None = None, aliases: Mapping[str, str] | None = None) -> ReadResult:
    """Read every VOC XML below ``root`` with its image; images without XML are kept as negatives."""
    root = Path(root)
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: not a folder")
    problems: list[Problem] = []
    resolver = ClassResolver(str(root), aliases, "name")
    xmls = walk_files(root, lambda name: name.lower().endswith(".xml"))
    parsed = [(x, _parse_xml(x, problems)) for x in xmls]
    entries = []
    claimed: set[Path] = set()
    for xml_path, doc in parsed:
        if doc is None:
            continue
        image = _find_image(root, xml_path, doc["filename"])
        if image is None:
            problems.append(
                Problem(str(xml_path), f"annotation without an image (its <filename> {doc['filename']!r} not found)")
            )
            continue
        if image in claimed:
            problems.append(Problem(str(xml_path), f"second annotation file for {image.name} (ignored)"))
            continue
        claimed.add(image)
        entries.append((image, xml_path, doc))
    for image in list_images(root):
        if image not in claimed:
            problems.append(Problem(str(image), "image without annotation file (kept as a negative)", "info"))
            entries.append((image, None, None))
    entries.sort(key=lambda e: e[0].as_posix())
    splits = _read_splits(root)
    sizes = probe_sizes([e[0] for e in entries])
    builder = DatasetBuilder(root)
    tag = source_tag(root, source)
    unlabelled: set[int] = set()
    for (image, xml_path, doc), size in zip(entries, sizes):
        if isinstance(size, ImageError):
            problems.append(Problem(str(image), f"unreadable image: {size.reason} (skipped)"))
            continue
        width, height = size
        split = splits.get(image.stem, "")
        image_id = builder.add_image(image.relative_to(root).as_posix(), width, height, tag, split)
        if doc is None:
            unlabelled.add(image_id)
            continue
        if doc["size"] not in (None, (width, height)):
            problems.append(
                Problem(
                    str(xml_path),
                    f"<size> says {doc['size'][0]}x{doc['size'][1]} but the image is {width}x{height} (image used)",
                    "warning",
                )
            )
        for number, name, voc_box, difficult in doc["objects"]:
            where = f"{xml_path} object {number}"
            box = sanitize_box(boxes.voc_to_xywh(voc_box), width, height, where, problems)
            if box is not None:
                builder.add_box(image_id, resolver.resolve(name, problems, where), box, iscrowd=int(difficult))
    dataset = builder.build({"format": "voc", "source_root": str(root.resolve())})
    return ReadResult(dataset, problems, frozenset(unlabelled), tuple(resolver.seen))


def _parse_xml(path: Path, problems: list[Problem]) -> dict | None:
    try:
        tree = ET.parse(path)
    except (ET.ParseError, OSError) as exc:
        problems.append(Problem(str(path), f"unreadable XML ({exc})"))
        return None
    node = tree.getroot()
    if node.tag != "annotation":
        return None  # some other XML file, not ours to judge
    size = None
    w, h = node.findtext("size/width"), node.findtext("size/height")
    if w and h:
        try:
            size = (int(float(w)), int(float(h)))
        except ValueError:
            problems.append(Problem(str(path), f"<size> {w}x{h} is not numeric (ignored)", "warning"))
    objects = []
    for i, obj in enumerate(node.findall("object")):
        name = (obj.findtext("name") or "").strip()
        coords = [obj.findtext(f"bndbox/{k}") for k in ("xmin", "ymin", "xmax", "ymax")]
        try:
            voc_box = [float(c) for c in coords]  # type: ignore[arg-type]
        except (TypeError, ValueError):
            problems.append(Problem(f"{path} object {i + 1}", f"bndbox {coords} is missing or not numeric (dropped)"))
            continue
        if not name:
            problems.append(Problem(f"{path} object {i + 1}", "object without a <name> (dropped)"))
            continue
        objects.append((i + 1, name, voc_box, (obj.findtext("difficult") or "0").strip() in ("1", "true")))
    filename = (node.findtext("filename") or path.with_suffix(".jpg").name).strip()
    return {"filename": filename, "size": size, "objects": objects}


def _find_image(root: Path, xml_path: Path, filename: str) -> Path | None:
    name = Path(filename).name
    candidates = [xml_path.parent / name, root / "JPEGImages" / name, xml_path.parent.parent / "JPEGImages" / name]
    stem = xml_path.stem
    candidates += [xml_path.parent / f"{stem}{suffix}" for suffix in (".jpg", ".jpeg", ".png")]
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    return None


def _read_splits(root: Path) -> dict[str, str]:
    """image stem -> split from ``ImageSets/Main/{train,val,test}.txt`` when present."""
    out: dict[str, str] = {}
    for split in _SPLITS:
        listing = root / "ImageSets" / "Main" / f"{split}.txt"
        if listing.is_file():
            for line in listing.read_text(encoding="utf-8").split():
                out.setdefault(line.strip(), split)
    return out

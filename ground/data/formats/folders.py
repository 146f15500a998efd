"""A classification layout: one sub-folder of images per class, as image-level fire data is shipped (``fire/`` and
``normal/``; ``fire_images/`` and ``non_fire_images/``), optionally below split folders (``train/fire/``,
``test/nofire/``). No boxes: every image of a class folder holds that class at the image level, every image of a
folder named like :data:`NEGATIVE_FOLDERS` holds none. The set is judged by image recall, never by AP.

``format: auto`` takes a folder for this layout only when every sub-folder is named for a known class
(:data:`ground.data.classes.KNOWN_CLASSES`, with synonyms) or a negative, at least one a class, and no image lies
outside them; ``format: folders`` takes any sub-folder name as a class. The reader says what it took (an info
line, code :data:`~ground.data.formats.images.IMAGE_LABELLED`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from ground.data.classes import canonical_class, is_known, normalise_name
from ground.data.dataset import SPLIT_ALIASES, DatasetBuilder
from ground.data.formats.common import ReadResult, list_images, probe_sizes, source_tag
from ground.data.formats.images import IMAGE_LABELLED
from ground.data.problems import Problem
from ground.image.imageio import ImageError, is_image_file

#: Folder names (normalised: lower case, ``_``/``-`` as spaces) of images that hold no class.
NEGATIVE_FOLDERS: frozenset[str] = frozenset(
    {"normal", "non fire", "nonfire", "no fire", "nofire", "not fire", "fire free", "negative", "negatives",
     "neutral", "none", "background", "backgrounds", "empty", "no smoke", "non smoke", "nosmoke"}
)  # fmt: skip
#: Split folder names a layout may hold its class folders in.
SPLIT_FOLDERS: frozenset[str] = frozenset({"train", "test", *(n for group in SPLIT_ALIASES for n in group)})
_SUFFIXES = (" images", " photos", " imgs", " pictures")


def folder_class(name: str, aliases: Mapping[str, str] | None = None) -> str | None:
    """The class a folder called ``name`` holds (synonyms and ``aliases`` applied; a trailing ``_images`` or
    ``_photos`` ignored), or None for a negative folder (:data:`NEGATIVE_FOLDERS`)."""
    key = normalise_name(name)
    for suffix in _SUFFIXES:
        key = key.removesuffix(suffix)
    return None if key in NEGATIVE_FOLDERS else canonical_class(key, aliases)


def _subfolders(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith("."))


def _loose_images(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_file() and is_image_file(p.name))


def class_folders(root: Path) -> list[tuple[str, Path]]:
    """(split, class folder) of the layout at ``root``: its sub-folders, or the sub-folders of each of its split
    folders when every sub-folder is named like a split (``train``, ``valid``, ``test``)."""
    tops = _subfolders(root)
    if tops and all(p.name.lower() in SPLIT_FOLDERS for p in tops):
        return [(top.name, sub) for top in tops for sub in _subfolders(top)]
    return [("", p) for p in tops]


def is_class_layout(root: Path, aliases: Mapping[str, str] | None = None) -> bool:
    """True when ``root`` reads as a classification layout under ``format: auto`` (module docstring)."""
    folders = class_folders(root)
    if not folders or _loose_images(root) or any(_loose_images(root / s) for s in {s for s, _ in folders if s}):
        return False
    held = [folder_class(f.name, aliases) for _, f in folders]
    return all(c is None or is_known(c) for c in held) and any(c is not None for c in held)


def read_folders(root: Path | str, source: str | None = None, aliases: Mapping[str, str] | None = None) -> ReadResult:
    """Every image of the class folders below ``root`` (module docstring), labelled with its folder's class
    (none for a negative folder), split by its split folder. Unreadable images and images outside the class
    folders are skipped and named. Raises ValueError when ``root`` has no class folder with images."""
    root = Path(root)
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: not a folder")
    folders = [(split, f, folder_class(f.name, aliases), list_images(f)) for split, f in class_folders(root)]
    folders = [entry for entry in folders if entry[3]]
    if not folders:
        raise ValueError(f"{root}: no class folders with images (a classification layout has fire/ and normal/)")
    problems = [Problem(str(root), _layout_note(root, folders), "info", code=IMAGE_LABELLED)]
    loose = _loose_images(root) + [p for s in sorted({s for s, *_ in folders if s}) for p in _loose_images(root / s)]
    if loose:
        problems.append(Problem(str(root), f"{len(loose)} images outside the class folders (skipped), e.g. "
                                           f"{loose[0].relative_to(root).as_posix()}", "warning"))  # fmt: skip
    builder = DatasetBuilder(root, [c for c in dict.fromkeys(c for *_, c, _ in folders) if c])
    tag = source_tag(root, source)
    for split, _, name, paths in folders:
        for path, size in zip(paths, probe_sizes(paths)):
            if isinstance(size, ImageError):
                problems.append(Problem(str(path), f"unreadable image: {size.reason} (skipped)"))
                continue
            rel = path.relative_to(root).as_posix()
            builder.add_image(rel, size[0], size[1], tag, split, labels=(name,) if name else ())
    dataset = builder.build({"format": "folders", "source_root": str(root.resolve())})
    return ReadResult(dataset, problems, frozenset(), tuple(f.name for _, f, c, _ in folders if c))


def _layout_note(root: Path, folders: list[tuple[str, Path, str | None, list[Path]]]) -> str:
    """``classification layout: fire/ 109 images (fire), normal/ 20 (no class): an image-labelled set ...``."""
    parts = [f"{f.relative_to(root).as_posix()}/ {len(paths)} images ({c or 'no class'})" for _, f, c, paths in folders]
    return f"classification layout: {', '.join(parts)}: an image-labelled set (image recall, no AP)"

"""Where a YOLO dataset is: its folder and dataset YAML, the label file of each image, and its split.

Layouts understood (folder names case-insensitive; links to folders and files are followed, see
:mod:`ground.data.walk`):

- ``<split>/images/*.jpg`` + ``<split>/labels/*.txt`` (Roboflow, D-Fire); ``image/`` + ``label/`` (singular)
  and ``JPEGImages/`` + ``labels/`` (darknet's VOC conversion) the same way;
- ``images/<split>/*.jpg`` + ``labels/<split>/*.txt`` (ultralytics);
- ``images/`` + ``labels/`` (one split), or images with their ``.txt`` side by side (flat folders);
- a dataset YAML (``data.yaml``, or any file passed in the folder's place; :func:`dataset_root`) whose
  ``train`` / ``val`` / ``test`` entries (a folder, a ``.txt`` list of images, or a list of either; relative to
  the dataset folder, or absolute) all exist: then those entries decide the splits, as ultralytics reads them.
  Otherwise (Roboflow's ``../train/images`` entries point nowhere) the folder layout does.

Label files that pair with no image are reported per folder; when their names match images that have no label
file, the error names both folders (a layout we do not understand is never read as "no labels").
"""

from __future__ import annotations

import os
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from ground.data.dataset import SPLIT_ALIASES
from ground.data.problems import Problem
from ground.data.walk import walk_files
from ground.image.imageio import is_image_file

IMAGE_FOLDERS = frozenset({"images", "image", "jpegimages", "imgs"})  # lower case
LABEL_FOLDERS = ("labels", "label", "Labels", "Label", "LABELS")  # tried in this order beside the image folder
_LABEL_FOLDERS_LOWER = frozenset(n.lower() for n in LABEL_FOLDERS)
YAML_SPLITS = ("train", "val", "valid", "test")
NOT_LABELS = frozenset({"classes.txt", "notes.txt", "readme.txt", "labels.txt", "license.txt"})
_EXAMPLES = 3  # file names quoted per grouped problem


@dataclass(frozen=True)
class Pair:
    """An image, where its label file is, whether that file exists, and the image's split ('' = none)."""

    image: Path
    label: Path
    split: str
    labelled: bool


def last_image_folder(parts: Sequence[str], names: frozenset[str] = IMAGE_FOLDERS) -> int | None:
    """Index in a path's ``parts`` of the last folder (not the file) whose lower-case name is in ``names``."""
    for i in range(len(parts) - 2, -1, -1):
        if parts[i].lower() in names:
            return i
    return None


class LabelLocator:
    """The label path and split of an image below ``root`` (module docstring); folder lookups are cached."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self._label_dir: dict[Path, str] = {}

    def label_folder(self, base: Path) -> str:
        """Name of the label folder beside an image folder inside ``base``: the first of :data:`LABEL_FOLDERS`
        that exists, else ``labels``."""
        if base not in self._label_dir:
            self._label_dir[base] = next((n for n in LABEL_FOLDERS if (base / n).is_dir()), "labels")
        return self._label_dir[base]

    def locate(self, image: Path) -> tuple[Path, str]:
        """(label file, split from the folder layout) of ``image`` (below ``root``, or elsewhere when a data.yaml
        entry points there: then the layout is read from its absolute path)."""
        inside = image.is_relative_to(self.root)
        top = self.root if inside else Path(image.anchor)
        parts = image.relative_to(top).parts
        i = last_image_folder(parts)
        if i is None:
            return image.with_suffix(".txt"), (parts[0] if len(parts) > 1 and inside else "")
        base = top.joinpath(*parts[:i])
        label = base.joinpath(self.label_folder(base), *parts[i + 1 :]).with_suffix(".txt")
        split = parts[i - 1] if i > 0 else (parts[i + 1] if len(parts) > i + 2 else "")
        return label, split


def pair_images(
    root: Path, doc: Mapping[str, Any] | None, problems: list[Problem], yaml_path: Path | None = None
) -> list[Pair]:
    """Every image of the dataset with its label path and split, sorted by image path; duplicate stems (two
    images claiming one label file) and unpaired label files are reported in ``problems``. ``doc``: the dataset
    YAML read from ``yaml_path`` (default ``root/data.yaml``), whose split entries decide when they all exist."""
    yaml_path = yaml_path or root / "data.yaml"
    locator = LabelLocator(root)
    files = walk_files(root)  # one walk: the images, and the text files that may be labels
    found = [f for f in files if is_image_file(f.name)]
    listed = yaml_splits(root, doc, problems, yaml_path) if doc else None
    images = listed if listed is not None else [(p, "") for p in found]
    if listed is not None and len(found) > len(listed):
        left = sorted(set(found) - {p for p, _ in listed})
        keys = ", ".join(f"{k}:" for k in YAML_SPLITS if doc and doc.get(k))
        problems.append(
            Problem(
                str(yaml_path),
                f"{len(left)} images below {root} are in none of its splits ({keys}) and are not read "
                f"(e.g. {_rel(root, left[0])})",
                "warning",
            )
        )
    pairs: list[Pair] = []
    owner: dict[Path, Path] = {}
    for image, yaml_split in images:
        label, split = locator.locate(image)
        if label in owner:
            problems.append(
                Problem(str(image), f"duplicate file stem: {owner[label].name} and {image.name} share {label.name}")
            )
            continue
        owner[label] = image
        pairs.append(Pair(image, label, yaml_split or split, label.is_file()))
    unmet = unmet_split_entries(root, doc) if doc else {}
    if unmet:
        problems.append(_unmet_problem(root, yaml_path, unmet, {p.split for p in pairs}))
    problems += unpaired_labels(root, pairs, [f for f in files if _maybe_label(f.name)])
    return pairs


def unmet_split_entries(root: Path, doc: Mapping[str, Any]) -> dict[str, list[tuple[str, Path]]]:
    """The split entries of a dataset YAML ``doc`` (``train``, ``val``, ...) that name no folder or ``.txt`` image
    list here: key -> [(entry as written, the path it resolves to against ``root``)]."""
    out: dict[str, list[tuple[str, Path]]] = {}
    for key in YAML_SPLITS:
        value = doc.get(key)
        for entry in (value if isinstance(value, list) else [value]) if value else []:
            target = _normal(root, Path(str(entry)))
            if not (target.is_dir() or (target.is_file() and target.suffix.lower() == ".txt")):
                out.setdefault(key, []).append((str(entry), target))
    return out


def unmet_text(yaml_path: Path, unmet: Mapping[str, list[tuple[str, Path]]]) -> str:
    """``data.yaml: val: 'images/val' (no /abs/images/val) is not a folder or image list here``, for the entries
    :func:`unmet_split_entries` found."""
    named = [f"{key}: {entry!r} (no {target})" for key, entries in unmet.items() for entry, target in entries]
    verb = "is not a folder or image list" if len(named) == 1 else "are not folders or image lists"
    return f"{yaml_path}: {', '.join(named)} {verb} here"


def _unmet_problem(
    root: Path, yaml_path: Path, unmet: Mapping[str, list[tuple[str, Path]]], layout_splits: set[str]
) -> Problem:
    """One line on the split entries of a dataset YAML that name nothing here, after the folder layout gave the
    splits ``layout_splits``: info when the layout has each of their splits (Roboflow's ``../train/images``),
    a warning naming the splits it lacks otherwise."""
    lacking = [k for k in unmet if not next((set(g) for g in SPLIT_ALIASES if k in g), {k}) & layout_splits]
    reason = unmet_text(yaml_path, unmet).removeprefix(f"{yaml_path}: ")
    reason += f": splits taken from the folder layout of {root}"
    if not lacking:
        return Problem(str(yaml_path), reason, "info", code="yaml-splits")
    has = ", ".join(repr(s) for s in sorted(layout_splits) if s) or "none"
    lacks = " or ".join(repr(k) for k in lacking)
    return Problem(str(yaml_path), f"{reason}, which has no {lacks} split (splits: {has})", "warning", "yaml-splits")


def yaml_splits(
    root: Path, doc: Mapping[str, Any], problems: list[Problem], yaml_path: Path | None = None
) -> list[tuple[Path, str]] | None:
    """(image, split) for the images the split entries of the dataset YAML ``yaml_path`` (default
    ``root/data.yaml``; parsed: ``doc``) name, when every entry resolves to an existing folder or image-list file
    (relative entries against ``root``, absolute ones anywhere, as ultralytics reads them); None (folder layout
    decides) otherwise. A listed image that does not exist is an error naming the list file, its line and the key,
    and is left out."""
    entries = {k: doc[k] for k in YAML_SPLITS if doc.get(k)}
    if not entries or unmet_split_entries(root, doc):
        return None
    out: dict[Path, str] = {}
    for split, value in entries.items():
        for entry in value if isinstance(value, list) else [value]:
            where = f"{split}: in {yaml_path or root / 'data.yaml'}"
            for image in _entry_images(_normal(root, Path(str(entry))), where, problems):
                out.setdefault(image, split)
    return sorted(out.items(), key=lambda kv: kv[0].as_posix())


def _entry_images(target: Path, key: str, problems: list[Problem]) -> list[Path]:
    """The images of one existing split entry ``target`` (folder, or ``.txt`` list whose relative lines resolve
    against its folder); paths below the dataset folder keep the route through it. A listed image that does not
    exist is reported (``key``: which entry listed the file) and left out."""
    if target.is_dir():
        return walk_files(target, is_image_file)
    images = []
    for lineno, line in enumerate(target.read_text(encoding="utf-8-sig").splitlines(), start=1):
        if not line.strip():
            continue
        image = _normal(target.parent, Path(line.strip()))
        if image.is_file():
            images.append(image)
        else:
            problems.append(Problem(f"{target}:{lineno}", f"listed image {line.strip()!r} does not exist ({key})"))
    return images


def _normal(base: Path, path: Path) -> Path:
    """``path`` (absolute, or relative to ``base``) lexically normalised, links not resolved."""
    return Path(os.path.normpath(path if path.is_absolute() else base / path))


def unpaired_labels(root: Path, pairs: Sequence[Pair], texts: Sequence[Path]) -> list[Problem]:
    """One error per folder holding text files (``texts``, found below ``root``) that pair with no image. Only
    folders where labels are looked for count, plus any folder whose file names match images without a label file
    (a layout we did not understand: the error names the image folder)."""
    unlabelled: dict[str, list[Path]] = defaultdict(list)
    for pair in pairs:
        if not pair.labelled:
            unlabelled[pair.image.stem].append(pair.image)
    owned = {pair.label for pair in pairs}
    by_folder: dict[Path, list[Path]] = defaultdict(list)
    for txt in texts:
        if txt not in owned:
            by_folder[txt.parent].append(txt)
    looked_in = {p.label.parent for p in pairs}
    problems = []
    for folder, files in sorted(by_folder.items()):
        matches = [unlabelled[f.stem][0] for f in files if f.stem in unlabelled]
        if folder not in looked_in and folder.name.lower() not in _LABEL_FOLDERS_LOWER and not matches:
            continue  # other text files (split lists, notes): not labels
        where = files[0] if len(files) == 1 else folder
        problems.append(Problem(str(where), _unpaired_message(root, files, matches), code="orphan-labels"))
    return problems


def _maybe_label(name: str) -> bool:
    low = name.lower()
    return low.endswith(".txt") and low not in NOT_LABELS and not low.startswith("readme")


def _unpaired_message(root: Path, files: Sequence[Path], matches: Sequence[Path]) -> str:
    if len(files) == 1:
        what = "label file without an image"
    else:
        names = ", ".join(f.name for f in files[:_EXAMPLES]) + (", ..." if len(files) > _EXAMPLES else "")
        what = f"{len(files)} label files ({names}) match no image"
    if not matches:
        return what
    image_dirs = sorted({m.parent for m in matches})
    where = ", ".join(_rel(root, d) for d in image_dirs[:_EXAMPLES])
    return (
        f"{what}, but {len(matches)} share their names with images that have no label file, in {where}: if they "
        "are their labels, name the folder 'labels' beside 'images' (<split>/images + <split>/labels, or "
        "images/<split> + labels/<split>), or put each .txt beside its image"
    )


def _rel(root: Path, path: Path) -> str:
    try:
        return path.relative_to(root).as_posix() or "."
    except ValueError:
        return str(path)


def dataset_root(path: Path, problems: list[Problem]) -> tuple[Path, dict[str, Any] | None, Path]:
    """(dataset folder, parsed dataset YAML or None, the YAML's path) of a YOLO dataset given as a folder (its
    ``data.yaml``) or as a dataset YAML file. Raises FileNotFoundError / ValueError when ``path`` is neither."""
    if path.is_dir():
        return path, _data_yaml(path / "data.yaml", problems), path / "data.yaml"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such folder or dataset file")
    doc = _data_yaml(path, problems)
    if doc is None:
        raise ValueError(f"{path}: not an ultralytics dataset file (a YAML mapping with train/val/names)")
    base = doc.get("path")
    if base:
        folder = _normal(path.parent, Path(str(base)))
        if folder.is_dir():
            return folder, doc, path
        problems.append(Problem(str(path), f"path: {base!r} is not a folder here (no {folder}); {path.parent} used",
                                "warning"))  # fmt: skip
    return path.parent, doc, path


def _data_yaml(path: Path, problems: list[Problem]) -> dict[str, Any] | None:
    """The parsed dataset YAML ``path`` (None when absent or unreadable, the latter reported, as is a file that
    is not a mapping of keys)."""
    if not path.is_file():
        return None
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8-sig"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        problems.append(Problem(str(path), f"unreadable YAML ({exc.__class__.__name__})"))
        return None
    if doc is not None and not isinstance(doc, dict):
        problems.append(Problem(str(path), f"not a mapping of keys (a YAML {type(doc).__name__}): ignored", "warning"))
    return doc if isinstance(doc, dict) else None


def missing_label_problems(root: Path, pairs: list[Pair]) -> list[Problem]:
    """An info line per image without a label file (a negative); one warning instead for a split where no image
    has one (labels elsewhere, or a split of unlabelled images: say it, not 200 times)."""
    by_split: dict[str, list[Pair]] = {}
    for pair in pairs:
        by_split.setdefault(pair.split, []).append(pair)
    out = []
    for split, members in by_split.items():
        missing = [p for p in members if not p.labelled]
        if missing and len(missing) == len(members) and len(members) > 1:
            folders = sorted({str(p.label.parent) for p in missing})
            out.append(
                Problem(
                    str(root),
                    f"split {split or '(none)'!r}: none of its {len(members)} images has a label file (looked for "
                    f"in {', '.join(folders[:3])}{', ...' if len(folders) > 3 else ''}): all read as negatives",
                    "warning",
                    code="no-labels",
                )
            )
            continue
        out += [Problem(str(p.image), "image without label file (kept as a negative)", "info") for p in missing]
    return out

"""Labelled sources to merge into one dataset (the first step of a FiIW-style curation).

Schemas are plain frozen dataclasses; ``ground.config.loader`` builds them from commented YAML.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Optional

from ground.data.dataset import Dataset, merge
from ground.data.formats.registry import read_dataset
from ground.data.load import data_classes
from ground.data.problems import Problem
from ground.data.writer import DEFAULT_IMAGE_MODE


@dataclass(frozen=True)
class SourceConfig:
    """One labelled dataset folder (or COCO file)."""

    path: Path  # folder or COCO .json; relative paths resolve against the config file's folder
    format: Literal["auto", "coco", "yolo", "voc", "dfire"] = "auto"
    name: str = ""  # source tag becomes real:<name>; default: the folder name
    names: Optional[tuple[str, ...]] = None  # YOLO class names when the folder has no data.yaml
    aliases: dict[str, str] = field(default_factory=dict)  # source class name -> canonical name
    drop_classes: tuple[str, ...] = ()  # canonical names whose boxes are removed (images kept)


@dataclass(frozen=True)
class MergeConfig:
    """Several sources merged into one dataset with a fixed class list."""

    sources: tuple[SourceConfig, ...]  # the labelled datasets (each: path, format, name, names, aliases, drop_classes)
    classes: Optional[tuple[str, ...]] = None  # output classes in YOLO id order; null = every class of the sources
    # (fire and smoke first, then the others by name); a source class outside a given list is an error unless
    # mapped (aliases) or dropped (drop_classes)
    images: Literal["copy", "hardlink", "symlink"] = DEFAULT_IMAGE_MODE  # how images reach the output folder


def read_source(src: SourceConfig, base: Path) -> tuple[Dataset, list[Problem]]:
    """Read one source (paths relative to ``base``), check its ``aliases`` name its classes, drop its
    ``drop_classes``."""
    path = src.path if src.path.is_absolute() else base / src.path
    tag = f"real:{src.name}" if src.name else None
    result = read_dataset(path, src.format, names=src.names, source=tag, aliases=src.aliases)
    result = result.drop_classes(src.drop_classes, option="drop_classes")
    return result.dataset, result.problems


def merge_sources(cfg: MergeConfig, base: Path, out_root: Path) -> tuple[Dataset, list[Problem]]:
    """Read every source and merge them with the classes ``cfg.classes`` (null: every class of the sources,
    :func:`ground.data.load.data_classes`); a class outside given ``cfg.classes`` is an error, never dropped
    silently."""
    datasets, problems = [], []
    for src in cfg.sources:
        ds, found = read_source(src, base)
        problems += found
        extra = [n for n in ds.category_names if cfg.classes is not None and n not in cfg.classes]
        if extra:
            raise ValueError(
                f"{src.path}: classes {extra} are not in classes {list(cfg.classes or ())}; "
                "add them, map them with aliases, list them in drop_classes, or leave classes out (null: every "
                "class of the sources)"
            )
        datasets.append(ds)
    classes = cfg.classes if cfg.classes is not None else data_classes(*datasets)
    unboxed = sorted({n for ds in datasets for n in ds.category_names} - set(classes))  # named, never boxed
    return merge(datasets, out_root, (*classes, *unboxed)), problems

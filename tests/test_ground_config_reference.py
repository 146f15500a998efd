"""The reference generated from config dataclasses: each key's type, default and comment, in Markdown and YAML."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Optional

import yaml

from ground.config.loader import build_config
from ground.config.reference import commented_yaml, field_docs, markdown, rows, type_name


@dataclass(frozen=True)
class Lamp:
    watts: float = 40.0  # power, W
    colour: Literal["warm", "cold"] = "warm"  # light colour


@dataclass(frozen=True)
class Room:
    name: str = "den"  # the room's name
    size: Optional[int] = None  # floor area, m2; null = unknown
    # (comment lines below a field continue its comment)
    doors: tuple[Path, ...] = ()  # door files, a long
    # comment continued on the next line
    lamp: Lamp = field(default_factory=Lamp)  # the lamp


def test_field_docs_join_a_fields_comment_and_its_continuation_lines() -> None:
    docs = field_docs(Room)
    assert docs["name"] == "the room's name"
    assert docs["doors"] == "door files, a long comment continued on the next line"
    assert docs["size"] == "floor area, m2; null = unknown (comment lines below a field continue its comment)"


def test_type_names_read_as_a_user_writes_them() -> None:
    assert type_name(Optional[int]) == "int | null"
    assert type_name(tuple[Path, ...]) == "list of path"
    assert type_name(Literal["warm", "cold"]) == "warm | cold"
    assert type_name(tuple[float, float]) == "[float, float]"


def test_rows_walk_nested_sections_with_dotted_keys() -> None:
    got = {r.key: (r.type, r.default) for r in rows(Room)}
    assert got["lamp"] == ("section", None) and got["lamp.watts"] == ("float", 40.0)
    assert got["doors"] == ("list of path", [])


def test_the_commented_yaml_loads_back_as_the_defaults_and_the_page_lists_every_key() -> None:
    text = commented_yaml(Room, "a room")
    assert text.startswith("# a room\n") and "watts: 40.0" in text and "# power, W" in text
    assert build_config(yaml.safe_load(text), Room) == Room()
    page = markdown("Reference", "intro", [("room", "A room.", Room)])
    assert all(f"`{r.key}`" in page for r in rows(Room)) and "| `lamp.colour` | warm \\| cold | `warm` |" in page

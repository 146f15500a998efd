"""The configuration reference, generated from the config dataclasses themselves: each key's type, default and
the comment written beside the field (``name: type = default  # comment``, continued on ``# ...`` lines below it).

:func:`rows` walks a dataclass (nested ones as dotted keys); :func:`markdown` writes ``docs/config.md``'s tables;
:func:`commented_yaml` writes a YAML file of the defaults with each key's comment (``configs/synth-method*.yaml``).
A test regenerates both and compares them with the files, so the reference cannot drift from the code.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import types
import typing
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import yaml

from ground.config.loader import to_dict

_FIELD = re.compile(r"^    (\w+)\s*:")
_COMMENT = re.compile(r"^    #\s?(.*)$")


@dataclass(frozen=True)
class Row:
    """One key of a config: dotted ``key``, readable ``type``, ``default`` as plain data, ``doc`` (one line)."""

    key: str
    type: str
    default: Any
    doc: str
    section: bool = False  # a nested dataclass (its keys follow as rows of their own)


def field_docs(cls: type) -> dict[str, str]:
    """{field name: its comment} from the class source (and its dataclass bases'): the ``#`` comment on the field's
    line and the comment-only lines right below it, joined."""
    docs: dict[str, str] = {}
    for base in reversed(cls.__mro__[1:]):
        if dataclasses.is_dataclass(base):
            docs.update({k: v for k, v in field_docs(base).items() if v})
    current: str | None = None
    for line in inspect.getsource(cls).splitlines():
        field, comment = _FIELD.match(line), _COMMENT.match(line)
        if field and not line.lstrip().startswith("#"):
            current = field.group(1)
            own = line.split("  # ", 1)[1].strip() if "  # " in line else ""
            docs[current] = own or docs.get(current, "")
        elif comment and current is not None:
            docs[current] = f"{docs[current]} {comment.group(1).strip()}".strip()
        elif line.strip().startswith(("def ", "@")):
            current = None
    return docs


def type_name(tp: Any) -> str:
    """A type as a reader writes it: ``int``, ``float | null``, ``list of path``, ``fluid | noise``."""
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        return " | ".join("null" if a is type(None) else type_name(a) for a in args)
    if origin is typing.Literal:
        return " | ".join(str(a) for a in args)
    if origin in (list, tuple, Sequence):
        if origin is tuple and len(args) == 2 and args[1] is not Ellipsis:
            return f"[{type_name(args[0])}, {type_name(args[1])}]"
        return f"list of {type_name(args[0]) if args else 'any'}"
    if origin is dict:
        return f"mapping of {type_name(args[1]) if args else 'any'}"
    if dataclasses.is_dataclass(tp):
        return "section"
    name = getattr(tp, "__name__", str(tp))
    return {"Path": "path", "str": "text", "NoneType": "null"}.get(name, name)


def _default(f: dataclasses.Field) -> Any:
    if f.default is not dataclasses.MISSING:
        return to_dict(f.default)
    if f.default_factory is not dataclasses.MISSING:
        value = f.default_factory()
        return None if dataclasses.is_dataclass(value) else to_dict(value)
    return "(required)"


def rows(cls: type, prefix: str = "") -> list[Row]:
    """Every key of dataclass ``cls``, nested dataclasses followed (a section row, then its keys)."""
    hints, docs, out = typing.get_type_hints(cls), field_docs(cls), []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        tp, key = hints[f.name], f"{prefix}{f.name}"
        inner = _dataclass_of(tp)
        if inner is not None:
            out.append(Row(key, "section", None, docs.get(f.name, ""), section=True))
            out += rows(inner, f"{key}.")
        else:
            out.append(Row(key, type_name(tp), _default(f), docs.get(f.name, "")))
    return out


def _dataclass_of(tp: Any) -> type | None:
    """The dataclass of a field typed ``D`` or ``D | None`` (a section), else None."""
    if dataclasses.is_dataclass(tp):
        return tp
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    return args[0] if len(args) == 1 and dataclasses.is_dataclass(args[0]) else None


def flow(value: Any) -> str:
    """``value`` as one line of YAML flow style."""
    return (
        yaml.safe_dump(value, default_flow_style=True, width=10_000, sort_keys=False)
        .strip()
        .removesuffix("...")
        .strip()
    )


def markdown(title: str, intro: str, sections: Sequence[tuple[str, str, type]]) -> str:
    """A Markdown page: ``title``, ``intro``, then per (heading, text, dataclass) a table key | type | default |
    meaning."""
    lines = [f"# {title}", "", intro.strip(), ""]
    for heading, text, cls in sections:
        lines += [f"## {heading}", "", text.strip(), "", "| key | type | default | meaning |", "|---|---|---|---|"]
        for r in rows(cls):
            default = "" if r.section else f"`{flow(r.default)}`" if r.default != "(required)" else "(required)"
            doc = r.doc.replace("|", "\\|")
            lines.append(
                f"| `{r.key}` | {r.type.replace('|', chr(92) + '|')} | {default.replace('|', chr(92) + '|')} | {doc} |"
            )
        lines.append("")
    return "\n".join(lines)


def commented_yaml(cls: type, header: str, width: int = 28) -> str:
    """A YAML file of ``cls``'s defaults, one key a line with its comment (nested dataclasses as indented
    mappings), under ``header`` (comment lines)."""
    out = [f"# {line}".rstrip() for line in header.strip().splitlines()] + [""]
    _yaml_lines(cls, 0, out, width)
    return "\n".join(out) + "\n"


def _yaml_lines(cls: type, depth: int, out: list[str], width: int) -> None:
    hints, docs = typing.get_type_hints(cls), field_docs(cls)
    pad = "  " * depth
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        inner = _dataclass_of(hints[f.name])
        text = f"{pad}{f.name}:" if inner is not None else f"{pad}{f.name}: {flow(_default(f))}"
        doc = docs.get(f.name, "")
        out.append(f"{text.ljust(width)}# {doc}".rstrip() if doc else text)
        if inner is not None:
            _yaml_lines(inner, depth + 1, out, width)

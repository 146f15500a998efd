"""Typed configuration: commented YAML -> frozen dataclasses, once, at the boundary.

Unknown keys, missing required keys and wrong types raise :class:`ConfigError` naming the key's path
(``sources[1].format``). ``--set a.b=c`` overrides go through the same validation (values parsed as YAML). A file
may ``extends:`` another in its folder and override some of its keys (:func:`read_yaml`).
Supported field types: ``str int float bool Path``, ``Literal[...]``, ``Optional[T]``, ``list[T]``,
``tuple[T, ...]``, ``dict[str, T]`` and nested dataclasses.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import yaml

T = TypeVar("T")


class ConfigError(ValueError):
    """A configuration value that does not fit its schema; the message starts with the key path."""


def load_config(path: Path | str, schema: type[T], overrides: Sequence[str] = ()) -> T:
    """Read the YAML file ``path`` (with the files it ``extends``: :func:`read_yaml`), apply ``overrides``
    (``a.b=value``), build ``schema``."""
    return build_config(apply_overrides(read_yaml(Path(path)), overrides), schema)


def read_yaml(path: Path, seen: tuple[Path, ...] = ()) -> dict[str, Any]:
    """The mapping of the YAML file ``path``. A top-level ``extends: NAME.yaml`` names a file in the same folder
    (so relative paths mean the same in both) whose keys this file's keys override: mappings merge key by key,
    anything else (a list, a value, null) replaces; a chain of such files is read in turn, a cycle is refused."""
    if path.resolve() in seen:
        raise ConfigError(f"{path}: extends itself through {' -> '.join(p.name for p in seen)}")
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:  # its mark names "<unicode string>": the file's name instead
        raise ConfigError(f"{path}: invalid YAML: {str(exc).replace('<unicode string>', str(path))}") from None
    raw = {} if raw is None else raw
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: the top level must be a mapping of keys")
    base = raw.pop("extends", None)
    if base is None:
        return raw
    if not isinstance(base, str) or Path(base).name != base or not base.endswith((".yaml", ".yml")):
        raise ConfigError(f"{path}: extends: expected the name of a .yaml file in the same folder, got {base!r}")
    if not (path.parent / base).is_file():
        raise ConfigError(f"{path}: extends {base}: no such file in {path.parent}")
    return merged(read_yaml(path.parent / base, (*seen, path.resolve())), raw)


def located(path: Path | str, message: str) -> str:
    """``PATH: message``, or ``message`` when it names ``path`` first already (an error of :func:`read_yaml`)."""
    return message if message.startswith(f"{path}:") else f"{path}: {message}"


def merged(base: Mapping[str, Any], top: Mapping[str, Any]) -> dict[str, Any]:
    """``base`` with ``top``'s keys over it: where both hold a mapping, merged the same way; else ``top``'s value."""
    out = _deepcopy(dict(base))
    for key, value in top.items():
        both = isinstance(value, dict) and isinstance(out.get(key), dict)
        out[key] = merged(out[key], value) if both else _deepcopy(value)
    return out


def build_config(raw: Mapping[str, Any], schema: type[T]) -> T:
    """Build the dataclass ``schema`` from plain data, validating every key."""
    return _convert(raw, schema, "")


def apply_overrides(raw: Mapping[str, Any], overrides: Sequence[str]) -> dict[str, Any]:
    """A copy of ``raw`` with each ``dotted.key=yaml-value`` applied (list items by index: ``a.0.b=1``)."""
    out: Any = _deepcopy(raw)
    for item in overrides:
        if "=" not in item:
            raise ConfigError(f"--set {item!r}: expected KEY=VALUE, e.g. train.epochs=3")
        key, _, text = item.partition("=")
        value = yaml.safe_load(text) if text.strip() else ""
        node = out
        parts = key.strip().split(".")
        for i, part in enumerate(parts[:-1]):
            node = _child(node, part, ".".join(parts[: i + 1]))
        _assign(node, parts[-1], value, key)
    return out


def to_dict(cfg: Any) -> Any:
    """Plain data (for saving the resolved config next to a run's outputs)."""
    if dataclasses.is_dataclass(cfg):
        return {f.name: to_dict(getattr(cfg, f.name)) for f in dataclasses.fields(cfg)}
    if isinstance(cfg, (list, tuple)):
        return [to_dict(v) for v in cfg]
    if isinstance(cfg, dict):
        return {k: to_dict(v) for k, v in cfg.items()}
    if isinstance(cfg, Path):
        return cfg.as_posix()
    return cfg


def _deepcopy(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _deepcopy(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_deepcopy(v) for v in value]
    return value


def _child(node: Any, part: str, where: str) -> Any:
    if isinstance(node, list):
        if not part.isdigit() or int(part) >= len(node):
            raise ConfigError(f"{where}: no list item {part}")
        return node[int(part)]
    if not isinstance(node, dict):
        raise ConfigError(f"{where}: cannot set a key inside a {type(node).__name__}")
    return node.setdefault(part, {})


def _assign(node: Any, part: str, value: Any, where: str) -> None:
    if isinstance(node, list):
        if not part.isdigit() or int(part) >= len(node):
            raise ConfigError(f"{where}: no list item {part}")
        node[int(part)] = value
    elif isinstance(node, dict):
        node[part] = value
    else:
        raise ConfigError(f"{where}: cannot set a key inside a {type(node).__name__}")


def _join(where: str, key: str | int) -> str:
    if isinstance(key, int):
        return f"{where}[{key}]"
    return f"{where}.{key}" if where else key


def _convert(value: Any, tp: Any, where: str) -> Any:
    label = where or "<top level>"
    if dataclasses.is_dataclass(tp):
        return _convert_dataclass(value, tp, where)
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        options = [a for a in args if a is not type(None)]
        errors = []
        for option in options:
            try:
                return _convert(value, option, where)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(errors[0] if len(errors) == 1 else f"{label}: {value!r} fits none of {options}")
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(f"{label}: {value!r} is not one of {list(args)}")
        return value
    if origin in (list, tuple, Sequence):
        if not isinstance(value, list):
            raise ConfigError(f"{label}: expected a list, got {type(value).__name__} {value!r}")
        item = args[0] if args else Any
        items = [_convert(v, item, _join(where, i)) for i, v in enumerate(value)]
        return tuple(items) if origin is tuple else items
    if origin in (dict, Mapping):
        if not isinstance(value, dict):
            raise ConfigError(f"{label}: expected a mapping, got {type(value).__name__} {value!r}")
        key_tp, val_tp = args if args else (str, Any)
        return {_convert(k, key_tp, where): _convert(v, val_tp, _join(where, str(k))) for k, v in value.items()}
    return _convert_scalar(value, tp, label)


def _convert_scalar(value: Any, tp: Any, label: str) -> Any:
    if tp is Any:
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{label}: expected true or false, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{label}: expected an integer, got {value!r}")
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{label}: expected a number, got {value!r}")
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{label}: expected a string, got {value!r}")
        return value
    if tp is Path:
        if not isinstance(value, str):
            raise ConfigError(f"{label}: expected a path string, got {value!r}")
        return Path(value)
    raise ConfigError(f"{label}: unsupported type {tp!r} in the schema")


def _convert_dataclass(value: Any, tp: Any, where: str) -> Any:
    label = where or "<top level>"
    if not isinstance(value, dict):
        raise ConfigError(f"{label}: expected a mapping for {tp.__name__}, got {type(value).__name__} {value!r}")
    hints = typing.get_type_hints(tp)
    fields = {f.name: f for f in dataclasses.fields(tp) if f.init}
    unknown = [k for k in value if k not in fields]
    if unknown:
        raise ConfigError(f"{_join(where, str(unknown[0]))}: unknown key (known: {', '.join(fields)})")
    kwargs = {}
    for name, f in fields.items():
        if name in value:
            kwargs[name] = _convert(value[name], hints[name], _join(where, name))
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ConfigError(f"{_join(where, name)}: required key is missing")
    return tp(**kwargs)

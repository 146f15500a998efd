"""One way to configure a command: an optional ``CONFIG.yaml`` of its dataclass, ``--set key=value`` overrides and
a few short flags, each an alias of one or more keys with the keys' own defaults.

A command declares its :class:`Alias` list; :func:`add_settings` (its settings after its own arguments, and what it
runs) adds through :func:`add_config_options` the positional ``config``, ``--set``, ``--print-config`` and the
aliases (their help shows the dataclass default, so the help and the code cannot disagree);
:func:`command_config` builds the dataclass from the file, then the flags given, then ``--set`` (later wins,
:func:`config_from_args`), validating every value before any work (:mod:`ground.config.loader`).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import sys
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import yaml

from ground.config.loader import ConfigError, apply_overrides, build_config, read_yaml, to_dict
from ground.config.reference import flow

T = TypeVar("T")


@dataclass(frozen=True)
class Alias:
    """A flag standing for config ``keys`` (dotted): ``flag`` ("--n"), ``help`` (one line, no default: it is added
    from the dataclass), ``keys`` set from the flag's value by ``to_keys`` (default: the one key, the value as
    parsed); argparse keywords in ``kwargs`` (type, nargs, action, metavar, choices)."""

    flag: str
    keys: tuple[str, ...]
    help: str
    kwargs: Mapping[str, Any] = field(default_factory=dict)
    to_keys: Callable[[Any], dict[str, Any]] | None = None

    @property
    def dest(self) -> str:
        return "alias_" + self.flag.lstrip("-").replace("-", "_")

    def values(self, value: Any) -> dict[str, Any]:
        """{dotted key: plain YAML value} that the flag's parsed ``value`` sets."""
        if self.to_keys is not None:
            return self.to_keys(value)
        return {self.keys[0]: _plain(value)}


def one_of(values: Sequence[str]) -> dict[str, Any]:
    """:attr:`Alias.kwargs` of a flag that takes one of ``values``, shown as ``a|b|c`` in the usage and help."""
    return {"choices": tuple(values), "metavar": "|".join(values)}


def _plain(value: Any) -> Any:
    if isinstance(value, Path):
        return value.as_posix()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def key_default(schema: type, key: str) -> Any:
    """The default of the dotted ``key`` of dataclass ``schema`` (nested dataclasses followed), as plain data."""
    node: Any = schema
    value: Any = None
    for part in key.split("."):
        fields = {f.name: f for f in dataclasses.fields(node)}
        if part not in fields:
            raise KeyError(f"{key}: no key {part!r} in {node.__name__}")
        f = fields[part]
        value = f.default if f.default is not dataclasses.MISSING else f.default_factory()  # type: ignore[misc]
        node = typing.get_type_hints(node)[part]
    return to_dict(value)


def add_config_options(
    p: argparse.ArgumentParser,
    schema: type | Callable[[], type],
    aliases: Sequence[Alias],
    reference: str,
    required: bool = False,
    flag: str | None = None,
) -> None:
    """The positional ``config`` (YAML of ``schema``; optional unless ``required``), ``--set KEY=VALUE``
    (repeatable), ``--print-config``, and the ``aliases`` in a group of their own, each help ending with its keys'
    defaults from ``schema``. ``schema`` may be a function that imports and returns the dataclass: the defaults are
    then read only when the help is printed (:class:`ground.cli.commands.HelpFormatter` shows them), so building
    the command line imports no generator. ``reference``: where every key is documented (``docs/config.md#...``).
    ``flag`` (e.g. ``"--config"``): the file is that option instead of the positional, for a command whose
    positionals are its inputs (argparse cannot take an optional positional after them once an option stands
    between)."""
    where = {"dest": "config", "required": required} if flag else {"nargs": None if required else "?"}
    p.add_argument(
        flag or "config",
        type=Path,
        metavar="CONFIG.yaml",
        help=f"settings file (every key: {reference})" + ("" if required else "; default: the defaults shown here"),
        **where,  # type: ignore[arg-type]
    )
    if flag:
        p.set_defaults(config_flag=flag)
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="set any config key (dotted, the value in YAML), after CONFIG.yaml and the options; repeatable",
    )
    p.add_argument("--print-config", action="store_true", help="print the resolved settings as YAML and stop")
    add_aliases(
        p.add_argument_group("settings (each an alias of a config key; defaults are the keys')"), schema, aliases
    )


#: The page documenting every settings key, a section per command (``## synth method2``).
CONFIG_REFERENCE = "docs/config.md"


def add_settings(
    p: argparse.ArgumentParser,
    schema: type | Callable[[], type],
    aliases: Sequence[Alias],
    func: Callable[[argparse.Namespace], int],
    *,
    section: str | None = None,
    flag: str | None = None,
    required: bool = False,
) -> None:
    """The settings of command ``p`` (:func:`add_config_options`: ``CONFIG.yaml``, positional or the option
    ``flag``, ``required`` or not; ``--set``, ``--print-config``, the ``aliases`` of ``schema``) and ``func``, what
    it runs. Added after the command's own arguments, they come after them in its usage and help. The keys are
    documented under the heading ``section`` of :data:`CONFIG_REFERENCE`: by default the command as typed after
    the program's name (``curate``, ``synth method2``)."""
    heading = section or p.prog.partition(" ")[2]
    add_config_options(p, schema, aliases, f"{CONFIG_REFERENCE}#{heading.replace(' ', '-')}", required, flag)
    p.set_defaults(func=func)


def add_aliases(group: Any, schema: type | Callable[[], type], aliases: Sequence[Alias]) -> None:
    """The flags of ``aliases`` in ``group`` (a parser or an argument group), each holding ``None`` until given and
    its help ending with its keys' defaults in ``schema`` (as in :func:`add_config_options`)."""
    for a in aliases:
        kwargs = dict(a.kwargs)
        if kwargs.get("action") is None:
            kwargs.setdefault("metavar", a.flag.lstrip("-").upper().replace("-", "_"))
        action = group.add_argument(a.flag, dest=a.dest, default=None, help=a.help, **kwargs)
        action.key_defaults = functools.partial(key_defaults, schema, a.keys)  # type: ignore[attr-defined]


def key_defaults(schema: type | Callable[[], type], keys: Sequence[str]) -> str:
    """``key=default, ...`` of ``keys`` in ``schema`` (a dataclass, or a function returning it), as a help line ends."""
    cls = schema if isinstance(schema, type) else schema()
    return ", ".join(f"{k}={flow(key_default(cls, k))}" for k in keys)


def config_from_args(args: argparse.Namespace, schema: type[T], aliases: Sequence[Alias]) -> T:
    """``schema`` built from ``args.config`` (if any), then the aliases given, then ``args.set``; a
    :class:`~ground.config.loader.ConfigError` or ValueError names the file or key at fault."""
    if args.config is not None and not Path(args.config).is_file():
        what = "is a folder" if Path(args.config).is_dir() else "does not exist"
        hint = "" if getattr(args, "config_flag", None) else " (CONFIG.yaml is the optional first argument)"
        raise ConfigError(f"{args.config}: {what}, not a settings file{hint}")
    raw: dict[str, Any] = read_yaml(args.config) if args.config is not None else {}
    given = [f"{k}={flow(v)}" for a in aliases if _given(getattr(args, a.dest, None))
             for k, v in a.values(getattr(args, a.dest)).items()]  # fmt: skip
    where = f"{args.config}: " if args.config is not None else ""
    try:
        return build_config(apply_overrides(raw, [*given, *args.set]), schema)
    except (ConfigError, ValueError) as exc:
        raise ConfigError(f"{where}{exc}") from None


def _given(value: Any) -> bool:
    """Whether an alias flag was given: a value, 0 included (its default is None; a switch not given is None)."""
    return value is not None and value is not False


def print_config(cfg: Any, stream: Any = None) -> None:
    """``cfg`` as YAML (what ``--print-config`` shows): a file :func:`config_from_args` reads back unchanged."""
    yaml.safe_dump(to_dict(cfg), stream or sys.stdout, sort_keys=False, default_flow_style=None, width=100)


def command_config(
    args: argparse.Namespace, schema: type[T], aliases: Sequence[Alias], required: Mapping[str, Any] | None = None
) -> T | None:
    """A command's settings (:func:`config_from_args`), or ``None`` once ``--print-config`` has printed them (the
    command then stops). Otherwise every input of ``required`` ({name as the user types it: its value}) must be
    given: a ValueError names those that are not (they are not argparse-required, so ``--print-config`` needs
    none)."""
    cfg = config_from_args(args, schema, aliases)
    if args.print_config:
        print_config(cfg)
        return None
    missing = [name for name, value in (required or {}).items() if value is None or value == []]
    if missing:
        names = ", ".join(missing[:-1]) + " and " + missing[-1] if len(missing) > 1 else missing[0]
        raise ValueError(f"{names} {'are' if len(missing) > 1 else 'is'} required (unless --print-config)")
    return cfg

"""Helpers for every package's commands (``<package>/cli.py``): a subcommand with examples, the options of a
command that reads a dataset, its arguments for the manifest, problems printed one per line, and a dataset
written, or else ``error: ...`` on stderr for the command to return 2. Settings: :mod:`ground.cli.options`."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, TextIO

from ground.cli.options import Alias
from ground.config.loader import to_dict
from ground.data.dataset import Dataset
from ground.data.formats.common import ReadResult
from ground.data.formats.registry import FORMATS, read_dataset
from ground.data.problems import Problem, count_levels
from ground.data.writer import OutputError, WriteResult, write_dataset


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """The description (with its examples) printed as written, and every option's default in its help line:
    ``(default: VALUE)`` is added unless the help already speaks of its default or there is none to show
    (None, a switch, an empty list); an alias of config keys (:func:`ground.cli.options.add_config_options`)
    ends with ``[key=default]``, read from its dataclass now."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        key_defaults = getattr(action, "key_defaults", None)
        if key_defaults is not None:
            return f"{text} [{key_defaults()}]"
        default = action.default
        if not action.option_strings or "default" in text or default in (None, argparse.SUPPRESS):
            return text
        if isinstance(default, bool) or default == []:
            return text
        return f"{text} (default: %(default)s)".lstrip()


def add_command(sub: argparse._SubParsersAction, name: str, help: str, description: str) -> argparse.ArgumentParser:
    """The subcommand ``name`` of ``sub``: ``help`` is its line in the parent's help, ``description`` (with its
    examples) is printed as written, and every option's help shows its default (:class:`HelpFormatter`)."""
    return sub.add_parser(name, help=help, formatter_class=HelpFormatter, description=description)


def add_reader_args(p: argparse.ArgumentParser, source: bool = True) -> None:
    """Options every command that reads a dataset accepts; ``--source`` (the tag of every image) only where the
    command writes or shows the tag (``source``)."""
    p.add_argument("--from", dest="fmt", choices=("auto", *FORMATS), help="source format (default: detect)")
    p.add_argument(
        "--names",
        type=lambda s: [n.strip() for n in s.split(",") if n.strip()],
        help="YOLO class names in id order, e.g. fire,smoke",
    )
    p.add_argument(
        "--alias",
        action="append",
        default=[],
        metavar="NAME=CLASS",
        help="map a source class to a class, e.g. --alias flame_big=fire (repeatable)",
    )
    p.add_argument(
        "--drop-class",
        action="append",
        default=[],
        metavar="NAME",
        help="remove the boxes of a class (its images stay, possibly as negatives); repeatable or comma-separated",
    )
    if source:
        p.add_argument("--source", help="source tag for every image (default: real:<folder name>)")


def read_from_args(args: argparse.Namespace) -> ReadResult:
    """The dataset ``args.src`` as the options of :func:`add_reader_args` describe it: format, YOLO names,
    source tag and aliases applied, the ``--drop-class`` classes removed. An ``--alias`` or ``--drop-class`` of a
    class the dataset does not have is an :class:`~ground.data.names.UnknownNameError`."""
    source = getattr(args, "source", None)
    aliases = parse_aliases(args.alias)
    result = read_dataset(args.src, args.fmt, names=args.names, source=source, aliases=aliases, alias_option="--alias")
    return result.drop_classes(args.drop_class)


def parse_aliases(items: Sequence[str]) -> dict[str, str]:
    """``--alias NAME=CLASS`` values (see :func:`add_reader_args`) -> ``{NAME: CLASS}``."""
    out = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"--alias {item!r}: expected NAME=CLASS")
        key, _, value = item.partition("=")
        out[key.strip()] = value.strip()
    return out


def command_args(args: argparse.Namespace) -> dict:
    """The user's arguments of a command, for its manifest (no internal parser fields)."""
    return {k: v for k, v in vars(args).items() if k not in ("func", "command")}


def settings_args(args: argparse.Namespace, config: Any, aliases: Sequence[Alias]) -> dict[str, Any]:
    """The manifest's arguments of a command with settings (:mod:`ground.cli.options`): its own inputs and switches
    (:func:`command_args`, less ``CONFIG.yaml``, ``--set``, ``--print-config`` and the ``aliases``' flags, whose
    values the settings hold) and every key of its resolved ``config``."""
    settings_fields = {"config", "config_flag", "set", "print_config", *(a.dest for a in aliases)}
    return {**{k: v for k, v in command_args(args).items() if k not in settings_fields}, **to_dict(config)}


def print_problems(problems: Sequence[Problem], stream: TextIO | None = None, limit: int | None = None) -> None:
    """One ``path: reason`` line per problem on ``stream`` (stdout), then the counts on stderr."""
    stream = stream or sys.stdout
    shown = problems if limit is None else problems[:limit]
    for p in shown:
        print(p, file=stream)
    if limit is not None and len(problems) > limit:
        print(f"... and {len(problems) - limit} more (fuzzyfire validate DATASET lists every one)", file=stream)
    stream.flush()
    counts = count_levels(problems)
    print(f"{counts['error']} errors, {counts['warning']} warnings, {counts['info']} info", file=sys.stderr)


def config_provenance(command: str, args: argparse.Namespace, config: Any) -> dict[str, Any]:
    """The manifest's provenance of a command driven by a YAML config (``args.config``, hashed): ``command``,
    the resolved ``config`` and the ``--set`` overrides (keyword arguments of
    :func:`ground.data.writer.write_dataset`)."""
    return {"command": command, "args": {"config": to_dict(config), "set": args.set}, "sources": [Path(args.config)]}


def write_dataset_or_report(
    ds: Dataset, args: argparse.Namespace, command: str, formats: Sequence[str], images: str, config: Any = None
) -> WriteResult | None:
    """Write ``ds`` to ``args.out`` (``args.overwrite`` honoured) with the command's provenance in the manifest:
    its arguments, or for a command driven by a YAML config the resolved ``config``, the ``--set`` overrides and
    the config file ``args.config`` (hashed). ``None`` after printing ``error: message`` on stderr when the
    output folder is refused (the command then returns 2)."""
    if config is None:
        provenance = {"command": command, "args": command_args(args)}
    else:
        provenance = config_provenance(command, args, config)
    try:
        return write_dataset(ds, args.out, formats, images, overwrite=args.overwrite, **provenance)
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return None

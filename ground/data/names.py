"""Values that name something (a class, a split, a file): checked against what exists, so a typo is a one-line
error that lists the candidates instead of an option quietly matching nothing."""

from __future__ import annotations

from collections.abc import Iterable, Sequence


class UnknownNameError(ValueError):
    """A name that matches nothing; the message lists what it could have been (a command prints it as
    ``error: ...`` and exits 2)."""


def split_names(values: Iterable[str]) -> list[str]:
    """Repeatable, comma-separated option values as one list: ``["default,smoke", "x"]`` -> ``["default",
    "smoke", "x"]`` (blanks dropped, order kept, no repeats)."""
    return list(dict.fromkeys(part.strip() for value in values for part in value.split(",") if part.strip()))


def shown(candidates: Sequence[str]) -> str:
    """``'fire', 'smoke'`` for a message; ``none`` when there is nothing."""
    return ", ".join(repr(c) for c in candidates) or "none"


def check_names(
    kind: str, names: Iterable[str], candidates: Sequence[str], where: str = "", plural: str = "", option: str = ""
) -> None:
    """Raise :class:`UnknownNameError` naming every one of ``names`` that is not in ``candidates``: ``kind`` is
    what a name names (``plural``: its plural when not ``kind + "s"``), ``option`` the option that gave it, e.g.
    ``DATA: --drop-class 'defualt': no such class (classes: 'fire', 'default', 'smoke')``."""
    unknown = [n for n in names if n not in candidates]
    if not unknown:
        return
    prefix = f"{where}: " if where else ""
    listed = ", ".join(repr(n) for n in unknown)
    what = f"{option} {listed}: no such {kind}" if option else f"no {kind} {listed}"
    raise UnknownNameError(f"{prefix}{what} ({plural or kind + 's'}: {shown(candidates)})")

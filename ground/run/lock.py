"""The locked environment: ``requirements.lock`` at the repository root pins every installed package.

``make install`` (and so ``make test``, ``make experiment`` and CI) installs with ``-c requirements.lock``;
``make lock`` refreshes the file from a fresh, unconstrained install. The same versions on any x86-64 machine
give the same decoded pixels and the same embeddings up to float noise (``experiments/embedding_noise.py``),
hence the same curation.

:func:`lock_status` says whether this process runs on the locked versions; every manifest and results file
records it, so an output made on another environment says so.
"""

from __future__ import annotations

import hashlib
import re
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import Any

LOCK_FILE = "requirements.lock"


def default_lock_path() -> Path:
    """``requirements.lock`` of the checkout this package runs from (absent in an installed wheel)."""
    return Path(__file__).resolve().parents[2] / LOCK_FILE


def canonical_name(name: str) -> str:
    """PEP 503 normal form: ``Jinja2`` -> ``jinja2``, ``ml_dtypes`` -> ``ml-dtypes``."""
    return re.sub(r"[-_.]+", "-", name).lower()


def parse_lock(text: str) -> dict[str, str]:
    """``name==version`` lines (comments, blank lines and ``-e`` lines skipped) -> {canonical name: version}.

    Raises ValueError naming the line for anything else (a lock pins exact versions only)."""
    pins: dict[str, str] = {}
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line or line.startswith("-e "):
            continue
        name, sep, version = line.partition("==")
        if not sep or not name.strip() or not version.strip() or any(c in version for c in "<>=!~*,; "):
            raise ValueError(f"{LOCK_FILE}:{number}: {raw.strip()!r} is not an exact pin (name==version)")
        pins[canonical_name(name.strip())] = version.strip()
    return pins


def installed_version(name: str) -> str | None:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def same_version(locked: str, installed: str | None) -> bool:
    """``2.13.0`` matches ``2.13.0+cpu`` (a local build tag of the same release), as pip's ``==`` does."""
    return installed is not None and (installed == locked or installed.split("+", 1)[0] == locked)


def compare(pins: dict[str, str], installed: dict[str, str | None]) -> dict[str, dict[str, str | None]]:
    """{name: {locked, installed}} of every pin the installed versions do not match."""
    return {
        name: {"locked": version, "installed": installed.get(name)}
        for name, version in sorted(pins.items())
        if not same_version(version, installed.get(name))
    }


@lru_cache(maxsize=4)
def lock_status(path: Path | None = None) -> dict[str, Any]:
    """Whether the installed packages are the locked ones: ``{"file", "sha256", "packages", "matches",
    "differs"}`` (``differs``: {name: {locked, installed}}), or ``{"file": None, "matches": None}`` when no
    lock file is found (an installed wheel)."""
    path = path or default_lock_path()
    if not path.is_file():
        return {"file": None, "matches": None}
    text = path.read_text(encoding="utf-8")
    pins = parse_lock(text)
    differs = compare(pins, {name: installed_version(name) for name in pins})
    return {
        "file": LOCK_FILE,
        "sha256": hashlib.sha256(text.encode("utf-8")).hexdigest()[:16],
        "packages": len(pins),
        "matches": not differs,
        "differs": differs,
    }


def lock_summary(status: dict[str, Any]) -> str:
    """One line for a console: ``locked environment (62 packages)`` or what differs."""
    if status["matches"] is None:
        return "no requirements.lock found: versions not checked"
    if status["matches"]:
        return f"locked environment ({status['packages']} packages, {status['file']} {status['sha256']})"
    shown = ", ".join(f"{n} {d['installed'] or 'missing'} (locked {d['locked']})" for n, d in status["differs"].items())
    return f"environment differs from {status['file']}: {shown}"


def main() -> int:
    """``python -m ground.run.lock``: print :func:`lock_summary`; exit 1 when the environment differs."""
    status = lock_status()
    print(lock_summary(status))
    return 1 if status["matches"] is False else 0


if __name__ == "__main__":
    raise SystemExit(main())

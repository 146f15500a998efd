"""Figures a study derives once from a run's ``predictions.json`` and keeps beside it, each file with the digest
of the predictions it was read from, so a set scored again is read again (:mod:`fuzzyfire.aggregate`,
:mod:`fuzzyfire.slicing`)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path


def digest(predictions: bytes) -> str:
    """The digest of a ``predictions.json`` (its bytes)."""
    return hashlib.sha256(predictions).hexdigest()[:16]


def kept(path: Path, predictions: bytes) -> dict | None:
    """The figures kept in ``path`` when they were read from these ``predictions`` (the file's bytes), else None."""
    if not path.is_file():
        return None
    doc = json.loads(path.read_text(encoding="utf-8"))
    return doc if doc.get("predictions") == digest(predictions) else None


def keep(path: Path, predictions: bytes, doc: dict) -> None:
    """Keep ``doc``, figures read from ``predictions`` (the file's bytes), in ``path`` with their digest."""
    path.write_text(json.dumps({"predictions": digest(predictions), **doc}) + "\n", encoding="utf-8")

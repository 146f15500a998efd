"""Class identity by name: case-insensitive, with a synonym table.

Across datasets, the *name* of a class (``fire``, ``smoke``) is its identity; numeric ids are local to a file.
"""

from __future__ import annotations

from collections.abc import Mapping

#: The vocabulary fuzzyfire knows. Other classes are kept under their own (normalised) name and reported.
KNOWN_CLASSES: tuple[str, ...] = ("fire", "smoke")

#: Lower-cased, whitespace-normalised aliases -> canonical name.
SYNONYMS: Mapping[str, str] = {
    "fire": "fire",
    "fires": "fire",
    "flame": "fire",
    "flames": "fire",
    "fire flame": "fire",
    "wildfire": "fire",
    "smoke": "smoke",
    "smokes": "smoke",
    "fume": "smoke",
    "fumes": "smoke",
}

#: D-Fire's YOLO class ids.
DFIRE_NAMES: tuple[str, ...] = ("smoke", "fire")


def normalise_name(name: str) -> str:
    """Lower case, ``_``/``-`` as spaces, runs of white space folded: ``"Fire_Flame "`` -> ``"fire flame"``."""
    return " ".join(str(name).replace("_", " ").replace("-", " ").lower().split())


def canonical_class(name: str, extra: Mapping[str, str] | None = None) -> str:
    """Canonical name of a class: the synonym table (plus ``extra`` user aliases), else the normalised name."""
    key = normalise_name(name)
    if extra:
        user = {normalise_name(k): v for k, v in extra.items()}
        if key in user:
            return normalise_name(user[key])
    return SYNONYMS.get(key, key)


def is_known(name: str) -> bool:
    """True for a canonical name in :data:`KNOWN_CLASSES`."""
    return name in KNOWN_CLASSES

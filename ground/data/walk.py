"""Walk a folder tree the way a user sees it: symlinked folders and files are followed (shared clusters link
``train/images`` to a folder elsewhere), each real folder is entered once (a link loop ends there), hidden
entries (``.name``) are skipped, and paths keep the route they were found by (``root/link/x.jpg``), so they
stay relative to ``root``.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path


def walk(root: Path | str) -> Iterator[tuple[Path, list[str], list[str]]]:
    """``(folder, sub-folder names, file names)`` below ``root`` (``root`` first), top-down, names sorted."""
    seen: set[tuple[int, int]] = set()
    for dirpath, dirnames, filenames in os.walk(root, followlinks=True):
        st = os.stat(dirpath)
        key = (st.st_dev, st.st_ino)
        if key in seen:  # reached again through a link: a loop or a second route to the same folder
            dirnames[:] = []
            continue
        seen.add(key)
        dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
        yield Path(dirpath), dirnames, sorted(f for f in filenames if not f.startswith("."))


def walk_files(root: Path | str, keep: Callable[[str], bool] = lambda name: True) -> list[Path]:
    """Files below ``root`` whose name passes ``keep``, sorted by POSIX path (see the module docstring)."""
    found = [folder / f for folder, _, files in walk(root) for f in files if keep(f)]
    return sorted(found, key=lambda p: p.as_posix())

"""``manifest.json``: what made a dataset folder (command, arguments, versions and whether they are the locked
ones, git commit, source files with content hashes). No timestamps, so the same inputs give a byte-identical manifest."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from importlib import metadata
from pathlib import Path
from typing import Any

from ground.run.lock import lock_status

_PACKAGES = ("fuzzyfire", "numpy", "opencv-contrib-python-headless", "pillow", "pycocotools", "torch", "onnxruntime")


def file_sha256(path: Path, chunk: int = 1 << 20) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            digest.update(block)
    return digest.hexdigest()


def versions() -> dict[str, str]:
    """Python and the installed versions of the packages that shape our outputs."""
    out = {"python": sys.version.split()[0]}
    for name in _PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return out


def git_commit(cwd: Path | None = None) -> str | None:
    """The commit of the fuzzyfire checkout (``None`` outside git), ``+dirty`` when it has changes."""
    here = cwd or Path(__file__).resolve().parent
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5)
        if sha.returncode != 0:
            return None
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=here,
            capture_output=True,
            text=True,
            timeout=5,
        )
        return sha.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return None


def hash_files(paths: Sequence[Path]) -> list[tuple[str, int]]:
    """``(sha256, bytes)`` of each file, hashed in a thread pool, in input order."""
    with ThreadPoolExecutor(max_workers=4) as pool:
        return list(pool.map(lambda p: (file_sha256(p), Path(p).stat().st_size), paths))


def build_manifest(
    command: str,
    args: Mapping[str, Any],
    sources: Iterable[Path],
    outputs: Mapping[str, str] | None = None,
    extra: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The manifest dict. ``sources`` (configs, input files) are hashed, listed sorted by path."""
    paths = sorted({Path(p).resolve() for p in sources}, key=lambda p: p.as_posix())
    hashes = hash_files(paths)
    return {
        "tool": "fuzzyfire",
        "command": command,
        "args": {k: _jsonable(v) for k, v in sorted(args.items())},
        "versions": versions(),
        "lock": lock_status(),  # whether the versions are requirements.lock's
        "git_commit": git_commit(),
        "outputs": dict(outputs or {}),
        **dict(extra or {}),
        "sources": [{"path": p.as_posix(), "sha256": h, "bytes": n} for p, (h, n) in zip(paths, hashes)],
    }


def write_manifest(out: Path, manifest: Mapping[str, Any]) -> Path:
    path = out / "manifest.json"
    path.write_text(json.dumps(manifest, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


def _jsonable(value: Any) -> Any:
    if isinstance(value, Path):
        return value.as_posix()
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    return str(value)

"""A persistent cache of per-file facts and embeddings, keyed by the file's content hash (sha256).

Renamed or moved files hit the cache; an edited file misses it. One SQLite file holds two tables:
``files_v2`` (size, width/height, decoded-pixel hash, sharpness) and ``vectors_v2`` (one float32 row per
``(model id, sha256)``). Safe for several processes (SQLite locking); used from one thread.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

_SCHEMA = """
CREATE TABLE IF NOT EXISTS files_v2 (
    sha256 TEXT PRIMARY KEY, bytes INTEGER, width INTEGER, height INTEGER, pixel_hash TEXT, sharpness REAL
);
CREATE TABLE IF NOT EXISTS vectors_v2 (
    model TEXT, sha256 TEXT, dim INTEGER, data BLOB, PRIMARY KEY (model, sha256)
);
"""
_CHUNK = 500  # keys per SELECT ... IN (...)


@dataclass(frozen=True)
class FileFacts:
    """What decoding a file taught us; independent of its path. Sizes are (after EXIF) pixels."""

    sha256: str
    bytes: int
    width: int
    height: int
    pixel_hash: str
    sharpness: float  # variance of the Laplacian of the grey image (higher = sharper)


class EmbeddingCache:
    """``get_facts`` / ``get_vectors`` / ``put``; use as a context manager (commits and closes)."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(self.path, timeout=60)
        self._db.executescript(_SCHEMA)

    def __enter__(self) -> EmbeddingCache:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._db.commit()
        self._db.close()

    def get_facts(self, shas: Sequence[str]) -> dict[str, FileFacts]:
        out = {}
        for chunk in _chunks(sorted(set(shas))):
            marks = ",".join("?" * len(chunk))
            rows = self._db.execute(f"SELECT * FROM files_v2 WHERE sha256 IN ({marks})", chunk)
            for row in rows:
                out[row[0]] = FileFacts(*row)
        return out

    def get_vectors(self, model: str, shas: Sequence[str]) -> dict[str, NDArray[np.float32]]:
        """sha256 -> (D,) float32 embedding, for the keys cached under ``model``."""
        out = {}
        for chunk in _chunks(sorted(set(shas))):
            marks = ",".join("?" * len(chunk))
            query = f"SELECT sha256, dim, data FROM vectors_v2 WHERE model = ? AND sha256 IN ({marks})"
            for sha, dim, data in self._db.execute(query, [model, *chunk]):
                vec = np.frombuffer(data, np.float32)
                if vec.shape == (dim,):
                    out[sha] = vec
        return out

    def put(self, model: str, facts: Iterable[FileFacts], vectors: NDArray[np.float32]) -> None:
        """Store ``facts`` and their embeddings (row i of ``vectors`` (N, D) belongs to facts i); commits."""
        facts = list(facts)
        assert len(facts) == len(vectors), "one vector per file"
        self._db.executemany(
            "INSERT OR REPLACE INTO files_v2 VALUES (?, ?, ?, ?, ?, ?)",
            [(f.sha256, f.bytes, f.width, f.height, f.pixel_hash, f.sharpness) for f in facts],
        )
        rows = [(model, f.sha256, int(v.shape[0]), np.asarray(v, np.float32).tobytes()) for f, v in zip(facts, vectors)]
        self._db.executemany("INSERT OR REPLACE INTO vectors_v2 VALUES (?, ?, ?, ?)", rows)
        self._db.commit()


def _chunks(keys: list[str]) -> Iterator[list[str]]:
    for i in range(0, len(keys), _CHUNK):
        yield keys[i : i + _CHUNK]

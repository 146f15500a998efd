"""The content-hash cache: round trip, per-model vectors, persistence across connections."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curate.embedcache import EmbeddingCache, FileFacts


def _facts(i: int) -> FileFacts:
    return FileFacts(f"{i:064x}", 100 + i, 10 + i, 20 + i, f"p{i}", float(i) / 3)


def test_round_trip_and_persistence(tmp_path: Path) -> None:
    vecs = np.arange(12, dtype=np.float32).reshape(3, 4)
    with EmbeddingCache(tmp_path / "c.sqlite") as cache:
        cache.put("m1", [_facts(i) for i in range(3)], vecs)
    with EmbeddingCache(tmp_path / "c.sqlite") as cache:
        shas = [_facts(i).sha256 for i in range(4)]
        facts = cache.get_facts(shas)
        assert set(facts) == set(shas[:3]) and facts[shas[1]] == _facts(1)
        got = cache.get_vectors("m1", shas)
        np.testing.assert_array_equal(np.stack([got[s] for s in shas[:3]]), vecs)
        assert cache.get_vectors("other-model", shas) == {}


def test_many_keys_are_chunked(tmp_path: Path) -> None:
    n = 1234
    vecs = np.random.default_rng(0).standard_normal((n, 8)).astype(np.float32)
    with EmbeddingCache(tmp_path / "c.sqlite") as cache:
        cache.put("m", [_facts(i) for i in range(n)], vecs)
        got = cache.get_vectors("m", [_facts(i).sha256 for i in range(n)])
    assert len(got) == n
    np.testing.assert_array_equal(got[_facts(999).sha256], vecs[999])

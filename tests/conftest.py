"""Shared test fixtures: the path to ../shared/data (tests using it skip when it is absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """``../shared/data``; skips the test when it is not there (a user's machine has no shared/ folder)."""
    if not (SHARED_DATA / "README.md").is_file():
        pytest.skip(f"real fire data not found at {SHARED_DATA} (only present in the fuzzyfire dev workspace)")
    return SHARED_DATA

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


@pytest.fixture(scope="session")
def split_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A COCO folder of 10 painted images (classes fire, smoke): ids 1-6 in split train, 7-10 in test."""
    from factories_train import painted_dataset

    from curate.core.writer import write_dataset

    root = tmp_path_factory.mktemp("split")
    ds = painted_dataset(root / "src", 10, seed=0)
    images = tuple(img.__class__(**{**img.__dict__, "split": "train" if img.id <= 6 else "test"}) for img in ds.images)
    write_dataset(ds.__class__(ds.root, images, ds.annotations, ds.categories), root / "ds", ("coco",))
    return root / "ds"

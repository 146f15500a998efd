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


@pytest.fixture(scope="session")
def ray_head(tmp_path_factory: pytest.TempPathFactory):
    """A real Ray head on loopback with 2 worker CPUs (``ray start --head``, token authentication as Ray >= 2.59
    sets it up), for the whole session; yields its address ``127.0.0.1:PORT`` and stops it at the end."""
    import os
    import shutil
    import socket
    import subprocess
    import sys

    ray_bin = shutil.which("ray") or str(Path(sys.executable).with_name("ray"))
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0"}
    env.pop("RAY_AUTH_MODE", None)
    head = [ray_bin, "start", "--head", f"--port={port}", "--num-cpus=2", "--include-dashboard=false"]
    subprocess.run(
        [*head, "--node-ip-address=127.0.0.1", "--disable-usage-stats"],
        check=True,
        capture_output=True,
        env=env,
        timeout=120,
    )
    try:
        yield f"127.0.0.1:{port}"
    finally:
        subprocess.run([ray_bin, "stop", "--force"], check=False, capture_output=True, timeout=120)


@pytest.fixture()
def cluster(ray_head: str):
    """A :class:`curate.core.cluster.Cluster` joined to :func:`ray_head`, closed after the test."""
    from curate.core.cluster import Cluster

    with Cluster(ray_head) as joined:
        yield joined

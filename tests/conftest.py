"""Shared test fixtures: the path to ../shared/data (tests using it skip when it is absent), the synthesis tests'
flame library, the built-in embedder, tiny datasets and a Ray head."""

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
def library() -> list:
    """Two tiny simulated flame sequences (:func:`factories.tiny_flames`): the synthesis tests' flame library."""
    from factories import tiny_flames

    return tiny_flames()


@pytest.fixture(scope="session")
def embedder(tmp_path_factory: pytest.TempPathFactory):  # -> curate.embed.OnnxEmbedder
    """The built-in EfficientNet-Lite0 embedder, its ONNX export cached once per test session."""
    from curate_helpers import use_session_cache

    from curate.embed import load_embedder

    use_session_cache(tmp_path_factory)
    return load_embedder()


@pytest.fixture(scope="session")
def split_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A COCO folder of 10 painted images (classes fire, smoke): ids 1-6 in split train, 7-10 in test."""
    from factories_train import painted_dataset

    from ground.data.writer import write_dataset

    root = tmp_path_factory.mktemp("split")
    ds = painted_dataset(root / "src", 10, seed=0)
    images = tuple(img.__class__(**{**img.__dict__, "split": "train" if img.id <= 6 else "test"}) for img in ds.images)
    write_dataset(ds.__class__(ds.root, images, ds.annotations, ds.categories), root / "ds", ("coco",))
    return root / "ds"


@pytest.fixture(scope="session")
def ray_head():
    """A real Ray head on loopback with 2 worker CPUs (``ray start --head --block``, token authentication as Ray
    >= 2.59 sets it up), for the whole session; yields its address ``127.0.0.1:PORT``. The head runs in a session
    of its own and that session is killed at the end, so a Ray that others run on this machine is left alone."""
    import os
    import shutil
    import signal
    import socket
    import subprocess
    import sys
    import time

    ray_bin = shutil.which("ray") or str(Path(sys.executable).with_name("ray"))
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0"}
    env.pop("RAY_AUTH_MODE", None)
    head = [ray_bin, "start", "--head", "--block", f"--port={port}", "--num-cpus=2", "--include-dashboard=false"]
    proc = subprocess.Popen(
        [*head, "--node-ip-address=127.0.0.1", "--disable-usage-stats"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 120
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"ray start --head did not come up on port {port}") from None
                time.sleep(0.5)
        time.sleep(2)  # the raylet registers after the GCS port opens
        yield f"127.0.0.1:{port}"
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
        time.sleep(1)
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # what the head left behind (raylet, workers)
        except ProcessLookupError:
            pass


@pytest.fixture()
def cluster(ray_head: str):
    """A :class:`ground.run.cluster.Cluster` joined to :func:`ray_head`, closed after the test."""
    from ground.run.cluster import Cluster

    with Cluster(ray_head) as joined:
        yield joined

"""Decoding and embedding on a real Ray head (2 workers, loopback): the same vectors, kept list, groups and
ranking as a local run, through ``fuzzyfire dedup --executor ray --address`` too; a worker killed mid-run is
retried and changes nothing; GPU shares are asked for only where they exist."""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from curate_helpers import save, scene, transformed

from curate import embedremote
from curate.dedupjob import dedup_options, run_dedup
from curate.embed import OnnxEmbedder
from curate.embedremote import TASKS_PER_GPU, task_gpus
from curate.scan import list_image_files, scan_images
from fuzzyfire.cli import main
from ground.run.cluster import Cluster, ClusterError

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 scenes at 640x480, a third with a near copy (flip, crop, resize or brighter), and a broken file."""
    root = tmp_path_factory.mktemp("imgs")
    kinds = ("hflip", "crop", "resize", "bright")
    for i in range(40):
        save(scene(i, (640, 480)), root / f"s{i:02d}.jpg")
        if i % 3 == 0:
            save(transformed(scene(i, (640, 480)), kinds[i % 4]), root / "copies" / f"c{i:02d}.jpg")
    (root / "broken.jpg").write_bytes(b"\xff\xd8\xff\xe0 not really a jpeg")
    return root


def _summary(run) -> dict:  # noqa: ANN001 - a DedupRun
    path = [im.path for im in run.scan.images]
    return {
        "kept": [path[i] for i in run.result.kept],
        "groups": [[path[i] for i in g] for g in run.result.groups],
        "ranking": [path[i] for i in run.ranking],
        "removed": [(path[r.index], path[r.duplicate_of], r.kind) for r in run.result.removed],
        "problems": [p.path for p in run.scan.problems],
    }


def test_ray_embeds_the_vectors_of_a_local_run(folder: Path, embedder: OnnxEmbedder, cluster: Cluster) -> None:
    paths = list_image_files([folder])
    local = run_dedup(paths, embedder, None, dedup_options())
    remote = run_dedup(paths, embedder, None, dedup_options(), cluster=cluster)
    assert np.array_equal(local.scan.vectors, remote.scan.vectors)  # the same onnxruntime batches
    assert np.array_equal(local.scan.crops, remote.scan.crops)
    assert [im.facts for im in local.scan.images] == [im.facts for im in remote.scan.images]
    assert _summary(local) == _summary(remote)
    assert len(local.result.groups) >= 10 and _summary(local)["problems"] == [(folder / "broken.jpg").as_posix()]


def test_the_dedup_command_on_a_cluster_writes_what_a_local_run_writes(
    folder: Path, embedder: OnnxEmbedder, ray_head: str, tmp_path: Path
) -> None:
    common = ["dedup", str(folder), "--no-cache"]
    assert main([*common, "--out", str(tmp_path / "local")]) == 0
    assert main([*common, "--out", str(tmp_path / "ray"), "--executor", "ray", "--address", ray_head]) == 0
    docs = [json.loads((tmp_path / name / "dedup.json").read_text()) for name in ("local", "ray")]
    assert docs[0] == docs[1] and docs[0]["counts"]["removed_near"] >= 10


def _kill_first_shard(seen: list[int], stop: threading.Event) -> None:
    """SIGKILL the first Ray worker seen running ``embed_shard`` (its process title while it works)."""
    while not stop.is_set() and not seen:
        for pid in filter(str.isdigit, os.listdir("/proc")):
            try:
                title = Path(f"/proc/{pid}/cmdline").read_bytes()
            except OSError:
                continue
            if title.startswith(b"ray::embed_shard"):
                os.kill(int(pid), signal.SIGKILL)
                seen.append(int(pid))
                return
        time.sleep(0.002)


def test_a_worker_killed_mid_run_is_retried_and_changes_nothing(
    folder: Path, embedder: OnnxEmbedder, cluster: Cluster, monkeypatch: pytest.MonkeyPatch
) -> None:
    paths = list_image_files([folder])
    local = scan_images(paths, embedder)
    monkeypatch.setattr(embedremote, "SHARD_IMAGES", 4)  # 14 tasks, so the kill lands mid-run
    killed: list[int] = []
    stop = threading.Event()
    killer = threading.Thread(target=_kill_first_shard, args=(killed, stop))
    killer.start()
    try:
        remote = scan_images(paths, embedder, cluster=cluster)
    finally:
        stop.set()
        killer.join()
    assert killed, "no embedding task was seen running"
    assert np.array_equal(local.vectors, remote.vectors) and local.images == remote.images
    assert [p.path for p in local.problems] == [p.path for p in remote.problems]


def test_gpu_shares_are_asked_for_only_where_gpus_exist(cluster: Cluster) -> None:
    assert task_gpus(cluster, "cpu") == 0 and task_gpus(cluster, "auto") == 0  # no GPU on this cluster
    with pytest.raises(ClusterError, match=f"needs {1 / TASKS_PER_GPU:g} GPU"):
        task_gpus(cluster, "cuda")

"""The Ray connection: tasks on a real Ray head (2 workers, loopback) give every item's result with its index,
a task's error is raised here, and wrong arguments are one clear error before anything starts."""

from __future__ import annotations

import json
import socket
import textwrap

import pytest

from ground.run.cluster import Cluster, ClusterError, open_cluster


@pytest.mark.slow
def test_map_gives_every_result_with_its_index(cluster: Cluster) -> None:
    items = [f"word{i} " * (i + 1) for i in range(12)]
    got = dict(cluster.map(textwrap.shorten, iter(items), 20, ahead=3))  # items taken lazily, 3 in flight
    assert got == {i: textwrap.shorten(item, 20) for i, item in enumerate(items)}
    assert cluster.cpus() == 2 and cluster.gpus() == 0


@pytest.mark.slow
def test_a_task_error_is_raised_and_a_gpu_task_that_cannot_be_placed_is_refused(cluster: Cluster) -> None:
    with pytest.raises(json.JSONDecodeError):
        list(cluster.map(json.loads, ["1", "{not json", "2"]))
    with pytest.raises(ClusterError, match="needs 1 GPU.* the Ray cluster has 0"):
        cluster.require_gpus(1, "embedding")


def test_open_cluster_checks_its_arguments_before_starting_anything() -> None:
    assert open_cluster("local") is None
    with pytest.raises(ClusterError, match="unknown executor 'dask'; choose one of local, ray"):
        open_cluster("dask")
    with pytest.raises(ClusterError, match="--address joins a Ray cluster: it needs --executor ray"):
        open_cluster("local", "127.0.0.1:6379")


def test_an_unreachable_address_is_one_line_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]  # nothing listens there
    monkeypatch.setenv("RAY_AUTH_MODE", "token")
    with pytest.raises(ClusterError, match=f"cannot join the Ray cluster at 127.0.0.1:{port}: .*ray status"):
        open_cluster("ray", f"127.0.0.1:{port}")

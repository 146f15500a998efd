"""A Ray connection shared by every command that leaves the machine: ``fuzzyfire dedup|curate`` (decode and
embed), ``synth method1|method2`` (blocks of views), the partitioned near-duplicate search, and the experiment's
runs (:mod:`fuzzyfire.executors`).

:class:`Cluster` joins a running cluster (``address``: ``HOST:6379`` or ``ray://HOST:10001``) or starts a local Ray
that it shuts down on :meth:`Cluster.close`. :meth:`Cluster.map` runs a module-level function over items as Ray
tasks, a bounded number in flight, and yields ``(index, result)`` as they finish; a task whose worker dies is
retried by Ray (``retries``), so a pure function gives the same result as if nothing had happened. Every node
must see the inputs and outputs at the same paths (a shared filesystem) and have fuzzyfire installed.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

EXECUTOR_CHOICES: tuple[str, ...] = ("local", "ray")
RETRIES = 3  # times Ray runs a task again after its worker died (a raised error is not retried)


class ClusterError(ValueError):
    """A cluster that cannot be joined, started or asked for what it lacks."""


class Cluster:
    """A Ray connection: ``address`` joins a running cluster, otherwise a local Ray is started with ``local_cpus``
    CPUs (default: all), no dashboard, and shut down by :meth:`close` (also a context manager)."""

    def __init__(self, address: str | None = None, local_cpus: int | None = None) -> None:
        if address:
            _token_mode()  # before Ray is imported: its core reads the mode once
        try:
            import ray
        except ImportError as exc:  # pragma: no cover - ray is a dependency
            raise ClusterError(f"running on Ray needs the ray package: {exc}") from exc
        self.ray = ray
        if address:
            _join(ray, address)
        else:
            os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
            ray.init(  # "local": a new Ray of our own, even where a `ray start` cluster runs on this machine
                address="local",
                num_cpus=local_cpus,
                include_dashboard=False,
                ignore_reinit_error=True,
                logging_level="ERROR",
            )

    def __enter__(self) -> Cluster:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def resources(self) -> dict[str, float]:
        """The cluster's total resources (``CPU``, ``GPU``, ...)."""
        return {k: float(v) for k, v in self.ray.cluster_resources().items()}

    def cpus(self) -> int:
        return max(1, int(self.resources().get("CPU", 1)))

    def gpus(self) -> float:
        return self.resources().get("GPU", 0.0)

    def require_gpus(self, num_gpus: float, what: str) -> None:
        """Raise :class:`ClusterError` when a task asking for ``num_gpus`` could never be placed."""
        if num_gpus > self.gpus():
            raise ClusterError(
                f"{what} needs {num_gpus:g} GPU(s) per task but the Ray cluster has {self.gpus():g}: no task could "
                "be scheduled"
            )

    def put(self, value: Any) -> Any:
        """``value`` in the object store (an ObjectRef): sent to each node once, not with every task."""
        return self.ray.put(value)

    def map(
        self,
        fn: Callable[..., Any],
        items: Iterable[Any],
        *args: Any,
        num_cpus: float = 1,
        num_gpus: float = 0,
        retries: int = RETRIES,
        ahead: int | None = None,
    ) -> Iterator[tuple[int, Any]]:
        """``fn(item, *args)`` for each item as one Ray task each (items are taken as tasks are submitted), at
        most ``ahead`` in flight (default: twice the cluster's CPUs); yields ``(index into items, result)`` as
        tasks finish. A task's error is raised here
        (the remaining tasks are cancelled); a task whose worker died is run again up to ``retries`` times.
        ``fn`` must be a module-level function (workers import it); ObjectRefs among ``args`` arrive resolved."""
        ray = self.ray
        remote = ray.remote(num_cpus=num_cpus, num_gpus=num_gpus, max_retries=retries)(fn)
        ahead = ahead or 2 * self.cpus()
        pending: dict[Any, int] = {}
        queue = iter(enumerate(items))
        try:
            while True:
                for index, item in queue:
                    pending[remote.remote(item, *args)] = index
                    if len(pending) >= ahead:
                        break
                if not pending:
                    return
                (done,), _ = ray.wait(list(pending), num_returns=1)
                yield pending.pop(done), ray.get(done)
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)

    def close(self) -> None:
        self.ray.shutdown()


def open_cluster(executor: str, address: str | None = None) -> Cluster | None:
    """A :class:`Cluster` for ``executor`` ``ray`` (joining ``address`` or a local Ray), None for ``local``;
    :class:`ClusterError` for an unknown executor or an address given without ``ray``."""
    if executor not in EXECUTOR_CHOICES:
        raise ClusterError(f"unknown executor {executor!r}; choose one of {', '.join(EXECUTOR_CHOICES)}")
    if executor == "local":
        if address:
            raise ClusterError("--address joins a Ray cluster: it needs --executor ray")
        return None
    return Cluster(address)


def _token_mode() -> None:
    """Clusters started by ``ray start --head`` (Ray >= 2.59) check a token, which a client sends only in token
    mode (``RAY_AUTH_MODE=token``; the token comes from ``RAY_AUTH_TOKEN``, ``RAY_AUTH_TOKEN_PATH`` or
    ``~/.ray/auth_token``). Switch token mode on when a token is at hand and the mode is not set (a cluster
    without authentication accepts it too). Ray reads the mode when it is first imported: this must run before."""
    if "RAY_AUTH_MODE" not in os.environ and _token_available() and "ray" not in sys.modules:
        os.environ["RAY_AUTH_MODE"] = "token"


def _join(ray: Any, address: str) -> None:
    """Join the cluster at ``address``; an unreachable or refusing cluster becomes one :class:`ClusterError`
    line instead of Ray's minutes of retries and its traceback."""
    _check_reachable(address)
    try:
        ray.init(address=address, ignore_reinit_error=True, logging_level="ERROR")
    except ConnectionError as exc:
        mode = os.environ.get("RAY_AUTH_MODE", "disabled")
        raise ClusterError(
            f"cannot join the Ray cluster at {address} ({exc}); is it running (ray status)? Clusters with token "
            f"authentication need RAY_AUTH_MODE=token and the cluster's token in RAY_AUTH_TOKEN or ~/.ray/auth_token "
            f"(here: RAY_AUTH_MODE={mode}, token {'found' if _token_available() else 'not found'})"
        ) from None


def _check_reachable(address: str) -> None:
    """Raise :class:`ClusterError` at once when nothing accepts connections at ``address`` (``host:port`` or
    ``ray://host:port``); Ray itself would retry for minutes."""
    import socket

    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        return  # not host:port (e.g. "auto"): Ray resolves it
    try:
        socket.create_connection((host, int(port)), timeout=5).close()
    except OSError as exc:
        raise ClusterError(
            f"cannot join the Ray cluster at {address}: {exc.strerror or exc}; is it running (ray status on the "
            "head)? The address is the head's GCS port (ray start --head --port, default 6379) or ray://HOST:10001"
        ) from None


def _token_available() -> bool:
    path = os.environ.get("RAY_AUTH_TOKEN_PATH") or str(Path.home() / ".ray" / "auth_token")
    return bool(os.environ.get("RAY_AUTH_TOKEN")) or Path(path).is_file()

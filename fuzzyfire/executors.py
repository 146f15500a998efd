"""Executors run the grid's runs: ``local`` (one at a time in this process, every core for each run) or ``ray``
(one Ray task per run with its CPU/GPU needs, on a local Ray or an existing cluster).

Both yield :class:`Outcome` objects as runs finish; a failing run is reported, not fatal, so the others go on.
A run is a pure function of its spec, so the two give identical results for the same seeds. On a cluster,
every node must see the experiment folder and the data at the same paths (a shared filesystem) and have
fuzzyfire installed.
"""

from __future__ import annotations

import os
import sys
import traceback
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any


class ExecutorError(ValueError):
    """An unknown executor name or an executor that cannot start."""


@dataclass(frozen=True)
class Outcome:
    """Run ``index`` of the submitted list: its result, or the error that stopped it."""

    index: int
    result: Any = None
    error: str | None = None


class LocalExecutor:
    """Runs one item at a time in this process (the run itself uses every core it is given)."""

    name = "local"

    def __init__(self, **_: Any) -> None:
        pass

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Outcome]:
        for i, item in enumerate(items):
            try:
                yield Outcome(i, fn(item))
            except Exception as exc:  # one failed run must not stop the grid
                yield Outcome(i, error=_describe(exc))

    def close(self) -> None:
        pass


class RayExecutor:
    """One Ray task per item with ``num_cpus`` / ``num_gpus``; ``address`` joins a running cluster, otherwise a
    local Ray is started with ``local_cpus`` CPUs (default: all) and no dashboard, and shut down by :meth:`close`."""

    name = "ray"

    def __init__(
        self, address: str | None = None, num_cpus: float = 1, num_gpus: float = 0, local_cpus: int | None = None
    ) -> None:
        if address:
            _token_mode()  # before Ray is imported: its core reads the mode once
        try:
            import ray
        except ImportError as exc:  # pragma: no cover - ray is a dependency
            raise ExecutorError(f"the ray executor needs the ray package: {exc}") from exc
        self._ray = ray
        self.num_cpus, self.num_gpus = num_cpus, num_gpus
        if address:
            _join(ray, address)
        else:
            ray.init(num_cpus=local_cpus, include_dashboard=False, ignore_reinit_error=True)
        gpus = float(ray.cluster_resources().get("GPU", 0))
        if num_gpus > gpus:
            ray.shutdown()
            raise ExecutorError(
                f"executor.num_gpus={num_gpus:g} but the Ray cluster has {gpus:g} GPU(s): no run could be scheduled; "
                "set executor.num_gpus=0 to train on CPUs"
            )

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Outcome]:
        ray = self._ray
        remote = ray.remote(num_cpus=self.num_cpus, num_gpus=self.num_gpus, max_retries=0)(fn)
        index = {remote.remote(item): i for i, item in enumerate(items)}
        pending = list(index)
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                try:
                    yield Outcome(index[ref], ray.get(ref))
                except Exception as exc:  # a task's error (RayTaskError) or a lost worker
                    yield Outcome(index[ref], error=_describe(exc))

    def close(self) -> None:
        self._ray.shutdown()


def _token_mode() -> None:
    """Clusters started by ``ray start --head`` (Ray >= 2.59) check a token, which a client sends only in token
    mode (``RAY_AUTH_MODE=token``; the token comes from ``RAY_AUTH_TOKEN``, ``RAY_AUTH_TOKEN_PATH`` or
    ``~/.ray/auth_token``). Switch token mode on when a token is at hand and the mode is not set (a cluster
    without authentication accepts it too). Ray reads the mode when it is first imported: this must run before."""
    if "RAY_AUTH_MODE" not in os.environ and _token_available() and "ray" not in sys.modules:
        os.environ["RAY_AUTH_MODE"] = "token"


def _join(ray: Any, address: str) -> None:
    """Join the cluster at ``address``; an unreachable or refusing cluster becomes one :class:`ExecutorError`
    line instead of Ray's minutes of retries and its traceback."""
    _check_reachable(address)
    try:
        ray.init(address=address, ignore_reinit_error=True, logging_level="ERROR")
    except ConnectionError as exc:
        mode = os.environ.get("RAY_AUTH_MODE", "disabled")
        raise ExecutorError(
            f"cannot join the Ray cluster at {address} ({exc}); is it running (ray status)? Clusters with token "
            f"authentication need RAY_AUTH_MODE=token and the cluster's token in RAY_AUTH_TOKEN or ~/.ray/auth_token "
            f"(here: RAY_AUTH_MODE={mode}, token {'found' if _token_available() else 'not found'})"
        ) from None


def _check_reachable(address: str) -> None:
    """Raise :class:`ExecutorError` at once when nothing accepts connections at ``address`` (``host:port`` or
    ``ray://host:port``); Ray itself would retry for minutes."""
    import socket

    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        return  # not host:port (e.g. "auto"): Ray resolves it
    try:
        socket.create_connection((host, int(port)), timeout=5).close()
    except OSError as exc:
        raise ExecutorError(
            f"cannot join the Ray cluster at {address}: {exc.strerror or exc}; is it running (ray status on the "
            "head)? The address is the head's GCS port (ray start --head --port, default 6379) or ray://HOST:10001"
        ) from None


def _token_available() -> bool:
    path = os.environ.get("RAY_AUTH_TOKEN_PATH") or str(Path.home() / ".ray" / "auth_token")
    return bool(os.environ.get("RAY_AUTH_TOKEN")) or Path(path).is_file()


EXECUTORS: dict[str, type] = {"local": LocalExecutor, "ray": RayExecutor}


def build_executor(name: str, **options: Any) -> LocalExecutor | RayExecutor:
    """The executor called ``name`` (see :data:`EXECUTORS`); raises :class:`ExecutorError` on unknown names."""
    if name not in EXECUTORS:
        raise ExecutorError(f"unknown executor {name!r}; choose one of {', '.join(EXECUTORS)}")
    return EXECUTORS[name](**options)


def _describe(exc: BaseException) -> str:
    last = traceback.format_exception_only(type(exc), exc)[-1].strip()
    return last if len(last) < 2000 else last[:2000] + " ..."

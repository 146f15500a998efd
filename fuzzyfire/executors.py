"""Executors run the grid's runs: ``local`` (one at a time in this process, every core for each run) or ``ray``
(one Ray task per run with its CPU/GPU needs, on a local Ray or an existing cluster: :mod:`ground.run.cluster`).

Both yield :class:`Outcome` objects as runs finish; a failing run is reported, not fatal, so the others go on.
A run is a pure function of its spec, so the two give identical results for the same seeds. On a cluster,
every node must see the experiment folder and the data at the same paths (a shared filesystem) and have
fuzzyfire installed.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from ground.run.cluster import Cluster, ClusterError

#: An unknown executor name or an executor that cannot start: the error of every Ray connection problem.
ExecutorError = ClusterError


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
    """One Ray task per item with ``num_cpus`` / ``num_gpus`` on a :class:`ground.run.cluster.Cluster`:
    ``address`` joins a running cluster, otherwise a local Ray is started with ``local_cpus`` CPUs (default: all)
    and shut down by :meth:`close`."""

    name = "ray"

    def __init__(
        self, address: str | None = None, num_cpus: float = 1, num_gpus: float = 0, local_cpus: int | None = None
    ) -> None:
        self.cluster = Cluster(address, local_cpus)
        self.num_cpus, self.num_gpus = num_cpus, num_gpus
        gpus = self.cluster.gpus()
        if num_gpus > gpus:
            self.cluster.close()
            raise ExecutorError(
                f"executor.num_gpus={num_gpus:g} but the Ray cluster has {gpus:g} GPU(s): no run could be scheduled; "
                "set executor.num_gpus=0 to train on CPUs"
            )

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Outcome]:
        ray = self.cluster.ray
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
        self.cluster.close()


EXECUTORS: dict[str, type] = {"local": LocalExecutor, "ray": RayExecutor}


def build_executor(name: str, **options: Any) -> LocalExecutor | RayExecutor:
    """The executor called ``name`` (see :data:`EXECUTORS`); raises :class:`ExecutorError` on unknown names."""
    if name not in EXECUTORS:
        raise ExecutorError(f"unknown executor {name!r}; choose one of {', '.join(EXECUTORS)}")
    return EXECUTORS[name](**options)


def _describe(exc: BaseException) -> str:
    last = traceback.format_exception_only(type(exc), exc)[-1].strip()
    return last if len(last) < 2000 else last[:2000] + " ..."

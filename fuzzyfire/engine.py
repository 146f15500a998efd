"""External trainers in the grid: ``engine: {name: command, ...}`` trains each run with a program of the user's
(ultralytics' ``yolo``, YOLOv5's ``train.py``, anything that writes an ONNX detector), whose model is then scored
by our scorer exactly like our own runs.

Templates are split like a shell would (``shlex``) but run without a shell, in the run folder, one after the
other: ``train`` then ``export`` (optional). Placeholders: ``{data_yaml}`` (the mixture's ultralytics
``data.yaml``), ``{mixture_dir}``, ``{epochs}``, ``{imgsz}``, ``{batch}``, ``{seed}``, ``{device}`` (``cpu`` or
a CUDA index as ultralytics wants it), ``{workers}``, ``{run_dir}`` (the run folder) and ``{python}`` (this
interpreter). Both commands' output goes to ``train/command.log`` in the run folder. A command that fails or
writes no ONNX fails its run with the log's last lines; the grid goes on. ``train/command.json`` records the
commands once they succeeded, so a resumed grid scores a finished run without training it again.
"""

from __future__ import annotations

import json
import os
import shlex
import string
import subprocess
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    from train.config import TrainConfig

PLACEHOLDERS = (
    "data_yaml",
    "mixture_dir",
    "epochs",
    "imgsz",
    "batch",
    "seed",
    "device",
    "workers",
    "run_dir",
    "python",
)
LOG_TAIL = 20  # log lines quoted when a command fails


class EngineError(ValueError):
    """An engine config that cannot work (unknown name, missing template, unknown placeholder)."""


class CommandError(RuntimeError):
    """An engine command that failed or left no ONNX (the run folder, the command and its log's tail)."""


@dataclass(frozen=True)
class EngineConfig:
    """Who trains each run: ``fuzzyfire`` (our detector, the ``train:`` section) or ``command`` (module
    docstring; ``train.epochs``, ``imgsz``, ``batch`` and ``device`` fill the placeholders)."""

    name: Literal["fuzzyfire", "command"] = "fuzzyfire"  # fuzzyfire (our detector) | command (e.g. ultralytics)
    train: str = ""  # command template that trains, e.g. "yolo detect train data={data_yaml} ..."
    export: str = ""  # command template that exports the ONNX (empty when train writes it)
    onnx: str = "train/weights/best.onnx"  # the ONNX the commands leave, relative to the run folder (a template)
    env: dict[str, str] = field(default_factory=dict)  # extra environment variables for the commands

    def check(self) -> None:
        """Raise :class:`EngineError` unless the templates can be filled."""
        if self.name not in ("fuzzyfire", "command"):
            raise EngineError(f"engine.name {self.name!r}: choose fuzzyfire or command")
        if self.name == "fuzzyfire":
            return
        if not self.train.strip():
            raise EngineError("engine.name is command but engine.train (the training command template) is empty")
        for key in ("train", "export", "onnx"):
            unknown = [f for _, f, _, _ in string.Formatter().parse(getattr(self, key)) if f and f not in PLACEHOLDERS]
            if unknown:
                raise EngineError(
                    f"engine.{key}: unknown placeholder {{{unknown[0]}}}; known: "
                    + ", ".join(f"{{{p}}}" for p in PLACEHOLDERS)
                )


@dataclass(frozen=True)
class CommandJob:
    """What one run asks of the engine: ``train`` the run's resolved train config (its seed, threads, device),
    ``data`` the mixture folder, ``out`` the run folder, ``key`` the run's identity hash (a finished job is
    recognised by it)."""

    train: TrainConfig
    data: Path
    out: Path
    key: str


def values(job: CommandJob) -> dict[str, str]:
    """The placeholder values of a run (module docstring)."""
    t = job.train
    cuda = t.device.startswith("cuda")
    return {
        "data_yaml": str(job.data / "data.yaml"),
        "mixture_dir": str(job.data),
        "epochs": str(t.epochs),
        "imgsz": str(t.imgsz),
        "batch": str(t.batch),
        "seed": str(t.seed),
        "device": (t.device.partition(":")[2] or "0") if cuda else ("cpu" if t.device == "cpu" else ""),
        "workers": str(max(1, t.threads)),
        "run_dir": str(job.out),
        "python": sys.executable,
    }


def command_train(job: CommandJob, engine: EngineConfig) -> Path:
    """Run the engine's commands for ``job`` (or find their finished output); returns the ONNX path.
    Raises :class:`CommandError` naming the failed command with the tail of its log."""
    filled = values(job)
    steps = [(k, _argv(getattr(engine, k), filled)) for k in ("train", "export") if getattr(engine, k).strip()]
    onnx = job.out / engine.onnx.format(**filled)
    folder = job.out / "train"
    folder.mkdir(parents=True, exist_ok=True)
    record = {"hash": job.key, "commands": [argv for _, argv in steps]}
    done = folder / "command.json"
    if done.is_file() and json.loads(done.read_text(encoding="utf-8")) == record and onnx.is_file():
        return onnx
    log = folder / "command.log"
    env = {**os.environ, **engine.env}
    with log.open("w", encoding="utf-8") as out:
        for step, argv in steps:
            out.write(f"$ {shlex.join(argv)}\n")
            out.flush()
            try:
                code = subprocess.run(argv, cwd=job.out, stdout=out, stderr=subprocess.STDOUT, env=env).returncode
            except OSError as exc:
                raise CommandError(f"{job.out}: engine.{step} command {argv[0]!r} cannot start: {exc}") from None
            if code != 0:
                raise CommandError(f"{job.out}: engine.{step} command exited with {code}:\n{_tail(log)}")
    if not onnx.is_file():
        raise CommandError(f"{job.out}: the engine's commands left no ONNX at {onnx} (engine.onnx):\n{_tail(log)}")
    done.write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    return onnx


def _argv(template: str, filled: Mapping[str, Any]) -> list[str]:
    """``template`` split like a shell would, each word filled (a path with spaces stays one argument)."""
    return [word.format(**filled) for word in shlex.split(template)]


def _tail(log: Path) -> str:
    lines = log.read_text(encoding="utf-8", errors="replace").splitlines()
    return "\n".join(f"  | {line}" for line in lines[-LOG_TAIL:])

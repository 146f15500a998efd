"""The ``fuzzyfire`` console script: subcommands gathered from each package's ``cli.register``, and
``fuzzyfire experiment CONFIG``: the whole study (curate -> synth -> mix -> train -> score -> report)."""

from __future__ import annotations

import argparse
import errno
import importlib
import sys
from collections.abc import Sequence
from pathlib import Path

from fuzzyfire import __version__
from ground.cli.commands import HelpFormatter, add_command
from ground.cli.options import Alias, add_settings
from ground.data.writer import OutputError

#: Modules whose ``register(subparsers)`` adds commands, in help order (imported when the parser is built);
#: ``experiment``, this module's own, comes last.
COMMAND_MODULES: tuple[str, ...] = ("curate.cli", "synth.cli", "train.cli", "eval.cli")


_DESCRIPTION = """Run the study of a YAML config: curate the real data (optional), generate the Method 1 and
Method 2 pools, draw the R(m)_S(n) mixtures, train every mixture x seed, score each run on the common, the
rare and the named test sets (tests:; a set without labels gets its false alarms per 100 images), and write
tables (Markdown, CSV, LaTeX), Figure 5 and report.html. With grid.control each real + synthetic mixture is
also trained on flame-free copies of its own real images instead of its synthetic ones and compared with them.
Stages are cached by a hash of their config and every run writes results.json last: run the same command again
to resume (a test set added later is scored on the finished runs without training them again; --report-only
lists what is not scored yet).

example:
  fuzzyfire experiment configs/demo.yaml --out out/demo
  fuzzyfire experiment configs/shared-data.yaml --out out/shared --set grid.seeds=[0,1,2]
  fuzzyfire experiment configs/shared-data.yaml --out out/shared --report-only   # tables so far
  fuzzyfire experiment configs/demo.yaml --out out/demo --set grid.control=true   # + the control runs
  fuzzyfire experiment configs/shared-data.yaml --out out/shared --set tests.mine.path=/data/my-photos
  fuzzyfire experiment configs/paper.yaml --out /shared/study --executor ray --address ray://head:10001 \\
      --set real.path=/data/fiiw --set rare.path=/data/rare

configs/demo.yaml needs no data: its 'real' and 'rare' sets are generated stand-ins (labelled so everywhere)."""


def cmd_experiment(args: argparse.Namespace) -> int:
    from fuzzyfire.aggregate import STANDIN_NOTICE, answer_text, table_text
    from fuzzyfire.executors import ExecutorError, build_executor
    from fuzzyfire.experiment import run_experiment
    from fuzzyfire.experiment_config import ExperimentConfig, ExperimentConfigError
    from ground.cli.options import command_config
    from ground.config.loader import ConfigError, located

    try:
        cfg = command_config(args, ExperimentConfig, ALIASES)
        if cfg is None:
            return 0
        cfg.resolved(Path(args.config).resolve().parent)  # every check, the holdout shares' too, named by the file
        if cfg.executor.address and cfg.executor.name != "ray":
            raise ExperimentConfigError("--address (executor.address) needs --executor ray")
        e = cfg.executor
        options = {"address": e.address, "num_cpus": e.num_cpus, "num_gpus": e.num_gpus, "local_cpus": e.local_cpus}
        executor = None if args.report_only else build_executor(e.name, **(options if e.name == "ray" else {}))
    except (ConfigError, ExperimentConfigError, ExecutorError) as exc:
        print(f"error: {located(args.config, str(exc))}", file=sys.stderr)
        return 2
    out = args.out or Path("out") / Path(args.config).stem
    try:
        result = run_experiment(cfg, Path(args.config).resolve().parent, out, executor)
    finally:
        if executor is not None:
            executor.close()
    print(table_text(out.resolve()))
    print(answer_text(out.resolve()))
    if result.standin:
        print(STANDIN_NOTICE)
    if args.report_only:
        print(f"{len(result.failed)} runs not finished yet", file=sys.stderr)
    else:
        for spec in result.failed:
            print(f"error: run {spec.label} seed {spec.seed} failed (see above); rerun to retry", file=sys.stderr)
    print(f"report: {result.report}")
    return 1 if result.failed and not args.report_only else 0


#: Flags of ``fuzzyfire experiment``: aliases of ExperimentConfig keys.
ALIASES: tuple[Alias, ...] = (
    Alias("--executor", ("executor.name",), "where runs train: local (one at a time here) | ray (a task each)"),
    Alias("--address", ("executor.address",), "ray: a running cluster, e.g. ray://head:10001 (null: a local Ray)"),
)  # fmt: skip


def _experiment_config() -> type:
    from fuzzyfire.experiment_config import ExperimentConfig

    return ExperimentConfig


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``experiment`` to the ``fuzzyfire`` parser."""
    p = add_command(
        sub,
        "experiment",
        help="the whole study: curate, synth, mix, train each mixture x seed, score, tables and report",
        description=_DESCRIPTION,
    )
    add_settings(p, _experiment_config, ALIASES, cmd_experiment, required=True)
    p.add_argument("--out", type=Path, help="experiment folder (default: out/<config name>); rerun to resume")
    p.add_argument(
        "--report-only",
        action="store_true",
        help="train nothing: tables and report from the runs finished so far (e.g. while a cluster works)",
    )


def build_parser() -> argparse.ArgumentParser:

    parser = argparse.ArgumentParser(
        prog="fuzzyfire",
        formatter_class=HelpFormatter,
        description="Build and judge detectors of fuzzy objects (fire, smoke) from real and synthetic images.\n\n"
        "example:\n  fuzzyfire convert ../shared/data/fire-smoke-608 --to coco --out out/fs608\n"
        "  fuzzyfire validate out/fs608",
    )
    parser.add_argument("--version", action="version", version=f"fuzzyfire {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args))
    except (FileNotFoundError, FileExistsError, NotADirectoryError, PermissionError, ValueError, OutputError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (RuntimeError, OSError) as exc:
        if not link_loop(exc):
            raise
        print(f"error: {exc}: a symbolic link on that path leads back to itself; mend or remove it", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def link_loop(exc: BaseException) -> bool:
    """Whether ``exc`` is a path that cannot be resolved for a symbolic link loop: ``Path.resolve`` raises
    ``RuntimeError('Symlink loop from ...')`` up to Python 3.12 and ``OSError`` with ``ELOOP`` from 3.13 on."""
    if isinstance(exc, OSError):
        return exc.errno == errno.ELOOP
    return isinstance(exc, RuntimeError) and str(exc).startswith("Symlink loop")


if __name__ == "__main__":
    sys.exit(main())

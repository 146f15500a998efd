"""curate's ``fuzzyfire`` commands, one module per group: :mod:`~curate.cli.dataset` (convert, validate, stats,
merge), :mod:`~curate.cli.mix` (mix), :mod:`~curate.cli.dedup` (dedup, leakage) and :mod:`~curate.cli.curate`
(curate). Each ``cmd_*`` returns an exit code; the helpers every package's commands share are in
:mod:`ground.cli.commands`."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add curate's commands to the ``fuzzyfire`` parser, in help order: the dataset commands, the mixer,
    deduplication and curation."""
    from curate.cli import curate, dataset, dedup, mix

    for module in (dataset, mix, dedup, curate):
        module.register(sub)

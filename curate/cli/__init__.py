"""curate's ``fuzzyfire`` commands, one module per group: :mod:`~curate.cli.dataset` (convert, validate, stats,
merge), :mod:`~curate.cli.mix` (mix), :mod:`~curate.cli.dedup` (dedup, leakage) and :mod:`~curate.cli.curate`
(curate). Each ``cmd_*`` returns an exit code; the helpers every package's commands share are in
:mod:`curate.core.commands`."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``convert``, ``validate``, ``stats``, ``mix``, ``dedup`` and ``leakage`` to the ``fuzzyfire`` parser,
    in help order. ``curate`` and ``merge`` come later in ``fuzzyfire --help`` (after eval's commands and after
    ``experiment``): :func:`fuzzyfire.cli.register` adds them with :func:`curate.cli.curate.register` and
    :func:`curate.cli.dataset.register_merge`."""
    from curate.cli import dataset, dedup, mix

    dataset.register(sub)
    mix.register(sub)
    dedup.register(sub)

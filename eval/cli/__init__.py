"""eval's ``fuzzyfire`` commands, one module each: :mod:`~eval.cli.score` (score), :mod:`~eval.cli.compare`
(compare) and :mod:`~eval.cli.predict` (predict); what they share (the model, inference and test-set flags, and
what those build) is :mod:`~eval.cli.options`. Each ``cmd_*`` returns an exit code."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add eval's commands to the ``fuzzyfire`` parser, in help order: score, compare, predict."""
    from eval.cli import compare, predict, score

    for module in (score, compare, predict):
        module.register(sub)

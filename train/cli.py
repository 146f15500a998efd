"""``fuzzyfire`` subcommands of the train package (registered by ``fuzzyfire.cli``)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add this package's commands to the ``fuzzyfire`` parser (none yet)."""

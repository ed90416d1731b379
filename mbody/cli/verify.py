"""Placeholder: the commands of this group are being written."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add this group's commands (none yet)."""

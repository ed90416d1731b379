"""Sub-commands of `mbody`, one module per group; each module has `register(sub)`.

A command handler takes the parsed namespace and returns an exit code; it raises
`MbodyError` (or a subclass) for bad input, which `mbody.cli.main` turns into one
paragraph on stderr and a non-zero exit code.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from mbody.errors import MbodyError

EXIT_OK, EXIT_UNMET, EXIT_INPUT, EXIT_INTERNAL = 0, 1, 2, 70


def load_model(path: str, *, warn: bool = True):
    """The validated model at `path`; its warnings (e.g. a quaternion that was normalised)
    go to stderr, so that a questionable input never passes unseen. The file size limit
    is the command's ``--max-bytes`` (set around the command by `mbody.cli.app.main`)."""
    import sys

    from mbody.model.model import load

    model = load(path)
    if warn:
        for w in model.warnings:
            sys.stderr.write(f"mbody: warning: {w}\n")
    return model


_UNITS = {"": 1, "k": 2**10, "m": 2**20, "g": 2**30}


def byte_size(text: str) -> int:
    """``--max-bytes`` values: bytes, or with a binary unit (``200M``, ``1.5G``, ``64k``)."""
    import argparse
    import re

    m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([kKmMgG]?)(?:i?B)?\s*", text)
    if not m:
        raise argparse.ArgumentTypeError(f"expected a size in bytes such as 100000000 or "
                                         f"200M, got {text!r}")
    size = int(float(m.group(1)) * _UNITS[m.group(2).lower()])
    if size < 1:
        raise argparse.ArgumentTypeError(f"expected a size of at least 1 byte, got {text!r}")
    return size


def regular_file(path: str, what: str) -> None:
    """Refuse, before anything opens it, a `path` that exists but is not a regular file: a
    named pipe without a writer would block numpy's open() forever, a device never end."""
    import os
    import stat

    try:
        mode = os.stat(path).st_mode
    except OSError:
        return  # missing or unreadable: the reader says so
    if not stat.S_ISREG(mode):
        kind = ("a directory" if stat.S_ISDIR(mode) else "a named pipe" if stat.S_ISFIFO(mode)
                else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "not a file")
        raise MbodyError(f"{path}: this is {kind}, not a file; expected {what}")


def parse_known(pairs: Sequence[str]) -> dict[str, float]:
    """``["A.Fx=3", ...]`` -> ``{"A.Fx": 3.0}`` (labels are checked later, with hints)."""
    out = {}
    for p in pairs:
        label, sep, value = p.partition("=")
        if not sep:
            raise MbodyError(f"--known expects LABEL=VALUE (for example A.Fx=3), got {p!r}")
        try:
            x = float(value)
        except ValueError:
            raise MbodyError(f"--known {label}: {value!r} is not a number") from None
        if not math.isfinite(x):
            raise MbodyError(f"--known {label}: expected a finite number, got {value!r}")
        out[label.strip()] = x
    return out

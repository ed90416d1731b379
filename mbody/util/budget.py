"""The byte budget of what mbody reads: the most bytes a file may hold before it is
refused unread, so that a mistaken path (a log, a disk image) or a hostile archive (a
member that inflates a thousandfold) cannot take the machine's memory.

Each kind of file has its default:

- `MAX_BYTES` (32 MiB), a model file's text (YAML, MJCF and its includes, URDF);
- `DATA_BYTES` (1 GiB), the arrays of a run file or an npz/.mat export once inflated;
- `TEXT_BYTES` (32 MiB), a JSON or CSV export's text.

One setting raises (or lowers) them all: a reader's own ``max_bytes=N`` (`mbody.load`,
`mbody.Trajectory.load`, `mbody.load_export`) wins; else the budget set around a block by
`byte_budget` (the command line's ``--max-bytes N`` around a command, so that every file
the command reads, a model or the model inside a run file, gets the same one); else the
kind's default (`byte_limit`).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

MAX_BYTES = 32 * 1024 * 1024
"""Largest model file read by default, in bytes (a 10 000-body model written by
``yaml.dump`` is about 8 MB). ``mbody.load(path, max_bytes=N)`` or ``--max-bytes N`` on
the command line reads larger models."""
DATA_BYTES = 1 << 30
"""Most bytes of arrays a run or npz/.mat export may hold once inflated, read by default
(1 GiB: a run of 100 spatial bodies over 70 000 samples, with their reactions);
``--max-bytes N`` on the command line, or ``max_bytes=N`` to the reader
(`mbody.Trajectory.load`, `mbody.load_export`), reads more."""
TEXT_BYTES = MAX_BYTES
"""Largest JSON or CSV export read by default, in bytes of text: a model file's limit,
since a value read from text takes up to tens of times its characters in memory."""

_GIVEN: ContextVar[int | None] = ContextVar("mbody_max_bytes", default=None)
"""The budget `byte_budget` set around the current block, or None (each kind's default)."""


@contextmanager
def byte_budget(max_bytes: int | None) -> Iterator[None]:
    """Within the block, every file is read up to `max_bytes` (a data file's arrays once
    inflated) unless a call says otherwise; the command line's ``--max-bytes`` sets it
    around a command.

    Parameters
    ----------
    max_bytes : int or None
        The budget, in bytes; None keeps the current one.
    """
    token = _GIVEN.set(int(max_bytes)) if max_bytes is not None else None
    try:
        yield
    finally:
        if token is not None:
            _GIVEN.reset(token)


def byte_limit(max_bytes: int | None, default: int) -> int:
    """The budget of one read: `max_bytes` if given (the call's own), else the one
    `byte_budget` set around it, else `default` (the kind's: `MAX_BYTES`, `DATA_BYTES`
    or `TEXT_BYTES`)."""
    if max_bytes is not None:
        return int(max_bytes)
    given = _GIVEN.get()
    return default if given is None else given

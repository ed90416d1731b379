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

import numbers
import operator
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

from mbody.errors import MbodyError, wrong_type

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
    size = checked_max_bytes(max_bytes)
    token = _GIVEN.set(size) if size is not None else None
    try:
        yield
    finally:
        if token is not None:
            _GIVEN.reset(token)


def byte_limit(max_bytes: int | None, default: int) -> int:
    """The budget of one read: `max_bytes` if given (the call's own), else the one
    `byte_budget` set around it, else `default` (the kind's: `MAX_BYTES`, `DATA_BYTES`
    or `TEXT_BYTES`)."""
    size = checked_max_bytes(max_bytes)
    if size is not None:
        return size
    given = _GIVEN.get()
    return default if given is None else given


def checked_max_bytes(max_bytes: object, argument: str = "max_bytes") -> int | None:
    """A reader's `max_bytes` as the byte count it names, checked where it comes in: the
    one check of every reader's budget argument (`mbody.load`, `mbody.Trajectory.load`,
    `mbody.load_export`, `read_generalized`, and `byte_limit` under them all).

    A whole number of bytes, at least 1: an int (a numpy integer too), or a float with
    no fraction (``2.0 ** 30``). A bool is refused (an int to Python, not a size to
    anyone), as are a fraction of a byte and a size with a unit (``'1G'`` is the command
    line's ``--max-bytes``; in Python, ``2**30``).

    Returns
    -------
    int or None
        The budget in bytes; None when `max_bytes` is None (the current budget).

    Raises
    ------
    MbodyTypeError
        Not a whole number (the argument named, what was given, what is expected).
    MbodyError
        Below 1 byte.
    """
    if max_bytes is None:
        return None
    size: int | None = None
    if isinstance(max_bytes, bool):
        pass
    elif isinstance(max_bytes, numbers.Integral):
        size = operator.index(max_bytes)
    elif isinstance(max_bytes, numbers.Real) and float(max_bytes).is_integer():
        size = int(float(max_bytes))
    if size is None:
        hint = ("a size with a unit is the command line's --max-bytes; in Python, write "
                "2**30 for 1 GiB" if isinstance(max_bytes, str) else "")
        raise wrong_type(argument, "a whole number of bytes (such as 200 * 2**20)",
                         max_bytes, hint)
    if size < 1:
        raise MbodyError(f"{argument}: expected a size of at least 1 byte, got {max_bytes!r}")
    return size

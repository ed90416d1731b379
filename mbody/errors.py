"""Errors for bad input: every problem carries its file, line and column.

A `ModelError` holds every `Issue` found in one file so that a user fixes them all
in one pass, the way a compiler reports all errors rather than the first.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Issue:
    """One problem in a model file, located.

    Parameters
    ----------
    file : str
        The model file's path as given (``<dict>`` or ``<string>`` when not from a file).
    line, column : int
        1-based position, as editors show them; 0 when unknown.
    key : str
        Dotted path to the offending entry, e.g. ``bodies[2].inertia``.
    message : str
        What is wrong and what was expected.
    hint : str, optional
        A did-you-mean or a way to fix it.
    """

    file: str
    line: int
    column: int
    key: str
    message: str
    hint: str = ""

    def __str__(self) -> str:
        where = self.file or "<model>"
        if self.line:
            where += f":{self.line}:{self.column}"
        text = f"{where}: {self.key + ': ' if self.key else ''}{self.message}"
        if self.hint:
            text += f" ({self.hint})"
        return text


class MbodyError(Exception):
    """Base class of every error mbody raises on purpose (bad input, bad request)."""


class ModelError(MbodyError):
    """A model file (or model dictionary) is invalid; `issues` lists every problem.

    Parameters
    ----------
    issues : sequence of Issue
        Every problem found in the file, in file order.
    """

    def __init__(self, issues: Sequence[Issue]):
        self.issues = list(issues)
        super().__init__(self._text())

    SHOWN = 50
    """Most issues written out in the message; `issues` always holds every one."""

    def _text(self) -> str:
        n = len(self.issues)
        head = f"{n} problem{'s' if n != 1 else ''} in the model:" if n > 1 else ""
        body = "\n".join(str(i) for i in self.issues[:self.SHOWN])
        if n > self.SHOWN:
            body += f"\n... and {n - self.SHOWN} more (fix these first; often they repeat)"
        return f"{head}\n{body}" if head else body


class UnknownReactionsError(MbodyError):
    """Accelerations were asked for while some reaction components are still unknown.

    Parameters
    ----------
    unknown : sequence of str
        The labels of the unknown reaction components (``A.Fx``...).
    """

    def __init__(self, unknown: Sequence[str]):
        self.unknown = list(unknown)
        shown = ", ".join(self.unknown[:20]) + (" ..." if len(self.unknown) > 20 else "")
        super().__init__(
            f"{len(self.unknown)} reaction component(s) are unknown: {shown}. "
            "Give their values (in the file under 'reactions:', with --known LABEL=VALUE, "
            "or solve(known={...})) to get the accelerations."
        )


class OutputError(MbodyError, OSError):
    """An output could not be written (a full disk, a quota, a file-size limit, an I/O
    error): one message for the command line, and still an `OSError` (with the cause's
    errno and strerror, and the target as filename) for code that catches those."""

    def __init__(self, message: str, cause: OSError | None = None, filename=None):
        super().__init__(message)
        if cause is not None:
            self.errno, self.strerror = cause.errno, cause.strerror
        self.filename = filename

    def __str__(self) -> str:
        return str(self.args[0])


class TrajectoryFileError(MbodyError):
    """A trajectory file is unreadable, truncated or of the wrong kind."""


def given_twice(flag: str, name: str) -> MbodyError:
    """A repeatable NAME=VALUE option given twice for one name (``--known O.Fx=3 --known
    O.Fx=4``): which value was meant is a guess, so every command refuses it, in these
    words (``--set``, ``--known``, ``--q``, ``--qd``, ``kinematics --point``, ``sweep
    --set``)."""
    return MbodyError(f"{flag} {name} is given twice")


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """A 'did you mean ...?' hint for a misspelt name, or '' when nothing is close (a
    name that differs only in case is the closest: 'dop853' for 'DOP853')."""
    close = closest(word, choices)
    return f"did you mean '{close}'?" if close is not None else ""


def closest(word: str, choices: Iterable[str]) -> str | None:
    """The choice `word` was probably meant to be (`did_you_mean`'s), or None."""
    names = [str(c) for c in choices]
    same = [c for c in names if c.casefold() == str(word).casefold()]
    close = same or difflib.get_close_matches(str(word), names, n=1, cutoff=0.6)
    return close[0] if close else None

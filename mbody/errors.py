"""Errors for bad input: every problem carries its file, line and column.

A `ModelError` holds every `Issue` found in one file so that a user fixes them all
in one pass, the way a compiler reports all errors rather than the first.
"""

from __future__ import annotations

import contextlib
import difflib
import numbers
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
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


class MbodyTypeError(MbodyError, TypeError):
    """An argument of the wrong type (a dict where a `State` is expected, text where a
    number is): the message names the argument and what it takes. An `MbodyError`, so
    that one ``except`` catches every refusal of mbody's, and a `TypeError`, as Python
    reports a wrong type."""


class TrajectoryFileError(MbodyError):
    """A trajectory file is unreadable, truncated or of the wrong kind."""


def wrong_type(argument: str, expected: str, got: object, hint: str = "") -> MbodyTypeError:
    """The `MbodyTypeError` "<argument> must be <expected>, got <what got is>[; <hint>]".

    Parameters
    ----------
    argument : str
        The argument's name as the caller wrote it (``source``, ``values[2]``).
    expected : str
        What it accepts, in words.
    got : object
        What was given: its type is named (a short string or number is shown too).
    hint : str, optional
        How to get what was meant.
    """
    return MbodyTypeError(f"{argument} must be {expected}, got {_what(got)}"
                          + (f"; {hint}" if hint else ""))


def _what(value: object) -> str:
    if value is None:
        return "None"
    kind = type(value).__name__
    if isinstance(value, str):
        return f"str {value!r}" if len(value) <= 40 else f"a str of {len(value)} characters"
    if isinstance(value, bool | numbers.Number) and len(repr(value)) <= 40:
        return f"{kind} {value!r}"
    return kind


def real_number(value: object, argument: str, expected: str = "a number") -> float:
    """`value` as a float when it is a real number (an int, a float, a numpy scalar; not a
    bool, nor a number written as a string), else `wrong_type`'s error naming `argument`
    (the range is the caller's to check)."""
    if type(value) is float or type(value) is int:  # the usual: no ABC check (~0.3 us)
        return float(value)
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    hint = ""
    if isinstance(value, str):
        with contextlib.suppress(ValueError):
            hint = f"write it as a number: {float(value)!r}"
    raise wrong_type(argument, expected, value, hint)


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


CLOSE_CUTOFF = 0.6
"""difflib's similarity a did-you-mean needs (its default)."""


def closest(word: str, choices: Iterable[str]) -> str | None:
    """The choice `word` was probably meant to be (`did_you_mean`'s), or None."""
    word = str(word)
    names = [str(c) for c in choices]
    folded = word.casefold()
    same = [c for c in names if c.casefold() == folded]
    if same:
        return same[0]
    # the choices whose lengths alone allow the similarity (difflib's real_quick_ratio,
    # its first test, in its own arithmetic): the same answer, without difflib's per-choice
    # work on the others (a large model's names are thousands)
    n = len(word)
    names = [c for c in names if 2.0 * min(n, len(c)) / (n + len(c)) >= CLOSE_CUTOFF]
    close = difflib.get_close_matches(word, names, n=1, cutoff=CLOSE_CUTOFF)
    return close[0] if close else None


_FLAGS: ContextVar[Mapping[str, str] | None] = ContextVar("mbody_option_flags", default=None)


@contextmanager
def options_named(flags: Mapping[str, str]) -> Iterator[None]:
    """Within the block, messages name an option by the command-line flag it was typed
    as: `flags` maps a keyword argument (``joint_positions``) to its flag (``--q``). The
    command line sets it around every command."""
    token = _FLAGS.set(flags)
    try:
        yield
    finally:
        _FLAGS.reset(token)


def option_name(keyword: str, value: str = "") -> str:
    """How a message names the option `keyword` (set to `value`, when that is what it
    advises): its flag on the command line (`options_named`: ``--floating-base``), else
    the keyword argument of the call (``floating_base=True``)."""
    flag = (_FLAGS.get() or {}).get(keyword)
    if flag is not None:
        return flag
    return f"{keyword}={value}" if value else keyword

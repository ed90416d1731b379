"""Errors for bad input: every problem carries its file, line and column.

A `ModelError` holds every `Issue` found in one file so that a user fixes them all
in one pass, the way a compiler reports all errors rather than the first.
"""

from __future__ import annotations

import contextlib
import difflib
import numbers
import re
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


AT_LEAST_ONE_SAMPLE = "a run holds at least one sample"
"""Why a trajectory without samples is refused (`Trajectory.need_samples`, and reading a
run file: `mbody.simulate.run_file`)."""


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


def given_twice(entry: str, how: str = "") -> MbodyError:
    """A repeatable NAME=VALUE option given twice for one name (``--known O.Fx=3 --known
    O.Fx=4``): which value was meant is a guess, so every command refuses it, in these
    words (``--set``, ``--known``, ``--q``, ``--qd``, ``kinematics --point``, ``sweep
    --set``; from Python, `mbody.run_sweep`'s values, whose mapping's keys name one path
    once the spaces around them are dropped). `entry` is the option and its name as the
    caller gives them (``--known O.Fx``; `option_entry`: ``values['bodies.rod.mass']``
    from Python); `how`, when given, says how it was given twice."""
    return MbodyError(f"{entry} is given twice" + (f" ({how})" if how else ""))


SYNONYMS: Mapping[str, tuple[str, str]] = {
    "omega": ("angular_velocity", ""), "w": ("angular_velocity", ""),
    "v": ("velocity", ""), "pos": ("position", ""), "theta": ("angle", ""),
    "point": ("at", ""), "location": ("at", ""), "position": ("at", ""),
    "I": ("inertia", ""), "I_G": ("inertia", ""), "J": ("inertia", ""),
    "moment_of_inertia": ("inertia", ""), "m": ("mass", ""),
    "moment": ("torque", "a couple, a pure moment"),
    "couple": ("torque", "a couple, a pure moment"),
    "k": ("stiffness", ""), "spring_constant": ("stiffness", ""), "c": ("damping", ""),
    "free_length": ("rest_length", ""), "L0": ("rest_length", ""),
    "quat": ("quaternion", ""), "g": ("gravity", ""),
    "name": ("model", "the model's name"),
}
"""Words a textbook or another program uses for what mbody names otherwise: word ->
(mbody's name, a note). A hint names mbody's word only where it is one of the choices
(`did_you_mean`): ``position`` on a load means its ``at``, on a body it is the key."""


def did_you_mean(word: str, choices: Iterable[str],
                 synonyms: Mapping[str, str] | None = None) -> str:
    """A hint for a name that is not one of `choices`, or '' when nothing is close.

    A word mbody calls otherwise (`SYNONYMS`, or `synonyms`: another program's names,
    such as a joint type's aliases) gets "mbody calls it '...'"; a misspelt one "did you
    mean '...'?" (a name that differs only in case is the closest: 'dop853' for
    'DOP853'), unless every choice is far from it (`closest`)."""
    names = [str(c) for c in choices]
    meant = synonym(word, names, synonyms)
    if meant is not None:
        return meant
    close = closest(word, names)
    return f"did you mean '{close}'?" if close is not None else ""


def synonym(word: str, choices: Sequence[str], synonyms: Mapping[str, str] | None = None
            ) -> str | None:
    """"mbody calls it '...'" when `word` is another name of one of `choices` (`synonyms`
    first, then `SYNONYMS`; the exact word, else its case folded), else None."""
    text = str(word)
    tables: tuple[Mapping[str, str | tuple[str, str]], ...] = (synonyms or {}, SYNONYMS)
    for table in tables:
        entry = table.get(text)
        if entry is None:
            entry = next((v for k, v in table.items() if k.casefold() == text.casefold()),
                         None)
        if entry is None:
            continue
        target, note = (entry, "") if isinstance(entry, str) else entry
        if target in choices:
            return f"mbody calls it '{target}'" + (f": {note}" if note else "")
    return None


def name_list(names: Iterable[object], most: int = 5) -> str:
    """The first `most` names, and how many more ('O, A, … 3 more')."""
    texts = [str(n) for n in names]
    more = len(texts) - most
    return ", ".join(texts[:most]) + (f", … {more} more" if more > 0 else "")


def not_found(what: str, name: object, names: Sequence[str], many: str,
              none: str = "") -> KeyError:
    """The one KeyError of every lookup by name: "no <what> <name!r>", then a did-you-mean,
    else the names there are ("(the <many>: a, b, … 3 more)"), else `none` ("(there are no
    <many>)" by default).

    Parameters
    ----------
    what : str
        What was looked for, as the message names it ("body named", "reaction component").
    name : object
        What was asked for.
    names : sequence of str
        The names there are.
    many : str
        Their plural ("bodies").
    none : str, optional
        What to say when there are none.
    """
    said = f"no {what} {name!r}"
    hint = did_you_mean(name, names) if isinstance(name, str) else ""
    if hint:
        return KeyError(f"{said}; {hint}")
    if len(names):
        return KeyError(f"{said} (the {many}: {name_list(names)})")
    return KeyError(f"{said} ({none or f'there are no {many}'})")


CLOSE_CUTOFF = 0.6
"""difflib's similarity a did-you-mean needs (its default)."""


def closest(word: str, choices: Iterable[str]) -> str | None:
    """The choice `word` was probably meant to be (`did_you_mean`'s), or None: one that
    differs only in case, else difflib's closest match when it is a misspelling rather
    than another word: it starts with the same letter (a misspelling keeps it: 'bodys',
    'damp', 'veloctiy'), or it is a few edits away (`_EDITS_PER_LETTER`: 'ngle' for
    'angle'). 'frame' is not taken for 'name': two edits in five letters, and another
    first letter."""
    names = [str(c) for c in choices]
    text = str(word)
    folded = text.casefold()
    same = [c for c in names if c.casefold() == folded]
    if same:
        return same[0]
    # the choices whose lengths alone allow the similarity (difflib's real_quick_ratio,
    # its first test, in its own arithmetic): the same answer, without difflib's per-choice
    # work on the others (a large model's names are thousands)
    n = len(text)
    names = [c for c in names if 2.0 * min(n, len(c)) / (n + len(c)) >= CLOSE_CUTOFF]
    close = difflib.get_close_matches(text, names, n=1, cutoff=CLOSE_CUTOFF)
    if not close:
        return None
    meant = close[0]
    if text[:1].casefold() == meant[:1].casefold() or _edits(text, meant) <= max(
            1, max(len(text), len(meant)) // _EDITS_PER_LETTER):
        return meant
    return None


_EDITS_PER_LETTER = 4
"""A suggestion that starts with another letter is at most one edit (a letter added,
dropped, changed, or two swapped) per this many letters away, one at least."""


def _edits(a: str, b: str) -> int:
    """The optimal string alignment distance: letters inserted, deleted, substituted, or
    two neighbours transposed (counted once), to make `a` into `b`."""
    if abs(len(a) - len(b)) > max(len(a), len(b)) // _EDITS_PER_LETTER + 1:
        return abs(len(a) - len(b))  # too far apart for a suggestion: no table needed
    rows = [list(range(len(b) + 1))]
    for i in range(1, len(a) + 1):
        row = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cost = a[i - 1] != b[j - 1]
            row[j] = min(rows[-1][j] + 1, row[j - 1] + 1, rows[-1][j - 1] + cost)
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                row[j] = min(row[j], rows[-2][j - 2] + 1)
        rows.append(row)
    return rows[-1][-1]


_FLAGS: ContextVar[Mapping[str, str] | None] = ContextVar("mbody_option_flags", default=None)

# How a message names an argument: each surface in its own spelling. The functions below
# build a message's words for an argument; within `options_named` (the command line sets
# it around every command, from the command's own options) they give the flag the user
# typed (``--t-end``, ``--known A.Fx``), elsewhere the keyword of the Python call
# (``t_end``, ``known['A.Fx']``). A keyword the command has no option for keeps its
# Python spelling.


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


def option_name(keyword: str, value: str = "", typed: str = "") -> str:
    """How a message names the option `keyword` (set to `value` in Python, `typed` on the
    command line, when that is what it advises): its flag on the command line
    (`options_named`: ``--floating-base``; ``--samples N`` with `typed` ``"N"``), else
    the keyword argument of the call (``floating_base=True``, ``samples=N``)."""
    flag = (_FLAGS.get() or {}).get(keyword)
    if flag is not None:
        return f"{flag} {typed}" if typed else flag
    return f"{keyword}={value}" if value else keyword


def comma_words(given: str | Iterable[object], keyword: str, expected: str) -> list[str]:
    """The words of an argument that takes a text of comma-separated words or a sequence
    of such texts (``--require lower,upper.theta``, repeatable; ``require=["lower"]``),
    each stripped, empty ones kept (the caller says what an empty one means).

    Raises
    ------
    MbodyTypeError
        An item that is not text, or `given` neither text nor a sequence: "<option>:
        expected <expected>, got <type>".
    """
    texts = [given] if isinstance(given, str) else \
        list(given) if isinstance(given, Iterable) else [given]
    words: list[str] = []
    for text in texts:
        if not isinstance(text, str):
            raise MbodyTypeError(f"{option_name(keyword)}: expected {expected}, got "
                                 f"{type(text).__name__}")
        words += [w.strip() for w in text.split(",")]
    return words


def option_names() -> dict[str, str]:
    """The flags `options_named` set around this call ({} outside a command): what a
    piece of work done elsewhere (a sweep's cases on a cluster's workers) names its
    arguments by, to say it as the caller would."""
    return dict(_FLAGS.get() or {})


def g_text(x: float) -> str:
    """`x` as %g writes it, its exponent as people write it: 1e-6, 2.5e13 (not 1e-06,
    2.5e+13); the one home of that rule (`mbody.util.formatting.number` uses it)."""
    return re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", f"{x:g}")


def option_setting(keyword: str, value: object) -> str:
    """The option `keyword` set to `value`, as a message says what was given or advises:
    ``--max-steps 1000`` on the command line (a switch, `value` True, by its flag alone:
    ``--equilibrium``), ``max_steps=1000`` in Python (text quoted as Python writes it:
    ``method='Radau'``; a float as %g writes it, its exponent as people write it:
    ``1e-6``)."""
    flag = (_FLAGS.get() or {}).get(keyword)
    shown = g_text(value) if isinstance(value, float) else str(value)
    if flag is None:
        return f"{keyword}={value!r}" if isinstance(value, str) else f"{keyword}={shown}"
    return flag if value is True else f"{flag} {shown}"


def option_entry(keyword: str, key: str) -> str:
    """One entry of a mapping argument, as a message names it: ``--known A.Fx`` on the
    command line (a repeatable NAME=VALUE option), ``known['A.Fx']`` in Python."""
    flag = (_FLAGS.get() or {}).get(keyword)
    return f"{flag} {key}" if flag is not None else f"{keyword}[{key!r}]"

"""An XML attribute's numbers and keywords, read as MuJoCo's and URDF's parsers read them.

Every number of MJCF and URDF goes through `read_numbers`: each token must be a number
in C's syntax (``strtod``: a decimal, or in MJCF a hexadecimal ``0x1.8p3``; no ``1_000``,
no ``1,5``, no unit), finite, within a double's range (``1e400`` is not) and within the
magnitudes mbody reads in any model (1e100, `mbody.model.checks.MAX_MAGNITUDE`: their
products would overflow), a whole number within a C ``int`` where the attribute is an
integer (``group``, ``contype``), and the attribute must hold as many numbers as it
takes. A problem is an `Issue` at the line and
column of the attribute where the value was written (a ``<default>`` class's, when the
value comes from there), saying what was found and what was expected, so a bad number
is a clean error (exit 2), never an internal one. Reading is linear in the value's length.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import numpy as np

from mbody.errors import Issue, did_you_mean
from mbody.io.interop.xmlsource import Element
from mbody.model.checks import MAX_MAGNITUDE

INT_MIN, INT_MAX = -2**31, 2**31 - 1
"""The range of a C ``int``: MuJoCo's integer attributes (``group``, ``contype``)."""

_SPACE = re.compile(r"[ \t\n\r\f\v]+")
"""C's ``isspace``: what separates numbers (Python's str.split would also split at a
no-break space or an em space, which MuJoCo does not)."""
_DECIMAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_HEX = re.compile(r"[+-]?0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)(?:[pP][+-]?[0-9]+)?")
_NONFINITE = re.compile(r"[+-]?(?:inf|infinity|nan)", re.IGNORECASE)
_INTEGER = re.compile(r"[+-]?[0-9]+")
SHOWN = 40
"""Longest token quoted whole in a message (a 2 MB token is cut)."""


def _shown(token: str) -> str:
    return token if len(token) <= SHOWN else token[:SHOWN] + "..."


def split(text: str) -> list[str]:
    """The tokens of an attribute value, separated as C's ``isspace`` separates them."""
    return [t for t in _SPACE.split(text) if t]


def _number(token: str, attr: str, integer: bool, hexadecimal: bool
            ) -> tuple[float, str, str]:
    """(value, '', '') for a good token, or (0, what is wrong with it, a hint)."""
    if integer:
        if not _INTEGER.fullmatch(token):
            return 0.0, f"'{_shown(token)}' is not a whole number", \
                f"'{attr}' takes a whole number, such as 0 or 3"
        digits = token.lstrip("+-").lstrip("0") or "0"
        value = 0 if len(digits) > 10 else -int(digits) if token[0] == "-" else int(digits)
        if len(digits) > 10 or not INT_MIN <= value <= INT_MAX:
            return 0.0, (f"'{_shown(token)}' is outside the integers MuJoCo reads "
                         f"({INT_MIN} to {INT_MAX})"), ""
        return float(value), "", ""
    if _DECIMAL.fullmatch(token):
        x = float(token)
    elif hexadecimal and _HEX.fullmatch(token):
        try:
            x = float.fromhex(token)
        except OverflowError:
            x = math.inf
    elif _NONFINITE.fullmatch(token):
        return 0.0, f"'{token}' is not a finite number", ""
    else:
        hint = ("separate numbers with spaces, not commas" if "," in token else
                "write the digits without '_'" if "_" in token else
                "values are decimal numbers separated by spaces, such as \"0 0 1\"")
        return 0.0, f"'{_shown(token)}' is not a number", hint
    if math.isinf(x):
        return 0.0, f"'{_shown(token)}' is too large for a number (beyond 1.8e308)", ""
    if abs(x) > MAX_MAGNITUDE:
        return 0.0, (f"'{_shown(token)}' is beyond the magnitudes mbody reads (at most "
                     f"{MAX_MAGNITUDE:g}: products of larger numbers overflow)"), ""
    return x, "", ""


def read_numbers(e: Element, attr: str, text: str, issues: list[Issue], *,
                 count: int | None = None, least: int | None = None,
                 integer: bool = False, hexadecimal: bool = False) -> np.ndarray | None:
    """The numbers of attribute `attr` of `e`, whose value is `text`.

    Parameters
    ----------
    e : Element
        Where the value was written (its attribute `attr` locates the problems).
    attr : str
        The attribute's name.
    text : str
        Its value.
    issues : list of Issue
        Problems are appended here.
    count : int, optional
        The most numbers the attribute takes (None: any number).
    least : int, optional
        The fewest (default: `count`, an exact count; 0 lets the value be empty).
    integer : bool, optional
        Each number must be a whole number within a C ``int``.
    hexadecimal : bool, optional
        Also accept C's hexadecimal numbers (MJCF: MuJoCo reads them with ``strtod``).

    Returns
    -------
    numpy.ndarray or None
        The numbers (floats), or None when anything is wrong (then one issue says what).
    """
    tokens = split(text)
    values = np.empty(len(tokens))
    for k, t in enumerate(tokens):
        x, wrong, hint = _number(t, attr, integer, hexadecimal)
        if wrong:
            issues.append(e.issue(wrong, hint, attr))
            return None
        values[k] = x
    fewest = count if least is None else least
    if count is not None and not (fewest or 0) <= len(values) <= count:
        want = f"{count}" if fewest == count else f"{fewest} to {count}"
        kind = "whole number" if integer else "number"
        issues.append(e.issue(f"expected {want} {kind}{'s' if count > 1 else ''}, "
                              f"got {len(values)}", attr=attr))
        return None
    return values


def read_keyword(e: Element, attr: str, text: str, choices: Sequence[str],
                 issues: list[Issue]) -> str | None:
    """`text` if it is one of `choices` (MuJoCo's keywords are exact: ``True`` is not
    ``true``), else None with an issue at the attribute."""
    if text in choices:
        return text
    hint = did_you_mean(text, choices) or f"expected {' or '.join(choices)}"
    issues.append(e.issue(f"'{_shown(text)}' is not a value of '{attr}'", hint, attr))
    return None


BOOLEAN = ("false", "true")
"""MuJoCo's boolean keywords."""

"""JSON text that every strict reader parses: what ``--json`` prints and the JSON export.

Python's `json` writes ``Infinity`` and ``NaN`` for floats that are not finite; they are
not JSON (JavaScript's ``JSON.parse``, and most other readers, refuse the whole
document). Here such a number is written as ``null``, and the page that describes each
output says what a ``null`` there means (for ``mbody solve --json``: a condition
estimate that is not computed, or infinite because the system is singular). numpy
scalars and arrays become JSON numbers and lists, tuples become lists.

    dumps({"condition": float("inf")})     # '{\\n  "condition": null\\n}'

Read the other way, from a file that may be hostile (a run's info, a JSON export),
`loads` bounds the nesting before Python's parser recurses into it.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Mapping
from typing import IO, Any

import numpy as np

from mbody.util.formatting import number


def plain(value: Any) -> Any:
    """`value` as JSON types: a float that is not finite -> None, numpy scalars -> Python
    numbers, numpy arrays and tuples -> lists, mapping keys -> str.

    Parameters
    ----------
    value
        Nested dicts, lists, tuples, numpy arrays and scalars, str, numbers, None.

    Returns
    -------
    Any
        The same structure, every float finite or None.
    """
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, str | bool | int) or value is None:
        return value
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "f" and np.isfinite(value).all():
            return value.tolist()  # the common case, without a Python walk per number
        return plain(value.tolist())
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return plain(value.item())
    raise TypeError(f"{type(value).__name__} is not a JSON value")


def dumps(value: Any, *, indent: int | None = 2) -> str:
    """Strict JSON text of `value` (`plain`), UTF-8 characters kept as they are.

    Parameters
    ----------
    value
        What to write.
    indent : int or None
        Indentation (None: one line).

    Returns
    -------
    str
        JSON without ``NaN`` or ``Infinity`` (no trailing newline).
    """
    return json.dumps(plain(value), indent=indent, allow_nan=False, ensure_ascii=False)


def dump(value: Any, fh: IO[str], *, indent: int | None = 2) -> None:
    """Write `dumps(value)` and a newline to the text file `fh`.

    Parameters
    ----------
    value
        What to write.
    fh
        An open text file (or ``sys.stdout``).
    indent : int or None
        Indentation (None: one line).
    """
    fh.write(dumps(value, indent=indent))
    fh.write("\n")


MAX_DEPTH = 64
"""Deepest nesting of arrays and objects `loads` parses (as for a model file's YAML,
`mbody.model.loader.MAX_DEPTH`); what mbody writes nests 4 deep at most."""

_NOT_MARKS = bytes(range(256)).translate(None, b'"[]{}')
"""Every byte but a quote or a bracket: what `nesting` deletes (one C call at import,
where a generator over the 256 bytes took 0.02 ms of every simulation's start)."""


def nesting(text: str) -> int:
    """How deep the arrays and objects of JSON `text` nest (brackets inside strings do not
    count), in one pass of C scans over the text, then numpy over the quotes and brackets
    left: time linear in the text, whatever it holds.

    Escapes first: a run of backslashes is pairs (each an escaped backslash), and one
    more when the run is odd, which escapes the character after it; so dropping every
    pair and then every backslash-quote leaves exactly the quotes that begin and end
    strings. A bracket is inside a string when an odd number of those come before it.
    In valid JSON a backslash is only ever inside a string, so the count is exact; in
    text that is not JSON it is exact up to the first error, where the parser stops.
    (A regular expression for a string with its escapes inside ran from every quote of
    ``"\\"\\"\\"...``, a string that never ends, to the end of the text: time quadratic in
    its length, 21 s for 64 kB.)"""
    unescaped = text.replace("\\\\", "").replace('\\"', "")
    marks = np.frombuffer(unescaped.encode("utf-8", "surrogatepass").translate(
        None, _NOT_MARKS), dtype=np.uint8)
    if not len(marks):
        return 0
    quote = marks == ord('"')
    brackets = marks[~(quote | np.logical_xor.accumulate(quote))]
    if not len(brackets):
        return 0
    opens = (brackets == ord("[")) | (brackets == ord("{"))
    return int(np.cumsum(opens.astype(np.int32) * 2 - 1, dtype=np.int64).max())


def loads(text: str, *, max_depth: int = MAX_DEPTH) -> Any:
    """`json.loads(text)` for text that may be hostile: refused before parsing when its
    arrays and objects nest deeper than `max_depth` (Python's parser recurses once a
    level, and a file of 10 000 ``[`` would end in a RecursionError).

    Parameters
    ----------
    text : str
        JSON text (``NaN`` and ``Infinity`` are read, as Python's `json` writes them).
    max_depth : int
        The deepest nesting accepted.

    Returns
    -------
    Any
        The parsed value.

    Raises
    ------
    ValueError
        The text nests deeper than `max_depth` (saying how deep), holds a whole number of
        more digits than Python converts (saying how many), or is not JSON
        (`json.JSONDecodeError`, a `ValueError`).
    """
    depth = nesting(text)
    if depth > max_depth:
        raise ValueError(f"JSON nested {depth} deep; at most {max_depth} levels are read")
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        raise
    except ValueError:  # json's other ValueError: a whole number longer than Python reads
        json.loads(text, parse_int=_bounded_int)  # read again, only now: raises why
        raise


def _bounded_int(digits: str) -> int:
    """A JSON whole number, or a ValueError saying it is too long in words, rather than
    Python's advice to raise its limit (`sys.set_int_max_str_digits`, a setting of the
    interpreter, not of a file being read): the limit bounds the time of the conversion,
    which grows as the square of the digits."""
    limit = sys.get_int_max_str_digits()  # 0: none
    size = len(digits.lstrip("-"))
    if limit and size > limit:
        raise ValueError(f"a whole number of {number(size)} digits; at most "
                         f"{number(limit)} are read")
    return int(digits)

"""A small, safe parser for a student's equation, such as ``"2*a_y = O.Fy - 19.62"``.

    equation := expr '=' expr
    expr     := term (('+' | '-') term)*
    term     := unary (('*' | '/') unary)*
    unary    := ('+' | '-') unary | power
    power    := atom (('^' | '**') unary)?          right-associative, binds tighter than '-'
    atom     := NUMBER | NAME | FUNC '(' expr ')' | '(' expr ')'
    FUNC     := sin | cos | tan | sqrt | exp

The text becomes a tree of tuples and nothing else: no `eval`, no `sympify`, no attribute
access. Names are not looked up here (`mbody.answers.linear` resolves them against the
body's vocabulary, with a did-you-mean); a reaction label such as ``O.Fy`` or
``pin-1.Fx`` is one name. Every node keeps the 0-based character position it starts at,
so that each error can point at its column in the answers file.

A few characters pasted from textbooks are read as what they mean: ``−`` (minus sign)
as ``-``, ``·`` and ``×`` as ``*``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, NoReturn

from mbody.errors import MbodyError
from mbody.model.expressions import Labels, OperatorParser, tokenise

FUNCTIONS = ("sin", "cos", "tan", "sqrt", "exp")
"""The functions an equation may call (one argument each; angles in radians)."""
MAX_LENGTH = 2000
"""Longest equation accepted (characters)."""

_PASTED = str.maketrans({"\u2212": "-", "\u00b7": "*", "\u00d7": "*", "\u22c5": "*"})
_TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)
  | (?P<name>[^\W\d]\w*(?:\.[^\W\d]\w*)?)
  | (?P<op>\*\*|[-+*/^()=])
""", re.VERBOSE)

# A node: ('num', value, pos) | ('name', text, pos) | ('neg', node, pos)
# | (op, a, b, pos) for op in + - * / ^ | ('call', name, node, pos).
Node = tuple


class EquationError(MbodyError):
    """An equation that cannot be read; `position` is the 0-based character index.

    Parameters
    ----------
    text : str
        The equation as written.
    position : int
        Where the problem is (0-based index into `text`).
    message : str
        What is wrong.
    hint : str, optional
        A way to fix it, or a did-you-mean.
    """

    def __init__(self, text: str, position: int, message: str, hint: str = ""):
        self.text, self.position, self.reason, self.hint = text, position, message, hint
        super().__init__(f"{message} at character {position + 1} of {text!r}"
                         + (f" ({hint})" if hint else ""))


@dataclass(frozen=True)
class ParsedEquation:
    """``lhs = rhs`` as two trees.

    Parameters
    ----------
    text : str
        The equation as written.
    lhs, rhs : tuple
        The trees of the two sides (see the module's grammar).
    equals : int
        The 0-based position of its '='.
    """

    text: str
    lhs: Node
    rhs: Node
    equals: int = 0


def parse_equation(text: str, labels: Iterable[str] = ()) -> ParsedEquation:
    """Parse ``lhs = rhs``; raise `EquationError` (with the position) when it is not valid.

    Parameters
    ----------
    text : str
        The equation.
    labels : iterable of str
        Reaction labels of the model: each is read as one name even where its joint's
        name holds characters that are operators elsewhere (``pin-1.Fx``).

    Returns
    -------
    ParsedEquation
        The two sides as trees of tuples.
    """
    if not isinstance(text, str):
        raise EquationError(str(text), 0, "expected an equation as text")
    if len(text) > MAX_LENGTH:
        raise EquationError(text[:40] + "...", 0,
                            f"the equation is longer than {MAX_LENGTH} characters")
    parser = _Parser(text, _tokenise(text, labels))
    if not text.strip():
        raise EquationError(text, 0, "the equation is empty",
                            "write it as left side = right side, e.g. 2*a_y = O.Fy - 19.62")
    lhs = parser.expr(0)
    kind, value, pos = parser.peek()
    if not (kind == "op" and value == "="):
        if kind == "end":
            raise EquationError(text, pos, "an equation needs '='",
                                "write it as left side = right side")
        parser.unexpected()
    equals = parser.take()[2]
    if parser.peek()[0] == "end":
        raise EquationError(text, parser.peek()[2], "nothing on the right of '='",
                            "write 0 if the right side is zero")
    rhs = parser.expr(0)
    kind, value, pos = parser.peek()
    if kind == "op" and value == "=":
        raise EquationError(text, pos, "a second '='", "write one equation per entry")
    if kind != "end":
        parser.unexpected()
    return ParsedEquation(text, lhs, rhs, equals)


def names_in(text: str, labels: Iterable[str] = ()) -> list[str]:
    """The names an equation uses (not its functions), each once, in reading order.

    Parameters
    ----------
    text : str
        The equation, as `parse_equation` reads it.
    labels : iterable of str
        As `parse_equation`'s: reaction labels read as one name.

    Returns
    -------
    list of str
    """
    seen = dict.fromkeys(value for kind, value, _ in _tokenise(text, labels)
                         if kind == "name" and value not in FUNCTIONS)
    return list(seen)


def _tokenise(text: str, labels: Iterable[str]) -> list[tuple[str, str, int]]:
    return tokenise(text.translate(_PASTED), _TOKEN, _label_index(tuple(labels)))


@lru_cache(maxsize=8)
def _label_index(labels: tuple[str, ...]) -> Labels:
    """The labels the name token would not read whole (``pin-1.Fx``); the longest is
    taken first (A.Fx is never a prefix of AB.Fx); made once per model."""
    return Labels.of(lab for lab in labels if not _TOKEN.fullmatch(lab))


_BAD_HINTS = {
    "<": "only equations (=) are checked", ">": "only equations (=) are checked",
    ",": "functions take one argument", "[": "use ( ) for grouping",
    "{": "use ( ) for grouping", ".": "a reaction is written <joint>.<component>, e.g. O.Fy",
    "'": "write derivatives by name: alpha, a_x, w", "\u0307": "write derivatives by "
    "name: alpha, a_x, w",
    "\u00b0": "angles are in radians: write pi/6 or 30*pi/180 for 30°",
    ";": "one equation per entry, without ';'",
}


class _Parser(OperatorParser):
    WHAT = "equation"

    def fail(self, pos: int, message: str, hint: str = "") -> NoReturn:
        raise EquationError(self.text, pos, message, hint)

    def bad_hint(self, ch: str) -> str:
        return _BAD_HINTS.get(ch, "")

    def node(self, op: str, pos: int, *operands: Any) -> Node:
        return (op, *operands, pos)

    def unexpected(self) -> NoReturn:
        kind, value, pos = self.peek()
        if kind == "op" and value == ")":
            self.fail(pos, "unmatched ')'")
        self.fail(pos, f"unexpected {self.describe(kind, value)}",
                  "an operator (+ - * / ^) is missing?" if kind in ("num", "name") else "")

    def atom(self, depth: int) -> Node:
        kind, value, pos = self.take()
        if kind == "num":
            x = float(value)
            if not math.isfinite(x) or x > 1e100:
                raise EquationError(self.text, pos, f"the number {value} is out of range",
                                    "at most 1e100")
            node: Node = ("num", x, pos)
        elif kind == "name" and value in FUNCTIONS:
            if self.peek()[1] != "(":
                raise EquationError(self.text, self.peek()[2],
                                    f"'{value}' must be followed by '('",
                                    f"write {value}(...)")
            self.take()
            arg = self.expr(depth + 1)
            if self.peek()[1] != ")":
                raise EquationError(self.text, self.peek()[2], "expected ')'"
                                    if self.peek()[0] != "end" else "missing ')'",
                                    f"to close {value}( at character {pos + 1}")
            self.take()
            node = ("call", value, arg, pos)
        elif kind == "name":
            if self.peek()[0] == "op" and self.peek()[1] == "(":
                raise EquationError(self.text, pos, f"unknown function '{value}'",
                                    "the functions are " + ", ".join(FUNCTIONS)
                                    + "; write '*' for a product, e.g. m*(a_x + 1)")
            node = ("name", value, pos)
        elif kind == "op" and value == "(":
            node = self.expr(depth + 1)
            if self.peek()[1] != ")":
                raise EquationError(self.text, self.peek()[2], "missing ')'",
                                    f"to close '(' at character {pos + 1}")
            self.take()
        elif kind == "end":
            raise EquationError(self.text, pos, "the equation ends too early")
        elif kind == "op" and value == "=":
            if pos > 0 and self.text[pos - 1] == "=":  # '==': a comparison's spelling
                raise EquationError(self.text, pos - 1, "'==' between the two sides",
                                    "an equation has one '=': m*a_x = O.Fx")
            raise EquationError(self.text, pos, "nothing on the left of '='"
                                if pos == self.tokens[0][2] else "unexpected '='",
                                "write 0 if that side is zero")
        else:
            raise EquationError(self.text, pos, f"unexpected {self.describe(kind, value)}")
        self.no_implicit_product("2*a_x")
        return node

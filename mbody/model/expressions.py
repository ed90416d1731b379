"""A small, safe parser for load expressions of time, such as ``"50*sin(2*t)"``.

    expr  := term (('+' | '-') term)*
    term  := unary (('*' | '/') unary)*
    unary := ('+' | '-') unary | power
    power := atom (('^' | '**') unary)?          right-associative, binds tighter than '-'
    atom  := NUMBER | 't' | 'pi' | FUNC '(' expr ')' | '(' expr ')'
    FUNC  := sin | cos | tan | exp | log | sqrt | abs

The text is tokenised and parsed once into a tree of tuples; evaluating the tree calls
only the numpy functions named above, so a model file can never run code (no `eval`,
no attribute access, no names other than ``t`` and ``pi``). `Expression(t)` accepts a
scalar or an array of times and returns a value of the same shape (vectorised over t).
Sub-trees without ``t`` are folded into constants when compiled.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from functools import cached_property
from typing import Any, NamedTuple, NoReturn, overload

import numpy as np

from mbody.errors import MbodyError, closest

FUNCTIONS: dict[str, Callable[[Any], Any]] = {
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "exp": np.exp,
    "log": np.log, "sqrt": np.sqrt, "abs": np.abs,
}
"""The functions an expression may call (one argument each; log is the natural log)."""
CONSTANTS = {"pi": math.pi}
VARIABLE = "t"
MAX_LENGTH = 1000
"""Longest expression accepted (characters); deeper than this is not a load, it is a bug."""
MAX_DEPTH = 100
MAX_NUMBER = 1e100
"""Largest number written in an expression (the model file's limit)."""

_TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)
  | (?P<name>[A-Za-z_][A-Za-z_0-9]*)
  | (?P<op>\*\*|[-+*/^()])
""", re.VERBOSE)


class ExpressionError(MbodyError):
    """An expression that cannot be parsed; `position` is the 0-based character index."""

    def __init__(self, text: str, position: int, message: str, hint: str = ""):
        self.text, self.position, self.reason, self.hint = text, position, message, hint
        super().__init__(f"{message} at character {position + 1} of {text!r}"
                         + (f" ({hint})" if hint else ""))

    def caret(self) -> str:
        """The expression with a caret under the offending character (two lines)."""
        return f"{self.text}\n{' ' * self.position}^"


# A node is ('num', value) | ('t',) | ('neg', a) | (op, a, b) for op in + - * / ^ |
# ('call', name, a).
Node = tuple


@dataclass(frozen=True)
class Expression:
    """A compiled expression of t: call it with a time (scalar or array).

    text: the source; tree: the parsed (constant-folded) tree; constant: True when it
    does not depend on t (then `value` is its number).
    """

    text: str
    tree: Node

    @property
    def constant(self) -> bool:
        return self.tree[0] == "num"

    @property
    def value(self) -> float:
        return float(self(0.0))

    @cached_property
    def _scalar(self) -> Callable[[float], float]:
        return _closure(self.tree)

    @cached_property
    def program(self) -> tuple[np.ndarray, np.ndarray]:
        """The tree in postfix order for `mbody.solve.compiled.evaluate_program`: (codes (P,)
        int64, numbers (P,) float64); `PROGRAM_CODES` names the codes."""
        codes: list[int] = []
        numbers: list[float] = []

        def emit(node: Node) -> None:
            node, spine = left_spine(node)
            kind = node[0]
            if kind == "call":
                emit(node[2])
                codes.append(PROGRAM_CODES[node[1]])
            else:
                for a in node[1:]:
                    if isinstance(a, tuple):
                        emit(a)
                codes.append(PROGRAM_CODES[kind])
            numbers.append(float(node[1]) if kind == "num" else 0.0)
            for op in reversed(spine):
                emit(op[2])
                codes.append(PROGRAM_CODES[op[0]])
                numbers.append(0.0)

        emit(self.tree)
        return np.array(codes, dtype=np.int64), np.array(numbers, dtype=float)

    def at(self, t: float) -> float:
        """The value at one time t (s): the same number as `self(t)`, about twenty times
        sooner (a tree of closures over `math`, no numpy calls; what a simulation's
        right-hand side evaluates thousands of times). Out of the domain of `math` (1/0,
        log of a negative number, overflow) it falls back to numpy's inf/nan."""
        try:
            return self._scalar(t)
        except (ArithmeticError, ValueError):
            return self(float(t))

    @overload
    def __call__(self, t: float) -> float: ...
    @overload
    def __call__(self, t: np.ndarray) -> np.ndarray: ...
    def __call__(self, t: float | np.ndarray) -> float | np.ndarray:
        """The value at t: a float for a number (or a 0-d array), an array of t's shape for
        an array."""
        # Out-of-domain values (log(-1), 1/0) become nan/inf; callers check finiteness.
        with np.errstate(all="ignore"):
            out = _eval(self.tree, np.asarray(t, dtype=float))
        return np.broadcast_to(out, np.shape(t)) + 0.0 if np.ndim(t) else float(out)

    def __str__(self) -> str:
        return self.text


def compile_expression(text: str) -> Expression:
    """Parse `text`; raise `ExpressionError` (with the position) when it is not valid."""
    if not isinstance(text, str):
        raise ExpressionError(str(text), 0, "expected an expression as text")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(text[:40] + "...", 0,
                              f"the expression is longer than {MAX_LENGTH} characters")
    tokens = tokenise(text)
    parser = _Parser(text, tokens)
    tree = parser.expr(0)
    kind, value, pos = parser.peek()
    if kind != "end":
        if value == ")":
            raise ExpressionError(text, pos, "unmatched ')'")
        raise ExpressionError(text, pos, f"unexpected {_describe(kind, value)}",
                              "an operator (+ - * / ^) is missing?" if kind in ("num", "name",
                                                                              "op") else "")
    return Expression(text, tree)


@dataclass(frozen=True)
class Labels:
    """Whole names a tokeniser takes before its pattern (a student's equation names
    reactions such as ``pin-1.Fx``, which the name token would split): the names, and
    their lengths longest first, so that a position costs one set lookup per distinct
    length, not one comparison per name (1000 reactions made an equation take a quarter
    of a second)."""

    names: frozenset[str]
    lengths: tuple[int, ...]

    @classmethod
    def of(cls, names: Iterable[str]) -> Labels:
        """The labels `names` (empty names dropped)."""
        kept = frozenset(n for n in names if n)
        return cls(kept, tuple(sorted({len(n) for n in kept}, reverse=True)))

    def __bool__(self) -> bool:
        return bool(self.names)

    def at(self, text: str, i: int) -> str | None:
        """The longest label at position i of `text` that ends where a name may end."""
        for n in self.lengths:
            name = text[i:i + n]
            if name in self.names and not text[i + n:i + n + 1].isalnum():
                return name
        return None


def tokenise(text: str, pattern: re.Pattern[str] = _TOKEN,
             labels: Labels | None = None) -> list[tuple[str, str, int]]:
    """(kind, text, position) tokens of `text` by `pattern`'s named groups, ending with
    ``("end", "", len(text))``; whitespace is dropped, a character no group matches is a
    ``"bad"`` token (reported when a parser reaches it, so errors come in reading order).

    `labels` are whole names taken before `pattern` is tried, where they stand alone
    (`Labels`).
    """
    out = []
    i = 0
    while i < len(text):
        label = None
        if labels and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            label = labels.at(text, i)
        if label is not None:
            out.append(("name", label, i))
            i += len(label)
            continue
        m = pattern.match(text, i)
        if not m:
            out.append(("bad", text[i], i))
            i += 1
            continue
        kind = m.lastgroup or ""
        if kind != "ws":
            out.append((kind, m.group(), i))
        i = m.end()
    out.append(("end", "", len(text)))
    return out


def _describe(kind: str, value: str, what: str = "expression") -> str:
    return {"num": f"number {value}", "name": f"name '{value}'", "op": f"'{value}'",
            "end": f"end of the {what}"}[kind]


class OperatorParser:
    """Sums, products, signs and powers over `tokenise`'s tokens, by precedence
    (``-2^2 = -4``, ``2^-1 = 0.5``, as on paper), nesting bounded by `MAX_DEPTH`.

    Nesting is what recurses: parentheses, function calls, signs and powers (``2^2^2``
    nests to the right) each count a level. A sum or a product of any length is read in
    a loop and becomes a chain that grows to the left (``((a + b) + c) + d``), which
    every walker of a tree follows in a loop too (`left_spine`): a long flat sum costs no
    stack however long it is.

    The grammar shared by load expressions and a student's equations; a subclass says
    what an atom is (`atom`), how a node is built (`node`) and which error is raised
    (`fail`, with `bad_hint` for a character no token matches).
    """

    WHAT = "expression"
    """What is parsed, in error messages ("the end of the expression")."""

    def __init__(self, text: str, tokens: list[tuple[str, str, int]]):
        self.text, self.tokens, self.i = text, tokens, 0

    def fail(self, pos: int, message: str, hint: str = "") -> NoReturn:
        raise NotImplementedError

    def node(self, op: str, pos: int, *operands: Any) -> Any:
        raise NotImplementedError

    def atom(self, depth: int) -> Any:
        raise NotImplementedError

    def bad_hint(self, ch: str) -> str:
        return ""

    def take(self) -> tuple[str, str, int]:
        tok = self.peek()
        self.i += 1
        return tok

    def peek(self) -> tuple[str, str, int]:
        kind, ch, pos = self.tokens[self.i]
        if kind == "bad":
            self.fail(pos, f"unexpected character {ch!r}", self.bad_hint(ch))
        return self.tokens[self.i]

    def describe(self, kind: str, value: str) -> str:
        return _describe(kind, value, self.WHAT)

    def no_implicit_product(self, example: str) -> None:
        """After an atom: "2t", "2(t+1)", "m g" are refused with the '*' they lack."""
        kind, value, pos = self.peek()
        if kind in ("num", "name") or (kind == "op" and value == "("):
            self.fail(pos, f"unexpected {self.describe(kind, value)}",
                      f"write '*' for multiplication, e.g. {example}")

    def _deeper(self, depth: int, pos: int) -> None:
        if depth > MAX_DEPTH:
            self.fail(pos, f"nesting deeper than {MAX_DEPTH} levels")

    def expr(self, depth: int) -> Any:
        self._deeper(depth, self.peek()[2])
        node = self.term(depth)
        while self.peek()[0] == "op" and self.peek()[1] in ("+", "-"):
            _, op, pos = self.take()
            node = self.node(op, pos, node, self.term(depth))
        return node

    def term(self, depth: int) -> Any:
        node = self.unary(depth)
        while self.peek()[0] == "op" and self.peek()[1] in ("*", "/"):
            _, op, pos = self.take()
            node = self.node(op, pos, node, self.unary(depth))
        return node

    def unary(self, depth: int) -> Any:
        kind, value, pos = self.peek()
        if kind == "op" and value in ("+", "-"):
            self.take()
            self._deeper(depth, pos)
            operand = self.unary(depth + 1)
            return operand if value == "+" else self.node("neg", pos, operand)
        return self.power(depth)

    def power(self, depth: int) -> Any:
        base = self.atom(depth)
        kind, value, pos = self.peek()
        if kind == "op" and value in ("^", "**"):
            self.take()
            self._deeper(depth + 1, pos)  # 2^2^...^2 nests to the right, one level a '^'
            return self.node("^", pos, base, self.unary(depth + 1))
        return base


class _Parser(OperatorParser):
    _BAD_HINTS = {"=": "comparisons are not supported", "<": "comparisons are not supported",
                  ">": "comparisons are not supported", ",": "functions take one argument",
                  "[": "use ( ) for grouping", "{": "use ( ) for grouping",
                  ".": "attribute access is not allowed"}

    def fail(self, pos: int, message: str, hint: str = "") -> NoReturn:
        raise ExpressionError(self.text, pos, message, hint)

    def error(self, message: str, hint: str = "") -> NoReturn:
        self.fail(self.peek()[2], message, hint)

    def bad_hint(self, ch: str) -> str:
        return self._BAD_HINTS.get(ch, "")

    def node(self, op: str, pos: int, *operands: Any) -> Node:
        return _fold((op, *operands))

    def atom(self, depth: int) -> Node:
        kind, value, pos = self.take()
        if kind == "num":
            x = float(value)
            if math.isinf(x) or x > MAX_NUMBER:
                raise ExpressionError(self.text, pos, f"the number {value} is out of range",
                                      f"at most {MAX_NUMBER:g}, as everywhere in a model")
            if x == 0 and value.lower().partition("e")[0].strip("0.") != "":
                raise ExpressionError(self.text, pos, f"the number {value} is below the "
                                      "smallest double", "it would be read as 0; write 0 if "
                                      "that is meant")
            node: Node = ("num", x)
        elif kind == "name":
            if value == VARIABLE:
                node = ("t",)
            elif value in CONSTANTS:
                node = ("num", CONSTANTS[value])
            elif value in FUNCTIONS:
                if self.peek()[1] != "(":
                    self.error(f"'{value}' must be followed by '('", f"write {value}(t)")
                self.take()
                arg = self.expr(depth + 1)
                if self.peek()[1] != ")":
                    self.error("expected ')'" if self.peek()[0] != "end"
                               else "missing ')'", f"to close {value}( at character {pos + 1}")
                self.take()
                node = _fold(("call", value, arg))
            else:
                raise ExpressionError(self.text, pos, f"unknown name '{value}'",
                                      _unknown_name_hint(value))
        elif kind == "op" and value == "(":
            node = self.expr(depth + 1)
            if self.peek()[1] != ")":
                self.error("missing ')'", f"to close '(' at character {pos + 1}")
            self.take()
        elif kind == "end":
            raise ExpressionError(self.text, pos, "the expression ends too early"
                                  if self.text.strip() else "the expression is empty")
        else:
            raise ExpressionError(self.text, pos, f"unexpected {_describe(kind, value)}")
        self.no_implicit_product("2*t")
        return node


_MEANT = {"ln": "log", "time": "t"}
"""Names other notations use for one of ours that neither its start nor
`mbody.errors.closest` finds (a name that differs only in case, ``Sin`` or ``T``, it
finds)."""


def _unknown_name_hint(name: str) -> str:
    """What a name the grammar does not know was probably meant to be: a function or `t`,
    `pi` (a did-you-mean: a name ours starts, ``cosine`` or ``sqrtf``, first), or a number
    (``nan``, ``inf``: no such value is allowed)."""
    if name.casefold() in ("nan", "inf", "infinity"):
        return "a value must be a finite number"
    known = [VARIABLE, *CONSTANTS, *FUNCTIONS]
    starts = [k for k in known if len(k) > 1 and name.casefold().startswith(k)]
    meant = (_MEANT.get(name.casefold()) or max(starts, key=len, default=None)
             or closest(name, known))
    listed = ("the only variable is t (time, s)" if len(name) == 1 and meant is None else
              "known names: " + ", ".join(known))
    return f"did you mean '{meant}'? {listed}" if meant else listed


def _fold(node: Node) -> Node:
    """Replace a node whose operands are all numbers by its value."""
    args = [a for a in node[1:] if isinstance(a, tuple)]
    if all(a[0] == "num" for a in args):
        with np.errstate(all="ignore"):
            v = float(_eval(node, np.asarray(0.0)))
        if math.isfinite(v):  # keep 1/0 unfolded so the error surfaces where it is used
            return ("num", v)
    return node


CHAINS = frozenset("+-*/")
"""The left-associative operators: a run of them builds a chain down the left operands."""


def left_spine(node: tuple) -> tuple[tuple, list[tuple]]:
    """(first operand, chain) of a left-growing chain of `CHAINS` operators:
    ``((a + b) * c) - d`` -> ``(a, [-, *, +])`` (outermost first; apply in reverse, each
    to the value so far and its right operand). A node that is no chain -> (node, []).

    A long sum (``1+1+...+1``) is a tree as deep as it has terms; walking its spine in a
    loop, and recursing only into right operands (whose depth the parser bounds), keeps
    every walker of a tree within a few frames per level of nesting."""
    spine = []
    while node[0] in CHAINS:
        spine.append(node)
        node = node[1]
    return node, spine


def _eval(node: Node, t: np.ndarray) -> Any:
    node, spine = left_spine(node)
    kind = node[0]
    if kind == "num":
        value = node[1]
    elif kind == "t":
        value = t
    elif kind == "neg":
        value = -_eval(node[1], t)
    elif kind == "call":
        value = FUNCTIONS[node[1]](_eval(node[2], t))
    else:  # '^'
        value = np.power(_eval(node[1], t), _eval(node[2], t))
    for op in reversed(spine):
        b = _eval(op[2], t)
        kind = op[0]
        if kind == "+":
            value = value + b
        elif kind == "-":
            value = value - b
        elif kind == "*":
            value = value * b
        else:
            value = np.divide(value, b)
    return value


PROGRAM_CODES = {"num": 0, "t": 1, "neg": 2, "+": 3, "-": 4, "*": 5, "/": 6, "^": 7,
                 "sin": 8, "cos": 9, "tan": 10, "exp": 11, "log": 12, "sqrt": 13, "abs": 14}
"""Operation codes of `Expression.program` (postfix: operands first)."""

_MATH: dict[str, Callable[[float], float]] = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "exp": math.exp,
    "log": math.log, "sqrt": math.sqrt, "abs": abs,
}
_OPS: dict[str, Callable[[float, float], float]] = {
    "+": float.__add__, "-": float.__sub__, "*": float.__mul__, "/": float.__truediv__,
    "^": math.pow,
}


def _closure(node: Node) -> Callable[[float], float]:
    """`_eval` of one scalar time as nested closures (built once per expression). `math`
    raises where numpy gives inf or nan (1/0, log(-1), (-8)^(1/3), overflow): the caller
    (`Expression.at`) then asks numpy."""
    kind = node[0]
    if kind in CHAINS:
        first, spine = left_spine(node)
        if len(spine) > 1:  # a long sum or product: one loop, not a closure per operator
            head = _closure(first)
            rest = [(_OPS[n[0]], _closure(n[2])) for n in reversed(spine)]

            def chain(t: float) -> float:
                value = head(t)
                for op, f in rest:
                    value = op(value, f(t))
                return value
            return chain
    if kind == "num":
        value = float(node[1])
        return lambda t: value
    if kind == "t":
        return float
    if kind == "neg":
        f = _closure(node[1])
        return lambda t: -f(t)
    if kind == "call":
        fn, f = _MATH[node[1]], _closure(node[2])
        return lambda t: fn(f(t))
    op, a, b = _OPS[kind], _closure(node[1]), _closure(node[2])
    return lambda t: op(a(t), b(t))


def check_finite(expr: Expression, t: float = 0.0) -> str:
    """'' when expr(t) is finite, else a sentence saying what went wrong."""
    v = expr(t)
    if math.isfinite(v):
        return ""
    return (f"the expression gives {v} at t = {t:g} (division by zero, log or sqrt of a "
            "negative number?)")


CHECK_SPAN = 10.0
"""Span, s, over which `mbody check` samples expressions: simulate's default t_end."""
MAX_CHECK_SAMPLES = 100_001


def check_times(t_end: float) -> np.ndarray:
    """Times at which an expression is sampled over [0, t_end]: every millisecond, computed
    as k / 1000 so that times such as 1, 0.1 or 2.5 are hit exactly (1/(t - 1) is infinite
    only at t = 1 exactly); for long spans a coarser round step (2, 5 or 10 times a power
    of ten) keeps it within `MAX_CHECK_SAMPLES` points. t_end itself is always included."""
    step = next(m * 10.0 ** e for e in range(-3, 300) for m in (1, 2, 5)
                if t_end / (m * 10.0 ** e) <= MAX_CHECK_SAMPLES - 1)
    k = np.arange(int(t_end / step) + 1, dtype=float)
    inverse = round(1 / step)  # 1000, 500, 200, ... 2: exact for every step below 1
    t = k / inverse if step < 1 else k * step
    t = t[t <= t_end]
    return t if t[-1] == t_end else np.append(t, t_end)


def first_nonfinite(expr: Expression, t_end: float) -> tuple[float, float] | None:
    """(t, value) of the first sample of [0, t_end] (`check_times`) where `expr` is not
    finite, or None."""
    if expr.constant:
        return None
    t = check_times(float(t_end))
    v = expr(t)
    bad = ~np.isfinite(v)
    if not bad.any():
        return None
    i = int(np.argmax(bad))
    return float(t[i]), float(v[i])


class ProgramTable(NamedTuple):
    """Time-varying load entries as `mbody.solve.compiled.set_loads` takes them (in this
    order, after the constant values)."""

    rows: np.ndarray  # (e,) int64: the load (row) of each varying entry
    cols: np.ndarray  # (e,) int64: its component
    which: np.ndarray  # (e,) int64: its expression, index into starts
    starts: np.ndarray  # (u + 1,) int64: each expression's program in codes/numbers
    codes: np.ndarray  # (P,) int64: operation codes (`PROGRAM_CODES`), postfix
    numbers: np.ndarray  # (P,) float64: the constants the codes push


@dataclass(frozen=True)
class ExpressionTable:
    """Time-varying entries of a (k, c) table of load components.

    rows, cols: (e,) where each varying entry sits; which: (e,) index into `exprs`, the
    distinct compiled expressions (an expression shared by many loads is evaluated once).
    """

    rows: np.ndarray
    cols: np.ndarray
    which: np.ndarray
    exprs: tuple[Expression, ...]

    @classmethod
    def build(cls, entries: list[tuple[int, int, Expression]]) -> ExpressionTable | None:
        """From (row, col, expression) triples; None when there are none."""
        if not entries:
            return None
        index: dict[Node, int] = {}
        exprs: list[Expression] = []
        which = []
        for _, _, e in entries:
            if e.tree not in index:
                index[e.tree] = len(exprs)
                exprs.append(e)
            which.append(index[e.tree])
        return cls(np.array([r for r, _, _ in entries], dtype=np.intp),
                   np.array([c for _, c, _ in entries], dtype=np.intp),
                   np.array(which, dtype=np.intp), tuple(exprs))

    @cached_property
    def program(self) -> ProgramTable:
        """The table for `mbody.solve.compiled.set_loads` (`ProgramTable`)."""
        progs = [e.program for e in self.exprs]
        starts = np.zeros(len(progs) + 1, dtype=np.int64)
        starts[1:] = np.cumsum([len(c) for c, _ in progs])
        return ProgramTable(
            rows=self.rows.astype(np.int64), cols=self.cols.astype(np.int64),
            which=self.which.astype(np.int64), starts=starts,
            codes=np.concatenate([c for c, _ in progs]),
            numbers=np.concatenate([v for _, v in progs]))

    @cached_property
    def _entries(self) -> tuple[tuple[int, int, int], ...]:
        """(row, column, expression) per varying entry, as Python ints."""
        return tuple(zip(self.rows.tolist(), self.cols.tolist(), self.which.tolist(),
                         strict=True))

    def apply(self, base: np.ndarray, t: float | np.ndarray) -> np.ndarray:
        """`base` (k, c) with the varying entries set to their values at `t`.

        Scalar t -> (k, c); array t of shape S -> S + (k, c).
        """
        if isinstance(t, float | int) or np.ndim(t) == 0:  # a simulation's right-hand side
            out = np.array(base, dtype=float)
            t = float(t)
            values = [e.at(t) for e in self.exprs]
            for r, c, w in self._entries:
                out[r, c] = values[w]
            return out
        t = np.asarray(t, dtype=float)
        out = np.broadcast_to(base, (*t.shape, *np.shape(base))).copy()
        vals = np.stack([e(t) for e in self.exprs], axis=-1)  # S + (u,)
        out[..., self.rows, self.cols] = vals[..., self.which]
        return out

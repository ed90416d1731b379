"""A parsed equation, with the model's numbers put in, as one linear `Row`.

Each sub-expression evaluates to a linear form ``Σ c_k u_k + c_0`` over the unknowns
(accelerations, reaction labels) carrying, per coefficient, two magnitudes:

- ``err``: first-order bound of the rounding error, in units of the tolerance: a
  number written in the equation counts with its magnitude, a name of the vocabulary
  (``m``, ``I_2``, ``w_3``...) with none, since it is exact;
- ``mag``: the magnitude of every term that made the coefficient, exact or not, so that
  ``cos(pi/2)`` (6e-17 in floating point) is seen to be zero.

A product of two forms that both hold unknowns, a division by one, or a function of one
is not a Newton-Euler equation: `NotLinear` says where.

Every number stays a finite double: an operation whose result (or the magnitudes that
go with it) goes beyond ±1.8e308, or a product of nonzero numbers that falls below the
smallest normal double (2.2e-308, where digits are lost and then everything is 0), is
refused at its operator with an `EquationError`, never carried on as inf, nan or a term
that silently vanished. A long sum is evaluated in a loop (`left_spine`).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field

from mbody.answers.compare import CONST, Row
from mbody.answers.parse import EquationError, Node, ParsedEquation
from mbody.answers.text import num as _num
from mbody.answers.vocabulary import Vocabulary
from mbody.model.expressions import left_spine

_WHAT = {"+": "this sum", "-": "this difference", "*": "this product", "/": "this quotient",
         "^": "this power", "exp": "exp( )", "tan": "tan( )", "sqrt": "sqrt( )",
         "sin": "sin( )", "cos": "cos( )", "=": "the two sides"}


class NotLinear(Exception):
    """The equation is not linear in the unknowns; `position` is where, `why` what."""

    def __init__(self, position: int, why: str):
        super().__init__(why)
        self.position, self.why = position, why


@dataclass
class _Form:
    value: dict[str, float] = field(default_factory=dict)  # CONST for the constant
    err: dict[str, float] = field(default_factory=dict)
    mag: dict[str, float] = field(default_factory=dict)

    @property
    def constant(self) -> bool:
        return all(k == CONST for k in self.value)

    @property
    def c(self) -> float:
        return self.value.get(CONST, 0.0)

    @staticmethod
    def number(v: float, exact: bool) -> _Form:
        return _Form({CONST: v}, {CONST: 0.0 if exact else abs(v)}, {CONST: abs(v)})

    def add(self, other: _Form, sign: float) -> _Form:
        out = _Form(dict(self.value), dict(self.err), dict(self.mag))
        for k, v in other.value.items():
            out.value[k] = out.value.get(k, 0.0) + sign * v
            out.err[k] = out.err.get(k, 0.0) + other.err[k]
            out.mag[k] = out.mag.get(k, 0.0) + other.mag[k]
        return out

    def times(self, a: float, a_err: float, a_mag: float) -> _Form:
        """self · a for a constant a (with its own error and magnitude)."""
        return _Form({k: v * a for k, v in self.value.items()},
                     {k: abs(v) * a_err + abs(a) * self.err[k] for k, v in self.value.items()},
                     {k: self.mag[k] * a_mag for k in self.value})


def linear_row(eq: ParsedEquation, vocab: Vocabulary) -> Row:
    """``lhs − rhs`` of `eq` as a `Row` over the body's unknowns.

    Parameters
    ----------
    eq : ParsedEquation
        The parsed equation.
    vocab : Vocabulary
        The body's names.

    Returns
    -------
    Row
        The coefficients (rounding noise zeroed) and their error scales.

    Raises
    ------
    EquationError
        A name outside the vocabulary (with a did-you-mean), or a number that cannot be
        computed (division by zero, square root of a negative number).
    NotLinear
        The equation multiplies, divides or takes a function of an unknown.
    """
    text = eq.text
    form = _checked(_eval(eq.lhs, vocab, text).add(_eval(eq.rhs, vocab, text), -1.0),
                    "=", eq.equals, text)
    # the constant's key is kept only when a number was written (even one that cancels,
    # m*g - m*g): "no number at all" is not "a reaction replaced by a number"
    keys = [k for k in form.value if k != CONST or form.mag[k] > 0.0]
    row = Row({k: form.value[k] for k in keys}, {k: form.err[k] for k in keys})
    return row.cleaned(form.mag)


def _eval(node: Node, vocab: Vocabulary, text: str) -> _Form:
    node, spine = left_spine(node)
    form = _leaf(node, vocab, text)
    for op in reversed(spine):
        form = _binary(op[0], form, _eval(op[2], vocab, text), op[3], text)
    return form


def _leaf(node: Node, vocab: Vocabulary, text: str) -> _Form:
    kind = node[0]
    if kind == "num":
        return _Form.number(float(node[1]), exact=False)
    if kind == "name":
        try:
            name = vocab.resolve(node[1])
        except KeyError as exc:
            raise EquationError(text, node[2], str(exc.args[0])) from None
        if name in vocab.values:
            return _Form.number(vocab.values[name], exact=True)
        return _Form({name: 1.0}, {name: 0.0}, {name: 1.0})
    if kind == "neg":
        inner = _eval(node[1], vocab, text)
        return _Form({k: -v for k, v in inner.value.items()}, inner.err, inner.mag)
    if kind == "call":
        arg = _eval(node[2], vocab, text)
        if not arg.constant:
            raise NotLinear(node[3], f"{node[1]}( ) of an unknown ({_names(arg)})")
        return _checked(_call(node[1], arg, text, node[3]), node[1], node[3], text)
    return _binary(kind, _eval(node[1], vocab, text), _eval(node[2], vocab, text), node[3],
                   text)


def _binary(kind: str, a: _Form, b: _Form, pos: int, text: str) -> _Form:
    """a (kind) b, checked: finite, and no product or quotient of nonzero numbers lost
    below the smallest normal double."""
    out = _operate(kind, a, b, pos, text)
    _checked(out, kind, pos, text)
    if kind in "*/^" and _lost(kind, a, b, out):
        raise EquationError(text, pos, f"{_WHAT[kind]} is too small to compute: below "
                            "2.2e-308, the smallest double (nonzero numbers would become "
                            "0)", "multiply both sides by a power of ten")
    return out


def _lost(kind: str, a: _Form, b: _Form, out: _Form) -> bool:
    """Whether a product, quotient or power of nonzero numbers fell below the smallest
    normal double (to 0, or to a subnormal that has lost its digits), in any term."""
    if kind == "^":
        return a.c != 0.0 and abs(out.c) < sys.float_info.min
    form, factor = (b, a.c) if kind == "*" and a.constant else (a, b.c)
    return factor != 0.0 and any(form.value.get(k, 0.0) != 0.0 and abs(v) < sys.float_info.min
                                 for k, v in out.value.items())


def _checked(form: _Form, kind: str, pos: int, text: str) -> _Form:
    for table in (form.value, form.err, form.mag):
        for v in table.values():
            if not math.isfinite(v):
                raise EquationError(text, pos, f"the numbers in {_WHAT[kind]} go beyond "
                                    "±1.8e308, the largest double",
                                    "divide both sides by a power of ten")
    return form


def _operate(kind: str, a: _Form, b: _Form, pos: int, text: str) -> _Form:
    if kind == "+":
        return a.add(b, 1.0)
    if kind == "-":
        return a.add(b, -1.0)
    if kind == "*":
        if a.constant:
            return b.times(a.c, a.err.get(CONST, 0.0), a.mag.get(CONST, 0.0))
        if b.constant:
            return a.times(b.c, b.err.get(CONST, 0.0), b.mag.get(CONST, 0.0))
        raise NotLinear(pos, f"a product of unknowns ({_names(a)} times {_names(b)})")
    if kind == "/":
        if not b.constant:
            raise NotLinear(pos, f"a division by an unknown ({_names(b)})")
        d = b.c
        if d == 0.0:
            raise EquationError(text, pos, "division by zero")
        # d(a/d) = da/d − a dd/d²: the divisor's error counts relative to it
        rel = b.err.get(CONST, 0.0) / abs(d)
        return _Form({k: v / d for k, v in a.value.items()},
                     {k: a.err[k] / abs(d) + abs(v / d) * rel for k, v in a.value.items()},
                     {k: a.mag[k] / max(abs(d), b.mag.get(CONST, 0.0)) for k in a.value})
    # power
    if not b.constant:
        raise NotLinear(pos, f"a power with an unknown exponent ({_names(b)})")
    p = b.c
    if not a.constant:
        if p == 1.0:
            return a
        if p == 0.0:
            return _Form.number(1.0, exact=True)
        raise NotLinear(pos, _power_text(a, p))
    x = a.c
    shown = f"{_num(x) if x >= 0 else f'({_num(x)})'}^{_num(p)}"
    try:
        v = math.pow(x, p)
    except OverflowError:
        raise EquationError(text, pos, f"{shown} is beyond ±1.8e308, the largest double",
                            "divide both sides by a power of ten") from None
    except ValueError:  # math.pow says "math domain error"
        raise EquationError(text, pos, f"{shown} cannot be computed",
                            "a negative number to a fractional power, or 0 to a negative "
                            "one") from None
    err = abs(p * v / x) * a.err.get(CONST, 0.0) if x != 0.0 else 0.0
    if x > 0.0:
        err += abs(v * math.log(x)) * b.err.get(CONST, 0.0)
    try:
        mag = math.pow(a.mag.get(CONST, 0.0), p) if a.mag.get(CONST, 0.0) > 0.0 else abs(v)
    except OverflowError:
        mag = math.inf  # the terms it was made of are too large: `_checked` says so
    return _Form({CONST: v}, {CONST: err}, {CONST: max(abs(v), mag)})


def _call(name: str, arg: _Form, text: str, pos: int) -> _Form:
    x, ex = arg.c, arg.err.get(CONST, 0.0)
    if name == "sin":
        return _Form({CONST: math.sin(x)}, {CONST: abs(math.cos(x)) * ex}, {CONST: 1.0})
    if name == "cos":
        return _Form({CONST: math.cos(x)}, {CONST: abs(math.sin(x)) * ex}, {CONST: 1.0})
    if name == "tan":
        c = math.cos(x)
        if abs(c) < 1e-15:
            raise EquationError(text, pos, f"tan({x:g}) is infinite")
        return _Form({CONST: math.tan(x)}, {CONST: ex / (c * c)},
                     {CONST: max(1.0, abs(math.tan(x)))})
    if name == "exp":
        try:
            v = math.exp(x)
        except OverflowError:
            raise EquationError(text, pos, f"exp({x:g}) is too large") from None
        return _Form({CONST: v}, {CONST: v * ex}, {CONST: v})
    if x < 0.0:
        raise EquationError(text, pos, f"the square root of a negative number ({x:g})")
    v = math.sqrt(x)
    return _Form({CONST: v}, {CONST: ex / (2 * v) if v > 0 else 0.0},
                 {CONST: math.sqrt(arg.mag.get(CONST, 0.0))})


def _power_text(base: _Form, p: float) -> str:
    """What a power of unknowns is, in words: "a_x squared", "(a_x, O.Fx) cubed"."""
    power = {2.0: "squared", 3.0: "cubed"}.get(p, f"to the power {_num(p)}")
    unknowns = [k for k in base.value if k != CONST]
    return f"{unknowns[0]} {power}" if len(unknowns) == 1 else \
        f"a sum of unknowns ({_names(base)}) {power}"


def _names(form: _Form) -> str:
    return ", ".join(sorted(k for k in form.value if k != CONST)) or "a number"

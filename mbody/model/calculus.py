"""Time derivatives of expressions of t (`mbody.model.expressions`), exactly, as trees.

A driver prescribes a joint coordinate q = f(t); the constraint it adds needs f (position
level), f′ (velocity level: Gᵀv = f′) and f″ (acceleration level: γ + f″). They are built
here by the usual rules on the parsed tree, with the constant sub-trees folded, so a law
such as ``0.4 + 0.2*sin(t)`` gives ``0.2*cos(t)`` and ``-0.2*sin(t)``, and the compiled
core evaluates all three as programs (`Expression.program`).

Rules (u, v sub-trees, c a number): (u ± v)′ = u′ ± v′; (u v)′ = u′ v + u v′;
(u / v)′ = (u′ v − u v′) / v²; (u^c)′ = c u^(c−1) u′; (u^v)′ = u^v (v′ log u + v u′ / u);
sin′ = cos, cos′ = −sin, tan′ = 1 + tan², exp′ = exp, log′ = 1 / u, sqrt′ = 1 / (2 sqrt),
abs′ = u / |u| (undefined at 0, where a law with |·| has a kink).
"""

from __future__ import annotations

from mbody.model.expressions import Expression, Node

ZERO: Node = ("num", 0.0)
ONE: Node = ("num", 1.0)


def derivative(e: Expression) -> Expression:
    """The expression of df/dt for f = `e` (text: ``d/dt(<text>)``)."""
    return Expression(f"d/dt({e.text})", _d(e.tree))


def _num(node: Node) -> float | None:
    return float(node[1]) if node[0] == "num" else None


def _add(a: Node, b: Node) -> Node:
    x, y = _num(a), _num(b)
    if x == 0.0:
        return b
    if y == 0.0:
        return a
    if x is not None and y is not None:
        return ("num", x + y)
    return ("+", a, b)


def _sub(a: Node, b: Node) -> Node:
    x, y = _num(a), _num(b)
    if y == 0.0:
        return a
    if x == 0.0:
        return _neg(b)
    if x is not None and y is not None:
        return ("num", x - y)
    return ("-", a, b)


def _neg(a: Node) -> Node:
    x = _num(a)
    if x is not None:
        return ("num", -x)
    if a[0] == "neg":
        return a[1]
    return ("neg", a)


def _mul(a: Node, b: Node) -> Node:
    x, y = _num(a), _num(b)
    if x == 0.0 or y == 0.0:
        return ZERO
    if x == 1.0:
        return b
    if y == 1.0:
        return a
    if x is not None and y is not None:
        return ("num", x * y)
    return ("*", a, b)


def _div(a: Node, b: Node) -> Node:
    x, y = _num(a), _num(b)
    if x == 0.0:
        return ZERO
    if y == 1.0:
        return a
    return ("/", a, b)


def _pow(a: Node, b: Node) -> Node:
    y = _num(b)
    if y == 1.0:
        return a
    if y == 0.0:
        return ONE
    return ("^", a, b)


def _call(name: str, a: Node) -> Node:
    return ("call", name, a)


def _d(node: Node) -> Node:
    kind = node[0]
    if kind == "num":
        return ZERO
    if kind == "t":
        return ONE
    if kind == "neg":
        return _neg(_d(node[1]))
    if kind == "call":
        name, u = node[1], node[2]
        du = _d(u)
        if _num(du) == 0.0:
            return ZERO
        outer = {
            "sin": lambda: _call("cos", u),
            "cos": lambda: _neg(_call("sin", u)),
            "tan": lambda: _add(ONE, _pow(_call("tan", u), ("num", 2.0))),
            "exp": lambda: _call("exp", u),
            "log": lambda: _div(ONE, u),
            "sqrt": lambda: _div(ONE, _mul(("num", 2.0), _call("sqrt", u))),
            "abs": lambda: _div(u, _call("abs", u)),
        }[name]()
        return _mul(outer, du)
    a, b = node[1], node[2]
    da, db = _d(a), _d(b)
    if kind == "+":
        return _add(da, db)
    if kind == "-":
        return _sub(da, db)
    if kind == "*":
        return _add(_mul(da, b), _mul(a, db))
    if kind == "/":
        return _div(_sub(_mul(da, b), _mul(a, db)), _pow(b, ("num", 2.0)))
    # a ^ b
    c = _num(b)
    if c is not None:  # c a^(c-1) a'
        return _mul(_mul(b, _pow(a, ("num", c - 1.0))), da)
    return _mul(node, _add(_mul(db, _call("log", a)), _div(_mul(b, da), a)))

"""The public functions' arguments, checked where they come in: a model, a state, known
reaction values, numbers.

What a notebook user hands over is checked once, at the public function that takes it
(`mbody.assemble`, `mbody.simulate`, `mbody.linearize`...), and refused with an
`MbodyError` that names the argument and says what it takes; a wrong type is an
`MbodyTypeError` (also a `TypeError`). Past that point the numeric code trusts it: a
state of another model's size would otherwise fail deep in the compiled core, a NaN would
come back as NaN accelerations without a word.

The checks cost next to nothing on the hot paths: nothing for a model's own initial
state (the default of every function), about a microsecond for another state of a few
bodies (its values' finiteness), a few for a large one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from numbers import Real
from typing import Any

import numpy as np

from mbody import joint_types
from mbody.errors import MbodyError, MbodyTypeError, did_you_mean, option_entry
from mbody.model.checks import number_hint, si_quantity
from mbody.model.expressions import Expression, ExpressionError, compile_expression
from mbody.model.model import Model, State
from mbody.model.reprs import count, name_list

__all__ = ["KnownValues", "checked_model", "checked_state", "known_at", "known_values"]

KnownValues = Mapping[str, "float | str | Expression"]
"""Known reaction values as the API takes them: label -> number, or expression of t as
text (or compiled, as `known_values` returns them)."""


def checked_model(model: Any, argument: str = "model") -> Model:
    """`model` when it is a `Model`; else an `MbodyTypeError` saying how to get one (a
    path: ``mbody.load(path)``)."""
    if isinstance(model, Model):
        return model
    got = f"{type(model).__name__} {model!r}" if isinstance(model, str) else \
        type(model).__name__
    hint = (f"; read the file first: mbody.load({str(model)!r})"
            if isinstance(model, str) or hasattr(model, "__fspath__") else
            "; mbody.load takes a dict of a model file's content too"
            if isinstance(model, Mapping) else "")
    raise MbodyTypeError(f"{argument} must be a Model (from mbody.load), got {got}{hint}")


STATE_SOURCES = ("model.initial or its .replace(...), mbody.State(...), "
                 "mbody.State.planar(...), run.state(k) of a Trajectory")
"""Where a `State` comes from, for the message of an argument that is not one."""


def checked_state(model: Model, state: Any, argument: str) -> State:
    """`state` when it is a `State` of `model`'s bodies with finite values and
    quaternions that are not 0; else an `MbodyError` naming `argument` (an
    `MbodyTypeError` when it is not a `State`). ``model.initial`` passes at once."""
    if state is model.initial:
        return state
    if not isinstance(state, State):
        hint = ("; for the state at given joint coordinates ({'O.angle': 0.1}) use "
                "mbody.solve.configure.configure(model, {...})"
                if isinstance(state, Mapping) else "")
        raise MbodyTypeError(f"{argument} must be a State ({STATE_SOURCES}), got "
                             f"{type(state).__name__}" + hint)
    n = state.position.shape[0]  # State itself checked that its arrays agree on n
    if n != model.n:
        raise MbodyError(f"{argument} has {count(n, 'body', 'bodies')}, model "
                         f"{model.name!r} has {model.n} ({name_list(model.body_names)}): "
                         "a state of another model?")
    problem = _problem(state)
    if problem is not None:
        name, body, what = problem
        raise MbodyError(f"{argument}.{name} of body {model.body_names[body]!r} is {what}")
    return state


SMALL = 8
"""Bodies up to which a state's values are looked at as Python floats: a few numpy calls
cost more than that (about 1 µs for one body, against 4 µs)."""


def _problem(state: State) -> tuple[str, int, str] | None:
    """(array, body index, what is wrong) of the first value that is not finite or
    quaternion that is 0, or None. One sum (or dot product) finds that all is well; only
    then are the arrays looked at one by one (a sum of finite values may overflow)."""
    q = state.quaternion
    if len(q) <= SMALL:
        rows = q.tolist()
        fine = math.isfinite(sum(state.position.ravel().tolist())
                             + sum(state.velocity.ravel().tolist())
                             + sum(state.omega.ravel().tolist()) + sum(map(sum, rows))
                             ) and all(map(any, rows))
    else:
        y = np.concatenate((state.position.ravel(), q.ravel(), state.velocity.ravel(),
                            state.omega.ravel()))
        fine = math.isfinite(y @ y) and bool(q.any(axis=1).all())
    if fine:
        return None
    for name in ("position", "quaternion", "velocity", "omega"):
        a = getattr(state, name)
        bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
        if len(bad):
            return name, int(bad[0]), f"{a[bad[0]].tolist()}: not finite"
    zero = np.flatnonzero(~state.quaternion.any(axis=1))
    if len(zero):
        return "quaternion", int(zero[0]), "0, not a rotation (a unit quaternion [w, x, y, z])"
    return None


def known_values(model: Model, known: Any, *, expressions: bool = True,
                 argument: str = "known") -> dict[str, float | Expression]:
    """The reaction values `known` (label -> number, or expression of t as text) checked:
    a mapping, each label a reaction component of `model` (with a did-you-mean), each
    value a finite number or an expression (compiled here: a constant one becomes its
    number, one that is not finite refused); `expressions` False: numbers only.

    Returns label -> float or `Expression` (those of t), in `known`'s order. A message
    names a value as the surface it came from spells it (`mbody.errors.option_entry`):
    ``known['A.Fx']`` in Python, ``--known A.Fx`` on the command line.
    """
    if not isinstance(known, Mapping):
        raise MbodyTypeError(f"{argument} must be a mapping of reaction label -> number"
                             + (" or expression of t" if expressions else "")
                             + f" ({{'O.Fx': 1.0}}), got {type(known).__name__}")
    out: dict[str, float | Expression] = {}
    labels = model.reaction_index
    for label, v in known.items():
        if label not in labels:
            hint = did_you_mean(str(label), model.reactions)
            raise MbodyError(f"no reaction component {label!r} in this model"
                             + (f"; {hint}" if hint else
                                " (it has none)" if not model.reactions else ""))
        if isinstance(v, str) and expressions:
            try:
                v = compile_expression(v)
            except ExpressionError as exc:
                refused = known_unit_refused(label, v)
                if refused is not None:
                    raise MbodyError(
                        f"{option_entry(argument, label)}: expected a number in "
                        f"{known_unit(label)}" + (" or an expression of t" if expressions
                                                  else "")
                        + f", got {v!r} ({refused[0]})") from None
                raise MbodyError(f"{option_entry(argument, label)}: {exc}") from None
        if isinstance(v, Expression):
            if v.constant:
                v = v.value
            else:
                out[label] = v
                continue
        elif isinstance(v, bool) or not isinstance(v, Real):
            got = f"{type(v).__name__} {v!r}" if isinstance(v, str | bool) else \
                type(v).__name__ + (f" of shape {v.shape}" if isinstance(v, np.ndarray)
                                    else "")
            raise MbodyTypeError(
                f"{option_entry(argument, label)} must be a number (N or N m)"
                + (" or an expression of t as text ('2*t')" if expressions else "")
                + f", got {got}")
        value = float(v)
        if not math.isfinite(value):
            raise MbodyError(f"{option_entry(argument, label)} must be a finite number "
                             f"(N or N m), got {value!r}")
        out[label] = value
    return out


def known_unit(label: str) -> str:
    """The unit of a known reaction value by its label: N for a force, N m for a moment
    (``O.Mz``, ``motor.M``); 'N or N m' for a label that names no component."""
    try:
        return joint_types.unit(label)
    except KeyError:
        return "N or N m"


def known_unit_refused(label: str, text: str) -> tuple[str, str | None] | None:
    """What to write for a known value `text` given with a unit (``'3 N'``, ``'3N'``,
    ``'2 kN*m'``): `mbody.model.checks.number_hint`'s advice for the label's unit, and the
    number in it (``'3'``, ``'2000'``) when the unit converts to it; None when `text` is
    not a number with a unit mbody knows (a misspelt expression keeps its own message)."""
    plain = text.replace("*", " ")
    si = si_quantity(plain)
    if si is None:
        return None
    unit = known_unit(label)
    meant = f"{si[0]:.6g}" if si[1] == unit else None
    return number_hint(plain, unit if unit in ("N", "N m") else None), meant


def known_at(model: Model, known: Any, t: float, argument: str = "known") -> dict[str, float]:
    """The model's known reaction values at time `t` (s), updated with `known` checked as
    `known_values` says, its expressions of t taken at `t` (a value that is not finite
    there refused): what one state's solve applies."""
    values = model.known_reactions_at(t)
    for label, v in known_values(model, known, argument=argument).items():
        if isinstance(v, Expression):
            x = float(v(t))
            if not math.isfinite(x):
                raise MbodyError(f"{option_entry(argument, label)} = {v.text!r} is not finite "
                                 f"at the state's t = {t:g} s ({x})")
            v = x
        values[label] = v
    return values

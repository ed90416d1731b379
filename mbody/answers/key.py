"""The answer key: a model's Newton-Euler rows written as an answers file.

    text = answer_key(model)              # what ``mbody assemble MODEL --answers-key
                                          # key.yaml`` writes

Every row of every body (or of the bodies named), at the model's state, one entry each,
the row's label as the entry's ``note``. The numbers are written to `DIGITS` significant
figures (their relative rounding, at most 5e-13, is far below any tolerance a grader
uses), so `mbody.answers.verify.verify` finds every equation of the key correct, at its
default tolerance and at 1e-9 alike, and the key covers every row of the model:
an instructor checks the grader with it before giving out an assignment, and gives it
out afterwards as the solution. A model with values set (`mbody.Model.with_values`,
``--set``) writes them in the key's ``set:``, so the key is the answer of that variant
whichever way the model is given to the grader.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

from mbody.answers.compare import CONST
from mbody.answers.rows import body_rows
from mbody.equations.assemble import assemble
from mbody.errors import MbodyError, not_found
from mbody.model.model import Model, State
from mbody.model.values import plain

DIGITS = 12
"""Significant figures of the key's numbers."""
STUDENT = "answer key"
"""The key's ``student`` line (a class's summary shows it as the row's student)."""


def answer_key(model: Model, *, bodies: Sequence[str] | None = None,
               state: State | None = None) -> str:
    """The answers file that gives every Newton-Euler row of `model` (module doc).

    Parameters
    ----------
    model : Model
        The model.
    bodies : sequence of str, optional
        Only these bodies' rows (default: every body, in the model's order).
    state : State, optional
        The state the rows are taken at (default: the model's initial state, as `verify`
        checks at).

    Returns
    -------
    str
        YAML text: a comment saying what it is, ``student``, ``set`` (the model's values
        set since it was read, if any) and ``equations``.

    Raises
    ------
    MbodyError
        A body that is not the model's (with a did-you-mean).
    """
    names = list(model.body_names if bodies is None else bodies)
    for b in names:
        if b not in model.index:  # an argument, not a lookup: MbodyError, in lookups' words
            raise MbodyError(not_found("body named", b, model.body_names, "bodies").args[0])
    asm = assemble(model, state)
    where = f" ({model.file})" if model.file else ""
    which = "every body" if bodies is None else \
        f"the bod{'y' if len(names) == 1 else 'ies'} {', '.join(names)}"
    lines = [f"# Answer key of model '{model.name}'{where}:",
             f"# every Newton-Euler row of {which}, at the model's state",
             f"# (mbody assemble --answers-key, numbers to {DIGITS} significant figures).",
             "# mbody verify MODEL THIS_FILE finds every equation correct.",
             f"student: {STUDENT}"]
    values = model.source.values if model.source is not None else ()
    if values:
        lines.append("set:")
        lines += [f"  {json.dumps(path)}: {json.dumps(plain(v), ensure_ascii=False)}"
                  for path, v in values]
    lines.append("equations:")
    for b in names:
        for r in body_rows(asm, b).rows:
            eq = json.dumps(row_equation(r.row.coef))
            lines.append(f"  - {{body: {json.dumps(b)}, eq: {eq}, note: {json.dumps(r.label)}}}")
    return "\n".join(lines) + "\n"


def row_equation(coef: dict[str, float]) -> str:
    """A row ``Σ c u + c0 = 0`` as an equation an answers file holds:
    accelerations on the left, the constant and the reactions on the right.

    Parameters
    ----------
    coef : dict
        Name -> coefficient; `CONST` the constant.

    Returns
    -------
    str
        ``0.167083333333*alpha = -0.433012701892*O.Fx - 0.25*O.Fy`` (numbers to
        `DIGITS` significant figures).
    """
    left = _sum([(c, k) for k, c in coef.items() if k != CONST and "." not in k])
    right = _sum([(-coef.get(CONST, 0.0), "")]
                 + [(-c, k) for k, c in coef.items() if k != CONST and "." in k])
    return f"{left} = {right}"


def _sum(terms: list[tuple[float, str]]) -> str:
    """``[(2.0, "a_x"), (-1.0, "O.Fx"), (19.62, "")]`` -> ``2*a_x - O.Fx + 19.62``."""
    out = ""
    for c, name in terms:
        mag = f"{abs(float(c)):.{DIGITS}g}"
        if float(mag) == 0.0:
            continue
        text = mag if not name else name if mag == "1" else f"{mag}*{name}"
        if not out:
            out = f"-{text}" if c < 0 else text
        else:
            out += f" {'-' if c < 0 else '+'} {text}"
    return out or "0"

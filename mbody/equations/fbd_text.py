"""A body's free body and Newton-Euler pair as text: the block `mbody assemble` prints and
``print(asm.bodies[name])`` writes (`BodyEquations.__str__`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.conventions import REACTION
from mbody.util.formatting import LENGTH_RTOL, NOISE
from mbody.util.formatting import num as _n
from mbody.util.formatting import table as _table
from mbody.util.formatting import vec as _v

if TYPE_CHECKING:
    from mbody.equations.fbd import BodyEquations, ForceOnBody

def force_cells(fo: ForceOnBody, dimension: int, minus: str = "-", size: float = 0.0
                ) -> list[str]:
    """One free-body row as the picture draws it: name, point, components with unit,
    moment about G.

    A reaction on the joint's parent (-R) is named ``-A.Fx`` (with `minus`) and listed
    with the unit vector and moment its arrow carries, along the +axis: the name times
    the row is what the body's equations hold (``- A.Fx`` in Newton's rows). A known
    reaction shows the value of what acts on this body (``-A.Fx = -98.1``) and the
    actual force. A planar couple is a scalar about z.

    Parameters
    ----------
    fo : ForceOnBody
    dimension : int
        2 (planar) or 3 (spatial).
    minus : str
        The minus of a parent-side name: ``-`` in text, ``−`` (U+2212) in HTML, as drawn.
    size : float
        The body's size (m, `FreeBodyDiagram.size`): a point's coordinate below
        `LENGTH_RTOL` of it prints as 0 (the file's rounding, not a dimension).

    Returns
    -------
    list of str
        ``[name, point (body axes), components and unit (world axes), moment about G]``.
    """
    unit = "N m" if fo.couple else "N"
    vec, mom = np.asarray(fo.W_vector, dtype=float), np.asarray(fo.B_moment, dtype=float)
    name = fo.name
    if fo.kind == REACTION:
        name = fo.label if fo.side > 0 else minus + fo.label
        if fo.value is None:  # per unit of what the name says: the arrow's +axis
            vec, mom = fo.side * vec, fo.side * mom
        else:
            name += f" = {_n(fo.side * fo.value)}"
    comp = _n(vec[2]) if fo.couple and dimension == cv.PLANAR else _v(vec, dimension)
    if fo.unknown:
        comp = "unit " + comp
    point = "-" if fo.couple else _v(fo.B_r, dimension, max(NOISE, LENGTH_RTOL * size))
    moment = _n(mom[2]) if dimension == cv.PLANAR else _v(mom, 3)
    return [name, point, f"{comp} {unit}", moment]


def body_text(eq: BodyEquations, dimension: int) -> str:
    f = eq.fbd
    out = [f"== {eq.body} ==  m {_n(f.mass)} kg, mass centre at {_v(f.W_position, dimension)} m"]
    out.append("free body:")
    rows = []
    for fo in f.forces:
        name, point, comp, mom = force_cells(fo, dimension, size=f.size)
        label = "reaction" if fo.kind == REACTION else "couple" if fo.couple else fo.kind
        rows.append([name, label, point, comp, mom])
    if f.forces:
        out += _table(["force", "kind", "point (body axes, m)", "components (world axes)",
                       "moment about G" + (" (N m)" if dimension == cv.PLANAR
                                           else " (body axes, N m)")], rows)
    if not f.forces:
        out.append("  (no forces)")
    out.append("Newton (world axes):")
    out += [f"  {e}" for e in eq.newton]
    if not eq.euler:  # a particle: translation only
        out.append("Euler: none (a particle has no rotation)")
        return "\n".join(out)
    out.append("Euler (about the mass centre, " + ("z):" if dimension == 2 else "body axes):"))
    out += [f"  {e}" for e in eq.euler]
    return "\n".join(out)

"""Each body's Newton-Euler pair written with symbols, as a student derives it:

    m a_x = Σ F_x                                   (Newton, world axes)
    I_1 α_1 = (I_2 − I_3) ω_2 ω_3 + Σ M_1          (Euler, body axes: J α = −ω × Jω + M_G)

The symbols are the physics: the body's mass ``m`` and inertia (``I_G``; ``I_1, I_2,
I_3`` when the tensor is diagonal in body axes; its entries ``I_11, I_12, ...``
otherwise), ``g``, the angular velocity ``w`` / ``w_1, w_2, w_3``, each applied load by
name (``F_push_x``, ``M_motor_1``, a spring's tension ``T_k1``) and each reaction by its
label (``O.Fx``). Geometry stays numbers: lever arms, directions and the rotation from
body to world axes are taken at the assembly's state, so substituting the model's values
gives back that assembly's M, b, Q and G rows (`SymbolicBody.evaluate`).

Rows are written ``M v̇ = −b + Q + G λ``: the stacked contract's ``M v̇ + b = Q + G λ``
with the gyroscopic term moved to the right, first, where the course writes it.

Modules, each with one job: `terms` (what a term is part of, the axis suffixes, `Term`),
`rows` (the rows, a body's pair and every body's, as data), `build` (the rows made from
an assembly), `applied` (the applied-load symbols and their values, which
`mbody.answers` uses without sympy) and `printing` (text and LaTeX).

sympy is imported only when equations are made (it takes a few hundred ms to load), so
this package costs `import mbody` and the numeric commands nothing.
"""

from mbody.equations.symbolic.applied import LoadSymbol, load_symbols
from mbody.equations.symbolic.build import NOISE, assembly_symbolic, body_symbolic
from mbody.equations.symbolic.printing import latex_symbol, latex_text
from mbody.equations.symbolic.rows import (
    RowValues,
    SymbolicBody,
    SymbolicEquations,
    SymbolicRow,
)
from mbody.equations.symbolic.terms import (
    APPLIED,
    BODY_AXES,
    GRAVITY,
    GYROSCOPIC,
    INERTIA,
    REACTION,
    WORLD_AXES,
    Term,
)

__all__ = ["APPLIED", "BODY_AXES", "GRAVITY", "GYROSCOPIC", "INERTIA", "NOISE", "REACTION",
           "WORLD_AXES", "LoadSymbol", "RowValues", "SymbolicBody", "SymbolicEquations",
           "SymbolicRow", "Term", "assembly_symbolic", "body_symbolic", "latex_symbol",
           "latex_text", "load_symbols"]

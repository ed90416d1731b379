"""Joint constraints at position and acceleration level, one per reaction component.

Gᵀ is the velocity-level constraint Jacobian: ``Gᵀ v = φ̇`` (see `joints`). The other two
levels, written once in the compiled core's constraint primitives (`mbody.kernel`,
kernel.h: one per kind of component) and read here from its columns:

- ``phi(model, state)``: position errors φ (0 when the joint holds).
  force along e (parent-fixed joint axis): φ = e · (P_c − P_p), P_c and P_p the joint
  point carried by the child and by the parent;
  moment, revolute/cylindrical (Mx, My): the tilt of the child's joint z axis seen in
  the parent's joint frame, φ_x = −z_rel,y, φ_y = z_rel,x;
  moment, fixed/prismatic: the small-rotation vector of R_rel = E_pᵀ E_c,
  φ = ½ vee(R_rel − R_relᵀ); universal Mt: φ = −a · b (a on the parent, b on the child);
  a driven coordinate: its value minus the law's, f(t).
- ``gamma(model, state)``: γ = −Ġᵀ v, the velocity-product terms, so that the joints
  hold at acceleration level when ``Gᵀ v̇ = γ`` (plus a law's f̈ for a driven one). With
  w = e · (V_c(P) − V_p(P)):
  force:  γ = −[(ω_p × e) · (V_c(P) − V_p(P)) + e · (ω_c × (ω_c × ρ_c) − ω_p × ṡ)],
          ρ_c = P − x_c, s = P − x_p, ṡ = v_c + ω_c × ρ_c − v_p;
  moment: γ = −(ω_p × e) · (ω_c − ω_p);
  universal: γ = −ė · (ω_c − ω_p), ė = (ω_p × a) × b + a × (ω_c × b).
  All vectors in world axes; ω_p, v_p are 0 for ground.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

# `joint_errors` and `JOINT_TOL` live in `joints` (a simulation checks its start without
# this module's ConstraintJacobian); imported here too, for their old path
from mbody.equations.joints import JOINT_TOL as JOINT_TOL
from mbody.equations.joints import ReactionColumns, reaction_columns
from mbody.equations.joints import joint_errors as joint_errors
from mbody.errors import not_found
from mbody.model.model import Model, State
from mbody.util.frozen import Frozen, dataclass_on_first_look

if TYPE_CHECKING:
    import scipy.sparse as sp


def phi(model: Model, state: State, R: np.ndarray | None = None,
        cols: ReactionColumns | None = None) -> np.ndarray:
    """(m,) position errors of every reaction component's constraint (see module doc)."""
    return (reaction_columns(model, state) if cols is None else cols).phi


def gamma(model: Model, state: State, cols: ReactionColumns,
          R: np.ndarray | None = None) -> np.ndarray:
    """(m,) γ = −Ġᵀ v: the right-hand side of Gᵀ v̇ = γ (see module doc), from `cols`
    (the columns at `state`)."""
    return cols.gamma


@dataclass_on_first_look(eq=False, init=False, repr=False)  # no ==: its fields are arrays; Frozen
class ConstraintJacobian(Frozen):
    """The velocity-level constraint Jacobian of the joints, Φ_v = Gᵀ, with labels.

    matrix: (m, N) sparse; row k is the constraint that reaction component `rows[k]`
    enforces, column i the coordinate `columns[i]` (rows of the stacked equations:
    Newton in world axes, Euler in body axes). ``matrix @ v`` is the relative velocity
    each joint forbids; ``matrix @ v̇ = gamma`` holds for motions that keep the joints;
    `phi` are the position errors (0 when the joints are assembled).
    """

    matrix: sp.csr_matrix
    rows: list[str]
    columns: list[str]
    gamma: np.ndarray
    phi: np.ndarray

    def __init__(self, matrix: sp.csr_matrix, rows: list[str], columns: list[str],
                 gamma: np.ndarray, phi: np.ndarray) -> None:
        # the dataclass's own __init__, written out: the generated one is compiled from
        # its source when the class is made, at every simulate's import (frozen: the
        # fields go into __dict__ directly, as object.__setattr__ would put them)
        self.__dict__.update({"matrix": matrix, "rows": rows, "columns": columns,
                              "gamma": gamma, "phi": phi})

    @property
    def shape(self) -> tuple[int, int]:
        return self.matrix.shape

    def toarray(self) -> np.ndarray:
        return self.matrix.toarray()

    def row(self, label: str) -> dict[str, float]:
        """The nonzero entries of one constraint row, by coordinate label.

        Parameters
        ----------
        label : str
            The row's reaction component (``A.Fx``: `rows`).

        Raises
        ------
        KeyError
            No such row (with a did-you-mean, or the rows there are).
        """
        try:
            i = self.rows.index(label)
        except ValueError:
            raise not_found("constraint row", label, self.rows,
                            "rows, one per reaction component") from None
        r = self.matrix.getrow(i).tocoo()
        return {self.columns[j]: float(v) for j, v in zip(r.col, r.data, strict=True)}

    def __repr__(self) -> str:  # the dataclass's would print every label and the matrix
        m, n = self.matrix.shape
        worst = float(np.abs(self.phi).max()) if self.phi.size else 0.0
        return (f"<ConstraintJacobian G^T: {m} constraints x {n} coordinates, "
                f"{self.matrix.nnz} nonzero, max |phi| {worst:.3g}; .row(label), "
                f".toarray(), .rows, .columns>")

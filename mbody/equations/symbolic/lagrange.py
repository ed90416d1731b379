"""Lagrange's equations of a planar tree in symbols: ``M(q) q'' = f(q, q')``.

    sym = mbody.assemble(model).generalized().symbolic()
    print(sym)              # one equation per coordinate
    sym.M[0, 1]             # m_lower*L*a*cos(A.angle) + ...: a sympy expression

Built the way a student derives them, from the kinematics of the tree: each body's angle
is its parent's plus its joint's angle; its mass centre is the parent's joint point (plus a
slide along the joint's axis) less its own arm turned by its angle. Positions are kept as
sums of turned vectors ``s R(α) u``, so that every dot product is written at once as
``(u·v) cos(β − α) − (u × v) sin(β − α)``: the mass matrix comes out in compact
trigonometric form (``cos(A.angle)``, ``cos(q1 − q2)``), never as expanded products.
Then

    M_kl = Σ_b m_b (∂x_b/∂q_k · ∂x_b/∂q_l) + I_b (∂θ_b/∂q_k)(∂θ_b/∂q_l)
    f_k  = −Σ_lm Γ_klm q'_l q'_m + Σ F · ∂P/∂q_k      (Christoffel symbols of M)

with gravity, every applied force and couple (by the symbols `mbody assemble --symbolic`
uses: ``F_push_x``, ``M_motor``), every spring (``k_<spring>``, ``L0_<spring>``,
``c_<spring>``: its law written out) and a chosen driver's effort (``motor.M``) on its
coordinate. The bodies' masses and inertias are symbols (``m_<body>``, ``I_<body>``),
gravity is ``g``; lengths stay numbers, held exactly (as the simplest rationals within
1e-12 of the model's size: the file's 0.25 is 1/4, its rounding noise is 0) so that the
forms are exact and print in six digits.

Only planar mechanisms whose joints form a tree (closed loops have no closed-form
dependent coordinates), in the default coordinates (`mbody.equations.coordinates`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp

from mbody import conventions as cv
from mbody.equations.coordinates import CoordinateSet
from mbody.errors import MbodyError
from mbody.kernel import _core
from mbody.util.progress import Progress

if TYPE_CHECKING:
    from mbody.model.model import Model

DIGITS = 6
"""Significant digits of the numbers printed."""


class NotSymbolicError(MbodyError):
    """The model has no closed-form Lagrange equations here (not planar, a closed loop, a
    particle, known reactions, other coordinates)."""


Term = tuple[sp.Expr, sp.Expr, tuple[sp.Expr, sp.Expr]]
"""``(s, α, u)``: the vector s R(α) u (R: rotation by α about z)."""


CLEAN_RTOL = 1e-12
"""A length within this fraction of the model's size of a simpler rational is that
rational (0.24999999999999997 is 1/4; a component of 1e-17 is 0): the rounding of the
model's own arithmetic (joint points from world coordinates, frames), not geometry."""


def _exact(x: float, scale: float = 1.0) -> sp.Expr:
    """A model's number as an exact rational: the simplest within `CLEAN_RTOL` of
    `scale` (so that the forms are exact, and free of rounding noise)."""
    x = float(x)
    tol = CLEAN_RTOL * max(scale, abs(x))
    if abs(x) <= tol:
        return sp.Integer(0)
    return sp.nsimplify(x, tolerance=tol, rational=True)


def _perp(u: tuple[sp.Expr, sp.Expr]) -> tuple[sp.Expr, sp.Expr]:
    return (-u[1], u[0])


def _dot(a: list[Term], b: list[Term]) -> sp.Expr:
    """Σ s t R(α)u · R(β)v = Σ s t ((u·v) cos(β − α) − (u × v) sin(β − α))."""
    out = []
    for s, al, u in a:
        for t, be, v in b:
            c, x = u[0] * v[0] + u[1] * v[1], u[0] * v[1] - u[1] * v[0]
            d = be - al
            out.append(s * t * (c * sp.cos(d) - x * sp.sin(d)))
    return sp.expand(sp.Add(*out))


def _diff(terms: list[Term], q: sp.Symbol) -> list[Term]:
    """∂/∂q of a sum of turned vectors."""
    out: list[Term] = []
    for s, al, u in terms:
        ds, da = sp.diff(s, q), sp.diff(al, q)
        if ds != 0:
            out.append((ds, al, u))
        if da != 0:
            out.append((s * da, al, _perp(u)))
    return out


@dataclass(frozen=True, eq=False)
class SymbolicLagrange:
    """``M(q) q'' = f(q, q')`` (+ a chosen driver's effort on its row) in symbols.

    Parameters
    ----------
    model : str
        The model's name.
    coordinates : tuple of str
        The coordinates' labels.
    q, qdot, qddot : tuple of sympy.Symbol
        Named ``<label>``, ``<label>_dot``, ``<label>_ddot``.
    M : sympy.Matrix
        The generalized mass, in compact trigonometric form.
    f : sympy.Matrix
        The generalized forces: velocity terms, gravity, loads, springs (efforts apart).
    efforts : dict of str to int
        A chosen driver's effort symbol name -> the row it acts on.
    values : dict of sympy.Symbol to float
        The model's value of every parameter symbol (masses, inertias, g, loads at t = 0
        where constant, springs).
    """

    model: str
    coordinates: tuple[str, ...]
    q: tuple[sp.Symbol, ...]
    qdot: tuple[sp.Symbol, ...]
    qddot: tuple[sp.Symbol, ...]
    M: sp.Matrix
    f: sp.Matrix
    efforts: dict[str, int] = field(default_factory=dict)
    values: dict[sp.Symbol, float] = field(default_factory=dict)

    def equations(self) -> list[sp.Eq]:
        """One equation per coordinate: ``Σ_l M_kl q''_l = f_k (+ effort)``."""
        out = []
        for k in range(len(self.q)):
            lhs = sp.Add(*(self.M[k, j] * self.qddot[j] for j in range(len(self.q))))
            rhs = self.f[k] + sp.Add(*(sp.Symbol(e) for e, r in self.efforts.items() if r == k))
            out.append(sp.Eq(lhs, rhs, evaluate=False))
        return out

    def evaluate(self, q, qdot, values: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(M, f) in numbers at coordinates `q` and rates `qdot` (and the parameters'
        values, default the model's; a load that varies in time needs its value)."""
        subs = {**self.values, **(values or {})}
        subs.update(zip(self.q, map(float, q), strict=True))
        subs.update(zip(self.qdot, map(float, qdot), strict=True))
        M = np.array(self.M.xreplace(subs).evalf(), dtype=float)
        f = np.array(self.f.xreplace(subs).evalf(), dtype=float).ravel()
        return M, f

    def shown(self, expr: sp.Expr) -> sp.Expr:
        """`expr` with its exact numbers (a float's binary value: a large denominator) as
        floats of `DIGITS` digits, for printing; ½ and other small fractions stay."""
        big = {r: sp.Float(r, DIGITS) for r in expr.atoms(sp.Rational)
               if not r.is_Integer and r.q > 1000}
        return expr.xreplace(big)

    def _repr_pretty_(self, p, cycle: bool) -> None:  # IPython shows the text table
        from mbody.present.lagrange import symbolic_text  # a display hook

        p.text(symbolic_text(self))

    def _repr_latex_(self) -> str:  # a notebook shows the equations as display math
        from mbody.present.lagrange import symbolic_latex  # a display hook

        return "$$\\begin{aligned}" + symbolic_latex(self) + "\\end{aligned}$$"


def symbolic_lagrange(model: Model, cs: CoordinateSet, bar: Progress | None = None
                      ) -> SymbolicLagrange:
    """The symbolic Lagrange equations of a planar tree (module doc); `bar` shows the rows
    of M and of the velocity terms as they are made (sympy's expansions: seconds for ten
    coordinates, their cost growing as the fourth power).

    Raises
    ------
    NotSymbolicError
        Not planar, a closed loop, a particle, known reactions, or coordinates other
        than the tree's.
    """
    if model.dimension != cv.PLANAR:
        raise NotSymbolicError("symbolic Lagrange equations are written for planar models; "
                               "a spatial model's are numeric (mbody lagrange MODEL)")
    if model.has_particles:
        raise NotSymbolicError("symbolic Lagrange equations are written for rigid bodies: "
                               "this model has a particle")
    if model.known_reactions or getattr(model, "known_expressions", None):
        raise NotSymbolicError("symbolic Lagrange equations need every joint held: this "
                               "model gives some reaction values (reactions:)")
    jt = model.joint_table
    tree = set(cs.tree)
    loops = [j.name for j in model.joints if j.name not in tree]
    if loops or not cs.tree and len(model.joints):
        raise NotSymbolicError(
            f"joint(s) {', '.join(loops)} close a loop: its dependent coordinates have no "
            "closed form, so the Lagrange equations are numeric only (mbody lagrange MODEL)")
    qs = {c.label: sp.Symbol(c.label) for c in cs.items}
    by_source: dict[tuple[str, str], str] = {}
    for coord in cs.items:
        if coord.kind == _core.GQ_BODY:
            by_source[(coord.source, ("x", "y", "", "", "", "theta")[coord.axis])] = coord.label
        else:
            kind = "angle" if coord.kind == _core.GQ_TURN else "displacement"
            by_source[(coord.source, kind)] = coord.label
    n = model.n
    L = cs.length
    theta: list[sp.Expr | None] = [None] * n
    pos: list[list[Term] | None] = [None] * n
    ref = model.file_state if model.file_state is not None else model.initial
    file_angle = 2.0 * np.arctan2(ref.quaternion[:, 3], ref.quaternion[:, 0])
    for i, name in enumerate(model.body_names):  # roots: their own coordinates
        if (name, "theta") in by_source:
            theta[i] = qs[by_source[(name, "theta")]]
            pos[i] = [(qs[by_source[(name, "x")]], sp.Integer(0), (sp.Integer(1), sp.Integer(0))),
                      (qs[by_source[(name, "y")]], sp.Integer(0), (sp.Integer(0), sp.Integer(1)))]
    joints = list(model.joints)
    pending = [j for j, jj in enumerate(joints) if jj.name in tree]
    while pending:
        progressed = False
        for j in list(pending):
            p, c = int(jt.parent[j]), int(jt.child[j])
            if p >= 0 and theta[p] is None:
                continue
            joint = joints[j]
            tp = sp.Integer(0) if p < 0 else theta[p]
            assert tp is not None
            angle_label = by_source.get((joint.name, "angle"))
            if angle_label is not None:
                theta[c] = tp + qs[angle_label]
            else:
                off = file_angle[c] - (file_angle[p] if p >= 0 else 0.0)
                theta[c] = tp + _exact(off, 1.0)
            Brp = tuple(_exact(x, L) for x in jt.B_r_parent[j][:2])
            Brc = tuple(_exact(-x, L) for x in jt.B_r_child[j][:2])
            base: list[Term] = [(sp.Integer(1), tp, Brp)] if p >= 0 else \
                [(sp.Integer(1), sp.Integer(0), Brp)]
            parent_pos = pos[p] if p >= 0 else []
            assert parent_pos is not None
            terms = [*parent_pos, *base]
            slide = by_source.get((joint.name, "displacement"))
            if slide is not None:
                e = tuple(_exact(x, 1.0) for x in jt.P_E3[j][:2, 0])
                terms.append((qs[slide], tp, e))
            terms.append((sp.Integer(1), theta[c], Brc))
            pos[c] = terms
            pending.remove(j)
            progressed = True
        if not progressed:
            raise NotSymbolicError("the joints do not connect every body to the ground or a "
                                   "free body")
    if any(t is None for t in theta):
        raise NotSymbolicError("a body has no coordinates: the coordinates are not the "
                               "tree's (symbolic forms are written in the default ones)")
    thetas: list[sp.Expr] = [t for t in theta if t is not None]
    positions: list[list[Term]] = [p for p in pos if p is not None]
    q = [qs[c.label] for c in cs.items]
    qd = [sp.Symbol(f"{c.label}_dot") for c in cs.items]
    qdd = [sp.Symbol(f"{c.label}_ddot") for c in cs.items]
    k = len(q)
    values: dict[sp.Symbol, float] = {}
    mass = [sp.Symbol(f"m_{b}") for b in model.body_names]
    inertia = [sp.Symbol(f"I_{b}") for b in model.body_names]
    for i in range(n):
        values[mass[i]] = float(model.mass[i])
        values[inertia[i]] = float(model.J[i][2, 2])
    dpos = [[_diff(positions[i], qk) for qk in q] for i in range(n)]
    dth = [[sp.diff(thetas[i], qk) for qk in q] for i in range(n)]
    M = sp.zeros(k, k)
    bar = bar if bar is not None else Progress(False, "")
    bar.step(f"the mass matrix M(q) in symbols ({k} rows)", k)
    for a in range(k):
        bar.update(a)
        for b in range(a, k):
            e = sp.Add(*(mass[i] * _dot(dpos[i][a], dpos[i][b]) + inertia[i] * dth[i][a] * dth[i][b]
                         for i in range(n)))
            M[a, b] = M[b, a] = sp.expand(e)
    # velocity terms: −Σ Γ_klm q'_l q'_m
    dM = [M.diff(qm) for qm in q]
    f = [sp.Integer(0)] * k
    bar.step(f"the velocity terms in symbols ({k} rows)", k)
    for a in range(k):
        bar.update(a)
        terms = []
        for b in range(k):
            for m_ in range(k):
                gam = (dM[m_][a, b] + dM[b][a, m_] - dM[a][b, m_]) / 2
                if gam != 0:
                    terms.append(gam * qd[b] * qd[m_])
        f[a] = -sp.expand(sp.Add(*terms))
    # gravity
    gnorm = float(np.linalg.norm(model.gravity))
    if gnorm > 0:
        g = sp.Symbol("g")
        values[g] = gnorm
        ghat = tuple(_exact(x / gnorm) for x in model.gravity[:2])
        down: list[Term] = [(sp.Integer(1), sp.Integer(0), ghat)]
        for a in range(k):
            f[a] += sp.expand(g * sp.Add(*(mass[i] * _dot(down, dpos[i][a]) for i in range(n))))
    _loads(model, f, q, qd, thetas, positions, values, L)
    efforts = {label: r for label, r in cs.efforts}
    return SymbolicLagrange(model.name, tuple(cs.labels), tuple(q), tuple(qd), tuple(qdd), M,
                            sp.Matrix(f), efforts, values)


def _loads(model: Model, f: list[sp.Expr], q: list[sp.Symbol], qd: list[sp.Symbol],
           thetas: list[sp.Expr], positions: list[list[Term]],
           values: dict[sp.Symbol, float], L: float) -> None:
    """The applied forces, couples and springs' generalized forces, added to f."""
    ft, spg = model.forces, model.springs
    loads = {ld.name: ld for ld in model.loads}
    vec = ft.vector_at(0.0)
    k = len(q)
    for j, name in enumerate(ft.names):
        b = int(ft.body[j])
        load = loads[name]
        exprs = getattr(load, "expressions", {}) or {}
        if ft.couple[j]:
            M_ = sp.Symbol(f"M_{name}")
            values[M_] = float(vec[j, 2])
            for a in range(k):
                f[a] += M_ * sp.diff(thetas[b], q[a])
            continue
        comps = []
        axes = ("1", "2") if ft.in_body[j] else ("x", "y")
        for c in (0, 1):
            if vec[j, c] == 0 and c not in exprs:
                comps.append(sp.Integer(0))
                continue
            s = sp.Symbol(f"F_{name}_{axes[c]}")
            values[s] = float(vec[j, c])
            comps.append(s)
        force: list[Term] = [(sp.Integer(1), thetas[b] if ft.in_body[j] else sp.Integer(0),
                              (comps[0], comps[1]))]
        point = [*positions[b], (sp.Integer(1), thetas[b],
                                 (_exact(ft.B_r[j][0], L), _exact(ft.B_r[j][1], L)))]
        for a in range(k):
            f[a] += _dot(force, _diff(point, q[a]))
    for s in range(len(spg.names)):
        name = spg.names[s]
        ends = []
        for body, r in ((int(spg.a[s]), spg.r_a[s]), (int(spg.b[s]), spg.r_b[s])):
            r2 = (_exact(r[0], L), _exact(r[1], L))
            ends.append([*positions[body], (sp.Integer(1), thetas[body], r2)] if body >= 0
                        else [(sp.Integer(1), sp.Integer(0), r2)])
        d = ends[1] + [(-t[0], t[1], t[2]) for t in ends[0]]  # P_b − P_a
        L = sp.sqrt(_dot(d, d))
        ks, L0 = sp.Symbol(f"k_{name}"), sp.Symbol(f"L0_{name}")
        values[ks], values[L0] = float(spg.stiffness[s]), float(spg.rest_length[s])
        dd = [_dot(d, _diff(d, qa)) for qa in q]  # d · ∂d/∂q_a = L ∂L/∂q_a
        tension = ks * (L - L0)
        if spg.damping[s] != 0:
            cs_ = sp.Symbol(f"c_{name}")
            values[cs_] = float(spg.damping[s])
            tension += cs_ * sp.Add(*(dd[a] * qd[a] for a in range(k))) / L
        for a in range(k):
            f[a] += -tension * dd[a] / L

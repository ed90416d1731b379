"""One body's true Newton-Euler rows as `Row`s, with what each term is made of.

From the assembly's per-body pair (`mbody.equations.fbd.BodyEquations`), each row is
written ``lhs − rhs = 0``: accelerations times M, plus b, minus Q, minus G λ for the
unknown reactions (a known reaction's value joins the constant). Beside the row are the
pieces a mistake changes: each applied load's share of Q (gravity too), the gyroscopic
part b, each reaction's coefficient; and the points a student may take moments about
(the body's joint points, the world origin) with the rows that moments about them give;
and what the joints say about the body's accelerations (`mbody.answers.kinematics`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.answers.compare import CONST, Row
from mbody.answers.kinematics import BodyKinematics, body_kinematics
from mbody.answers.text import equation_text
from mbody.answers.vocabulary import PLANAR_ACCELERATIONS, SPATIAL_ACCELERATIONS, joints_of
from mbody.equations.assemble import Assembly
from mbody.equations.fbd import BodyEquations, Equation

FIXED_POINT_JOINTS = {d: {name for name, t in types.items() if t.holds_point}
                      for d, types in joint_types.TYPES.items()}
"""Joint types that hold their point still when the parent is ground."""


@dataclass(frozen=True)
class LoadShare:
    """One applied load's part of a row's Q.

    Parameters
    ----------
    name : str
        The load's name, or ``gravity``.
    kind : str
        ``applied``, ``couple``, ``spring`` or ``gravity``.
    value : float
        What it adds to the row's right side (N, or N m on Euler rows).
    """

    name: str
    kind: str
    value: float


@dataclass(frozen=True)
class TrueRow:
    """One of the body's Newton-Euler rows.

    Parameters
    ----------
    label : str
        The coordinate label (``rod.y``, ``top.w1``).
    euler : bool
        An Euler row (rotation) rather than a Newton row (translation).
    axis : int
        0-2: the world axis of a Newton row, the body axis of an Euler row (planar: 2).
    acc : str
        The acceleration this row is about (``a_y``, ``alpha``, ``alpha_1``).
    row : Row
        The row itself, ``M v̇ + b − Q − G λ = 0``.
    equation : Equation
        The assembly's row (its text is what a student is shown as expected).
    gyro : float
        b on this row: (ω × Iω) on an Euler row (N m).
    loads : tuple of LoadShare
        Each applied load's and gravity's part of Q on this row.
    """

    label: str
    euler: bool
    axis: int
    acc: str
    row: Row
    equation: Equation
    gyro: float
    loads: tuple[LoadShare, ...]

    @property
    def text(self) -> str:
        """The row as `mbody assemble` writes it."""
        return equation_text(self.equation)


@dataclass(frozen=True)
class MomentPoint:
    """A point a student may take moments about.

    Parameters
    ----------
    name : str
        ``joint O`` or ``the origin``.
    W_P : (3,) array
        The point, world coordinates (m).
    fixed : bool
        It stays still: a joint to ground that holds its point.
    """

    name: str
    W_P: np.ndarray
    fixed: bool


@dataclass(frozen=True)
class BodyRows:
    """Everything the checker compares a body's equations with.

    Parameters
    ----------
    body : str
        The body's name.
    planar : bool
        A planar model.
    rows : tuple of TrueRow
        Newton's rows then Euler's, in stacking order.
    mass : float
        kg.
    J : (3, 3) array
        Inertia tensor about the mass centre, body axes.
    W_R_B : (3, 3) array
        Body -> world rotation.
    W_x : (3,) array
        The mass centre, world coordinates.
    omega : (3,) array
        Angular velocity, body axes.
    points : tuple of MomentPoint
        The joint points of the body and the world origin (when not at the mass centre).
    joints : dict of str to tuple
        Unknown reaction label -> (joint name, +1 on the child / −1 on the parent,
        the other body).
    kinematics : BodyKinematics or None
        What the enforced joints say about the body's accelerations (None: nothing).
    """

    body: str
    planar: bool
    rows: tuple[TrueRow, ...]
    mass: float
    J: np.ndarray
    W_R_B: np.ndarray
    W_x: np.ndarray
    omega: np.ndarray
    points: tuple[MomentPoint, ...]
    joints: dict[str, tuple[str, float, str]]
    kinematics: BodyKinematics | None = None

    @property
    def newton(self) -> list[TrueRow]:
        """Newton's rows (world axes)."""
        return [r for r in self.rows if not r.euler]

    @property
    def euler(self) -> list[TrueRow]:
        """Euler's rows (body axes; planar: one)."""
        return [r for r in self.rows if r.euler]

    def transport(self, e: TrueRow, point: MomentPoint, *, keep_acc: bool) -> Row:
        """Moments about `point` instead of the mass centre, on Euler row `e`.

        ``E + Σ_j C_j N_j`` with C = W_R_Bᵀ [d]×, d = G − P: the Euler row about G plus
        d × (the Newton rows). With `keep_acc` False the transport term d × m a_G is
        dropped (moments about P, but I_G α kept: the course's "wrong point").

        Parameters
        ----------
        e : TrueRow
            One of the body's Euler rows.
        point : MomentPoint
            The point moments are taken about.
        keep_acc : bool
            Keep the transport term (the correct equation about P) or not.

        Returns
        -------
        Row
            The moment equation about P, along e's axis.
        """
        C = self._lever(point)
        out = e.row
        for j, n in enumerate(self.newton):
            c = float(C[e.axis, j])
            if c != 0.0:
                out = out.plus(n.row if keep_acc else n.row.without([n.acc]), c)
        return out.cleaned(absolute=self.joints)

    def about_fixed_point(self, e: TrueRow, point: MomentPoint, *, gyro: bool = True) -> Row:
        """Moments about a fixed `point` with the inertia about it: the transport row
        with a_G = ω̇ × d + ω × (ω × d) put in (``I_P α = M_P`` in the plane). With `gyro`
        False the velocity terms are left out: ``I_P α = M_P`` in space, without
        ω × I_P ω.

        Parameters
        ----------
        e : TrueRow
            One of the body's Euler rows.
        point : MomentPoint
            A point that does not move.
        gyro : bool
            Keep the gyroscopic terms about the point.

        Returns
        -------
        Row
            The moment equation about the point with the inertia about it.
        """
        row = self.transport(e, point, keep_acc=True)
        if not gyro:
            row = row.with_term(CONST, row.get(CONST) - e.gyro,
                                max(0.0, row.err(CONST) - abs(e.gyro)))
        d = self.W_x - point.W_P
        R = self.W_R_B
        if self.planar:
            w = float(self.omega[2])
            A = np.array([[-d[1]], [d[0]], [0.0]])
            a0 = -w * w * d
            alphas: tuple[str, ...] = ("alpha",)
        else:
            w_W = R @ self.omega
            A = -_skew(d) @ R
            a0 = np.cross(w_W, np.cross(w_W, d))
            alphas = SPATIAL_ACCELERATIONS[3:]
        size = float(np.linalg.norm(d))
        A = _denoise(A, size)
        a0 = _denoise(a0, size * float(self.omega @ self.omega)) if gyro else 0.0 * a0
        accs = (PLANAR_ACCELERATIONS if self.planar else SPATIAL_ACCELERATIONS)[:3]
        net = 0.0  # the velocity terms' constant: added once, at its own magnitude
        for j, a in enumerate(accs[: 2 if self.planar else 3]):
            c = row.get(a)
            if c == 0.0:
                continue
            sub = {al: float(A[j, k]) for k, al in enumerate(alphas) if A[j, k] != 0.0}
            net += c * float(a0[j])
            row = row.without([a]).plus(Row.of(sub), c)
        # the centripetal terms' moments about a fixed point cancel (exactly, in the plane:
        # d x (w x (w x d)) = 0 for w along z): their sizes added one by one would widen
        # the constant's tolerance by terms nobody writes (review R6-2), growing with w²
        row = row.plus(Row.of({CONST: net}))
        return row.cleaned(absolute=self.joints)

    def _lever(self, point: MomentPoint) -> np.ndarray:
        """C (3, 3): Euler row k of the moment about P gains Σ_j C[k, j] N_j."""
        d = self.W_x - point.W_P
        if self.planar:
            C = np.zeros((3, 3))
            C[2] = _skew(d)[2]
            return C
        return _denoise(self.W_R_B.T @ _skew(d), float(np.linalg.norm(d)))


def _denoise(a: np.ndarray, size: float) -> np.ndarray:
    """Entries below 1e-12 of `size` (the lever arm they come from) are rotation noise."""
    return np.where(np.abs(a) <= 1e-12 * size, 0.0, a)


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def body_rows(asm: Assembly, body: str) -> BodyRows:
    """The true rows of `body` in `asm`, with their pieces and moment points.

    Parameters
    ----------
    asm : Assembly
        The model's equations at its state.
    body : str
        A body of the model.

    Returns
    -------
    BodyRows
        Rows, load shares, moment points and reaction sides.
    """
    model = asm.model
    eqs: BodyEquations = asm.bodies[body]
    i = model.index[body]
    planar = model.dimension == cv.PLANAR
    fbd = eqs.fbd
    rows = []
    for r, eq in enumerate(eqs.equations):
        euler = r >= len(eqs.newton)
        axis = (2 if planar else r - 3) if euler else r
        acc = _acc_name(planar, euler, axis)
        shares = []
        for f in fbd.applied:
            if euler:
                v = float(f.B_moment[axis])
            else:
                v = 0.0 if f.couple else float(f.W_vector[axis])
            if v != 0.0:
                kind = f.kind if f.kind != "applied" else (
                    "couple" if f.couple else _load_kind(model, f.name))
                shares.append(LoadShare(f.name, kind, v))
        coef: dict[str, float] = dict(eq.lhs)
        const = eq.gyro - eq.rhs
        const_scale = abs(eq.gyro) + sum(abs(s.value) for s in shares)
        for label, c in eq.reactions.items():
            if label in eq.known:
                const -= c * eq.known[label]
                const_scale += abs(c * eq.known[label])
            else:
                coef[label] = -c
        coef[CONST] = const
        scale = {k: abs(v) for k, v in coef.items()}
        scale[CONST] = max(abs(const), const_scale)
        row = Row(coef, scale).cleaned(absolute=[k for k in coef if k != CONST
                                                 and k not in eq.lhs])
        rows.append(TrueRow(eq.row, euler, axis, acc, row, eq, float(eq.gyro),
                            tuple(shares)))
    x = np.asarray(fbd.W_position, dtype=float)
    points = []
    seen: list[np.ndarray] = []
    known = model.known_reactions_at(asm.state.t)
    joints: dict[str, tuple[str, float, str]] = {}
    cols = asm.columns
    for j in joints_of(model, i).tolist():
        joint = model.joints[j]
        efforts = model.drivers.labels_of(j) if model.drivers is not None else ()
        for label in (*joint.labels, *efforts):  # a driver's effort acts as a reaction
            if label not in known:
                other = joint.parent if joint.child == body else joint.child
                joints[label] = (joint.name, 1.0 if joint.child == body else -1.0, other)
        P = np.asarray(cols.joint_W_P[j], dtype=float)
        if np.linalg.norm(P - x) < 1e-12 or any(np.allclose(P, q) for q in seen):
            continue
        seen.append(P)
        fixed = (joint.parent == cv.GROUND and joint.type in FIXED_POINT_JOINTS[model.dimension]
                 and not joint.particle_joint)
        points.append(MomentPoint(f"joint {joint.name}", P, fixed))
    origin = np.zeros(3)
    if np.linalg.norm(x) > 1e-12 and not any(np.allclose(origin, q) for q in seen):
        points.append(MomentPoint("the origin", origin, False))
    omega = np.asarray(asm.state.omega[i], dtype=float)
    kinematics = body_kinematics(asm, body, tuple(r.label for r in rows),
                                 tuple(r.acc for r in rows))
    return BodyRows(body, planar, tuple(rows), float(model.mass[i]),
                    np.asarray(fbd.inertia, dtype=float), np.asarray(fbd.W_R_B, dtype=float),
                    x, omega, tuple(points), joints, kinematics)


def _acc_name(planar: bool, euler: bool, axis: int) -> str:
    if not euler:
        return ("a_x", "a_y", "a_z")[axis]
    return "alpha" if planar else f"alpha_{axis + 1}"


def _load_kind(model, name: str) -> str:
    for load in model.loads:
        if load.name == name:
            return "spring" if load.type == "spring" else "applied"
    return "applied"

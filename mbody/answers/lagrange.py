"""A student's Lagrange equations checked against the model's equations in generalized
coordinates, ``M q'' = f`` (`mbody.equations.generalized`), the usual mistakes named.

An answers entry without a body is one such equation. Its names: the coordinates' own
labels (``O.angle``, its rate ``O.angle_dot``, its acceleration ``O.angle_ddot``) or the
answers' names for them (``coordinates: {theta1: O.angle}``, then ``theta1``,
``theta1_dot``, ``theta1_ddot``; also ``theta1dot``, ``theta1ddot``); the bodies' masses
and inertias ``m_<body>``, ``I_<body>``; ``g``; each load by the symbol `mbody assemble
--symbolic` uses (``F_push_x``, ``M_motor``); a spring's ``k_<spring>``, ``L0_<spring>``
and ``c_<spring>``; a chosen driver's effort by its label (``motor.M``, an unknown). The
answers' coordinates may be others than the model's default (absolute angles
``upper.theta`` instead of relative ``A.angle``): the equations are then those in the
answers' coordinates.

Each equation, with the model's numbers put in, is one linear row in the accelerations
(and efforts); it is compared up to scale with each row ``Σ_j M_kj q''_j − f_k = 0``
(`mbody.answers.compare`), then with the course's mistakes, each a variant of a true
row: a velocity-squared term left out (all of them, or one ``q'_i q'_j`` monomial), a
potential's gradient with the wrong sign (gravity, a spring, or both), an inertial
coupling term left out, a body's parallel-axis term left out of the generalized mass
(I_G where I_P = I_G + m d² belongs), absolute and relative angles mixed (the formulas of
one kind of angle evaluated at the other kind's values), and a mass matrix that is not
symmetric (a coupling coefficient that differs from its transpose in the answers'
equation of the other coordinate). An equation none of these explains is compared term by
term with the closest row, as a Newton-Euler one is: a number rounded too coarsely is
said so, else the terms that differ are named (`not_an_equation_of_this_model`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from mbody import conventions as cv
from mbody.answers.compare import CONST, Row, consensus, fit, matches, rounded_off
from mbody.answers.diagnose import CORRECT, ROUNDED_TOO_COARSELY, Diagnosis
from mbody.answers.linear import NotLinear, linear_row
from mbody.answers.load import Answer, Answers, AnswersError, hinted
from mbody.answers.parse import EquationError, names_in, parse_equation
from mbody.answers.text import differences, num, rounding
from mbody.answers.vocabulary import Vocabulary, name_gravity, newton_euler_bodies
from mbody.equations.coordinates import CoordinateSet, columns, coordinate_set
from mbody.equations.generalized import Generalized, evaluate, generalized
from mbody.equations.symbolic import load_symbols
from mbody.errors import Issue, MbodyError
from mbody.model.model import Model, State
from mbody.solve.configure import configure

MISSING_VELOCITY_TERM = "missing_velocity_term"
POTENTIAL_GRADIENT_SIGN = "potential_gradient_sign"
MISSING_COUPLING_TERM = "missing_coupling_term"
MISSING_PARALLEL_AXIS_TERM = "missing_parallel_axis_term"
ANGLES_MIXED = "absolute_relative_angles_mixed"
MASS_MATRIX_NOT_SYMMETRIC = "mass_matrix_not_symmetric"
NOT_AN_EQUATION_OF_THIS_MODEL = "not_an_equation_of_this_model"

LAGRANGE_DIAGNOSES = {
    MISSING_VELOCITY_TERM: "a velocity-squared term (centripetal, Coriolis or gyroscopic) "
                           "left out",
    POTENTIAL_GRADIENT_SIGN: "a potential's gradient with the wrong sign (gravity or a "
                             "spring pulling the wrong way)",
    MISSING_COUPLING_TERM: "an inertial coupling term (another coordinate's acceleration) "
                           "left out",
    MISSING_PARALLEL_AXIS_TERM: "a body's inertia about its mass centre where the inertia "
                                "about the axis the coordinate turns it about belongs: the "
                                "parallel-axis term m d² left out of the generalized mass",
    ANGLES_MIXED: "absolute and relative angles mixed: the formulas of one kind of angle "
                  "with the other kind's values",
    MASS_MATRIX_NOT_SYMMETRIC: "a coupling coefficient that differs from its transpose in "
                               "the equation of the other coordinate: the mass matrix is "
                               "not symmetric",
    NOT_AN_EQUATION_OF_THIS_MODEL: "none of the above explains it (an equation in "
                                   "generalized coordinates: the closest and the terms that "
                                   "differ are named)",
}
"""The diagnoses of Lagrange equations, in the order they are tried (after `CORRECT`; a
number rounded too coarsely, `mbody.answers.diagnose.ROUNDED_TOO_COARSELY`, before the
last). An entry of no body that nothing explains is `NOT_AN_EQUATION_OF_THIS_MODEL`, the
Newton-Euler label's twin."""


@dataclass(frozen=True)
class LagrangeRows:
    """The true rows ``Σ_j M_kj q''_j (− effort) − f_k = 0`` in the answers' coordinates.

    names: the answers' names of the coordinates (or the labels); labels: the model's;
    rows: one `Row` per coordinate, keys ``<label>_ddot``, effort labels and `CONST`.
    """

    names: tuple[str, ...]
    labels: tuple[str, ...]
    rows: tuple[Row, ...]
    g: Generalized

    def text(self, k: int) -> str:
        """Row k as the answers would write it."""
        row = self.rows[k]
        lhs = ""
        for name in self.names:
            c = row.get(f"{name}_ddot")
            if c == 0.0:
                continue
            mag = num(abs(c))
            body = f"{name}_ddot" if mag == "1" else f"{mag}*{name}_ddot"
            lhs += (f"-{body}" if c < 0 else body) if not lhs else \
                f" {'-' if c < 0 else '+'} {body}"
        rhs = num(-row.get(CONST))
        for key in sorted(row.unknowns):
            if not key.endswith("_ddot"):
                rhs += f" + {key}"
        return f"{lhs or '0'} = {rhs}"


def _rows_of(g: Generalized, names: tuple[str, ...]) -> tuple[Row, ...]:
    """One `Row` per coordinate of `g` (unknown keys ``<name>_ddot`` by the answers'
    `names`), each coefficient with the magnitude of the terms that made it as its error
    scale."""
    model = g.model
    cols = columns(model)
    T = np.abs(g.T)
    mass6 = np.concatenate((np.repeat(model.mass[:, None], 3, axis=1),
                            np.abs(model.J).sum(axis=2)), axis=1).reshape(-1)[cols]
    Mscale = T.T @ (mass6[:, None] * T)
    efforts = {r: e for e, r in g.coordinate_set.efforts}
    rows = []
    for k in range(len(g.f)):
        coef = {f"{names[j]}_ddot": float(g.M[k, j]) for j in range(len(g.f))}
        scale = {f"{names[j]}_ddot": float(Mscale[k, j]) for j in range(len(g.f))}
        coef[CONST], scale[CONST] = -float(g.f[k]), float(g.f_scale[k])
        if k in efforts:
            coef[efforts[k]], scale[efforts[k]] = -1.0, 1.0
        rows.append(Row(coef, scale).cleaned())
    return tuple(rows)


class _Truth:
    """The true rows and their variants at one state, made on first use."""

    def __init__(self, model: Model, state: State, names: tuple[str, ...],
                 labels: tuple[str, ...]):
        self.model, self.state = model, state
        self.names, self.labels = names, labels
        self.g = generalized(model, state, list(labels))
        self.cs: CoordinateSet = self.g.coordinate_set
        self.rows = LagrangeRows(names, labels, _rows_of(self.g, names), self.g)

    def acc(self, j: int) -> str:
        """The acceleration unknown of coordinate j, by the answers' name."""
        return f"{self.names[j]}_ddot"

    @cached_property
    def at_rest(self) -> Generalized:
        return evaluate(self.model, self.state, self.cs, np.zeros(len(self.labels)))

    @cached_property
    def monomials(self) -> list[tuple[str, np.ndarray]]:
        """Each velocity-squared monomial's share of f at the state: (its words, (k,))."""
        k = len(self.labels)
        qd = self.g.qdot
        f0 = self.at_rest.f

        def f(rates: np.ndarray) -> np.ndarray:
            return evaluate(self.model, self.state, self.cs, rates).f

        eye = np.eye(k)
        C = {}
        for i in range(k):
            C[i, i] = 0.5 * (f(eye[i]) + f(-eye[i])) - f0
        out = []
        for i in range(k):
            for j in range(i, k):
                if i == j:
                    c = C[i, i]
                    words = f"{self.names[i]}_dot^2"
                else:
                    s = eye[i] + eye[j]
                    c = (0.5 * (f(s) + f(-s)) - f0 - C[i, i] - C[j, j])
                    words = f"{self.names[i]}_dot*{self.names[j]}_dot"
                share = c * qd[i] * qd[j]  # c is 2 C_ij off the diagonal: the whole term
                if np.any(np.abs(share) > 1e-12 * np.maximum(self.g.f_scale, 1e-300)):
                    out.append((words, share))
        return out

    @cached_property
    def parallel(self) -> list[list[tuple[str, float, float, float]]]:
        """Per coordinate k, each body it turns and whose mass centre it moves: (name,
        m, d, m |∂x_G/∂q_k|²), d the distance of G from the axis the coordinate turns
        the body about (|∂x_G/∂q_k| / |∂θ/∂q_k|): the parallel-axis term of M_kk."""
        model = self.model
        cols = columns(model)
        body, part = np.divmod(cols, 6)
        T = self.g.T
        out = []
        for k in range(T.shape[1]):
            size = max(1.0, float(np.abs(T[:, k]).max(initial=0.0)))
            items = []
            for i, name in enumerate(model.body_names):
                moves = T[(body == i) & (part < 3), k]
                turns = float(np.linalg.norm(T[(body == i) & (part >= 3), k]))
                v2 = float(moves @ moves)
                if turns <= 1e-9 * size or v2 <= (1e-9 * size) ** 2:
                    continue  # a particle, a body the coordinate only slides or only turns
                m = float(model.mass[i])
                items.append((name, m, float(np.sqrt(v2)) / turns, m * v2))
            out.append(items)
        return out

    @cached_property
    def potentials(self) -> list[tuple[str, np.ndarray]]:
        """The conservative generalized forces at rest: (name, (k,)): gravity, each spring
        (its elastic part), and all of them together."""
        parts = self.at_rest.forces
        springs = set(self.model.springs.names)
        out = [(name, part) for name, part in parts.items()
               if (name == "gravity" or name in springs) and np.any(part)]
        if len(out) > 1:
            out.insert(0, ("gravity and the springs", sum((p for _, p in out),
                                                          np.zeros(len(self.labels)))))
        return out

    @cached_property
    def mixed(self) -> LagrangeRows | None:
        """The rows with every angle of the other kind (a joint's relative angle <-> its
        child's absolute angle) evaluated at the answers' values, or None."""
        if self.model.dimension != cv.PLANAR:
            return None
        model = self.model
        child_joint: dict[str, str] = {}
        for joint in model.joints:
            if joint.type in ("revolute", "slot") and not joint.particle_joint:
                child_joint.setdefault(joint.child, joint.name)
        alt = []
        for label in self.labels:
            source, _, what = label.rpartition(".")
            if what == "angle" and source in {j.name for j in model.joints}:
                joint = next(j for j in model.joints if j.name == source)
                alt.append(f"{joint.child}.theta" if joint.parent != cv.GROUND else label)
            elif what == "theta" and source in child_joint:
                joint = next(j for j in model.joints if j.name == child_joint[source])
                alt.append(f"{joint.name}.angle" if joint.parent != cv.GROUND else label)
            else:
                alt.append(label)
        if alt == list(self.labels):
            return None
        try:
            state = configure(model, dict(zip(alt, self.g.q, strict=True)),
                              dict(zip(alt, self.g.qdot, strict=True)), coordinates=alt,
                              start=self.state)
            g = generalized(model, state, alt)
        except MbodyError:
            return None
        return LagrangeRows(self.names, self.labels, _rows_of(g, self.names), g)


def vocabulary(model: Model, state: State, truth: _Truth) -> Vocabulary:
    """The names a Lagrange equation may use (module doc)."""
    g = truth.g
    planar = model.dimension == cv.PLANAR
    accelerations = tuple(truth.acc(j) for j in range(len(truth.labels)))
    efforts = tuple(e for e, _ in g.coordinate_set.efforts)
    values: dict[str, float] = {"pi": float(np.pi), "t": float(state.t)}
    absent: dict[str, str] = {}
    name_gravity(model, values, absent)
    aliases: dict[str, str] = {}
    for j, (name, label) in enumerate(zip(truth.names, truth.labels, strict=True)):
        if g.quasi[j]:
            absent[name] = (f"{name} is a quasi-velocity: it has a rate ({name}_dot) but "
                            "no value")
        else:
            values[name] = float(g.q[j])
        values[f"{name}_dot"] = float(g.qdot[j])
        for base in {name, label}:  # the answers' name, and the model's label
            for suffix, alts in (("", ("",)), ("_dot", ("_dot", "dot")),
                                 ("_ddot", ("_ddot", "ddot"))):
                for a in alts:
                    if base + a != name + suffix:
                        aliases[base + a] = name + suffix
    for i, body in enumerate(model.body_names):
        values[f"m_{body}"] = float(model.mass[i])
        J = model.J[i]
        if planar:
            values[f"I_{body}"] = float(J[2, 2])
        else:
            for r in range(3):
                for c in range(3):
                    values[f"I_{body}_{r + 1}{c + 1}"] = float(J[r, c])
            if not np.any(J - np.diag(np.diag(J))):
                for r in range(3):
                    values[f"I_{body}_{r + 1}"] = float(J[r, r])
        for sym in load_symbols(model, state, body):
            values.setdefault(sym.name, float(sym.value))
    sp = model.springs
    for s, name in enumerate(sp.names):
        values[f"k_{name}"] = float(sp.stiffness[s])
        values[f"L0_{name}"] = float(sp.rest_length[s])
        values[f"c_{name}"] = float(sp.damping[s])
    return Vocabulary("the generalized coordinates", model.dimension, accelerations, efforts,
                      values, {a: c for a, c in aliases.items() if a not in values}, absent)


def _explain(d: str, details: Mapping, rows: LagrangeRows, k: int) -> str:
    name = rows.names[k]
    if d == CORRECT:
        return f"This is Lagrange's equation for {name}: d/dt(∂T/∂{name}') − ∂T/∂{name} = Q_{name}."
    if d == MISSING_VELOCITY_TERM:
        return (f"Your equation for {name} lacks {details['term']}: d/dt(∂T/∂q') brings the "
                "derivative of the mass matrix along the motion, and ∂T/∂q the change of the "
                "kinetic energy with the configuration; together they give the centripetal "
                "and Coriolis terms (with the mass matrix's Christoffel symbols).")
    if d == POTENTIAL_GRADIENT_SIGN:
        return (f"The {details['potential']} term of your {name} equation has the wrong sign: "
                "the generalized force of a potential V is Q = −∂V/∂q (it pulls toward "
                "lower V), and on the left-hand side of L = T − V it appears as +∂V/∂q.")
    if d == MISSING_COUPLING_TERM:
        return (f"Your equation for {name} lacks the inertial coupling with "
                f"{details['coupling']}: the kinetic energy has the cross term "
                f"M_kl q'_k q'_l, so each coordinate's equation holds the other's "
                "acceleration.")
    if d == ANGLES_MIXED:
        return (f"Your {name} equation is what the formulas give when the angles of one kind "
                "(absolute, from a fixed direction) are fed the values of the other "
                "(relative, from the parent body), or the other way round: write every angle "
                "in one convention (cos(θ2 − θ1) with absolute angles is cos(θ2) with a "
                "relative θ2).")
    if d == MISSING_PARALLEL_AXIS_TERM:
        acc = f"{name}_ddot"
        return (f"The coefficient of {acc} in your {name} equation lacks {details['words']}: "
                f"the kinetic energy of a body that {name} turns is ½ I_G ω² + ½ m v_G², and "
                f"with G at d from the axis it turns about, that is ½ (I_G + m d²) ω²: the "
                f"inertia about the axis (the parallel-axis theorem), not about G.")
    if d == MASS_MATRIX_NOT_SYMMETRIC:
        return (f"Your coefficient of {details['other']}_ddot here ({details['here']}) "
                f"differs from that of {name}_ddot in your {details['other']} equation "
                f"({details['there']}): both are M_kl of T = ½ q'ᵀ M q', which is symmetric.")
    return details.get("why", "")


def _diagnose(s: Row, truth: _Truth, tol: float, hint: int | None,
              answered: dict[int, Row]) -> tuple[str, int, dict]:
    """(diagnosis, the row compared with, details) for the student's row `s`."""
    rows = truth.rows.rows
    order = ([hint] if hint is not None else []) + [k for k in range(len(rows)) if k != hint]
    accs = {truth.acc(j) for j in range(len(rows))}
    if not (s.unknowns & accs):
        return NOT_AN_EQUATION_OF_THIS_MODEL, hint if hint is not None else 0, {
            "why": "This has no generalized acceleration: Lagrange's equation of a "
                   "coordinate holds d/dt(∂T/∂q'), which brings the accelerations."}
    for k in order:
        if matches(s, rows[k], tol):
            return CORRECT, k, {}
    for k in order:  # velocity-squared terms left out
        row = rows[k]
        fv = sum((share for _, share in truth.monomials), np.zeros(len(rows)))
        candidates = [("its velocity-squared terms", fv)] + [
            (f"the term in {w}", share) for w, share in truth.monomials]
        for words, share in candidates:
            if share[k] == 0.0:
                continue
            variant = row.with_term(CONST, row.get(CONST) + share[k], row.err(CONST))
            if matches(s, variant, tol):
                return MISSING_VELOCITY_TERM, k, {"term": words, "value": float(share[k])}
    for k in order:  # a potential's gradient with the wrong sign
        row = rows[k]
        for name, part in truth.potentials:
            if part[k] == 0.0:
                continue
            variant = row.with_term(CONST, row.get(CONST) + 2 * part[k], row.err(CONST))
            if matches(s, variant, tol):
                return POTENTIAL_GRADIENT_SIGN, k, {"potential": name, "value": float(part[k])}
    for k in order:  # an inertial coupling left out
        row = rows[k]
        couplings = [j for j in range(len(rows)) if j != k and row.get(truth.acc(j)) != 0.0]
        for drop in [[j] for j in couplings] + ([couplings] if len(couplings) > 1 else []):
            variant = row.without([truth.acc(j) for j in drop])
            if matches(s, variant, tol):
                return MISSING_COUPLING_TERM, k, {
                    "coupling": ", ".join(f"{truth.names[j]}_ddot" for j in drop)}
    for k in order:  # a body's parallel-axis term left out of the generalized mass
        row, acc = rows[k], truth.acc(k)
        items = truth.parallel[k]
        for parts in [[x] for x in items] + ([items] if len(items) > 1 else []):
            term = sum(x[3] for x in parts)
            variant = row.with_term(acc, row.get(acc) - term, row.err(acc))
            if matches(s, variant, tol):
                words = " and ".join(f"{body}'s m d² = {num(m)}·{num(dist)}² = {num(md2)} "
                                     "kg m²" for body, m, dist, md2 in parts)
                return MISSING_PARALLEL_AXIS_TERM, k, {
                    "bodies": [x[0] for x in parts], "term": float(term), "words": words}
    mixed = truth.mixed
    if mixed is not None:
        for k in order:
            if matches(s, mixed.rows[k], tol):
                return ANGLES_MIXED, k, {}
    for k in order:  # right but for a coupling coefficient: its transpose?
        free = [truth.acc(j) for j in range(len(rows)) if j != k]
        f = matches(s, rows[k], tol, free=free)
        if f is None:
            continue
        for j in range(len(rows)):
            other = answered.get(j)
            if j == k or other is None:
                continue
            g = fit(other, rows[j], free=[truth.acc(i) for i in range(len(rows)) if i != j])
            if g is None or not g.ok(tol):
                continue
            here, there = s.get(truth.acc(j)) / f.k, other.get(truth.acc(k)) / g.k
            ref = max(abs(here), abs(there), 1e-300)
            if abs(here - there) > tol * ref:
                return MASS_MATRIX_NOT_SYMMETRIC, k, {
                    "other": truth.names[j], "here": float(here), "there": float(there)}
        wrong = [truth.names[j] for j in range(len(rows)) if j != k
                 and abs(s.get(truth.acc(j)) / f.k - rows[k].get(truth.acc(j)))
                 > tol * max(rows[k].err(truth.acc(j)), 1e-300)]
        if wrong:
            return NOT_AN_EQUATION_OF_THIS_MODEL, k, {
                "why": f"Its coupling coefficient(s) of "
                       f"{', '.join(w + '_ddot' for w in wrong)} are not those of the mass "
                       "matrix."}
    return _closest(s, truth, tol, order)


def _closest(s: Row, truth: _Truth, tol: float, order: list[int]) -> tuple[str, int, dict]:
    """The row the student's row is closest to, by the fewest terms that differ (the
    coordinate's own acceleration breaking ties): a number rounded too coarsely when
    every term is in place, else the terms that differ, as for a Newton-Euler row."""
    rows = truth.rows.rows
    best: tuple | None = None
    for k in order:
        f = consensus(s, rows[k], tol, truth.acc(k))
        if f is None:
            continue
        wrong = f.wrong(tol)
        key = (len(wrong), f.error)
        if best is None or key < best[0]:
            best = (key, k, f, wrong)
    if best is None:
        return NOT_AN_EQUATION_OF_THIS_MODEL, order[0], {
            "why": "It shares no term with the model's Lagrange equations."}
    _, k, f, wrong = best
    name, t = truth.names[k], rows[k]
    off = rounded_off(s, t, f, tol)
    if off is not None:
        return ROUNDED_TOO_COARSELY, k, {
            "why": f"This is Lagrange's equation for {name}, with every term in place, but "
                   + rounding(s, t, f, off, tol) + " (m_<body>, I_<body>, g...).",
            "rounded": {key: {"have": s.get(key), "expected": f.times(t.get(key)),
                              "relative": v} for key, v in off.items()}}
    return NOT_AN_EQUATION_OF_THIS_MODEL, k, {
        "why": "It is none of the model's Lagrange equations, nor one of the usual "
               f"mistakes. Closest is the equation of {name}; with every term on the left "
               "side, at your equation's scale: " + differences(s, t, f, wrong) + ".",
        "differs": {key: {"have": s.get(key), "expected": f.times(t.get(key))}
                    for key in wrong}}


def _forgotten_body(model: Model, state: State, vocab: Vocabulary, eq: str,
                    labels: Sequence[str], cache: dict[str, Vocabulary]) -> str:
    """The hint for an entry without ``body:`` whose names this Lagrange vocabulary lacks
    and a body's Newton-Euler equations have (``m*a_x = O.Fx``): "did you forget body:
    rod?"; '' when no body has them."""
    foreign = [n for n in names_in(eq, labels) if not _has(vocab, n)]
    if not foreign:
        return ""
    found, more = newton_euler_bodies(model, state, foreign, cache=cache)
    if not found:
        return ""
    why = "an entry without body: is an equation in generalized coordinates"
    if len(found) == 1 and not more:
        return f"did you forget body: {found[0]}? {why}"
    shown = ", ".join(found) + (" ..." if more else "")
    are = "are names" if len(foreign) > 1 else "is a name"
    return (f"did you forget body: NAME? {', '.join(foreign)} {are} of the Newton-Euler "
            f"equations of {shown}; {why}")


def _has(vocab: Vocabulary, name: str) -> bool:
    return vocab.canonical(name) is not None


def coordinate_names(model: Model, sheet: Answers) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(the answers' names, the model's labels) of the coordinates: the answers'
    ``coordinates:`` or the model's default ones."""
    if sheet.coordinates:
        return (tuple(n for n, _ in sheet.coordinates), tuple(lab for _, lab in sheet.coordinates))
    labels = tuple(coordinate_set(model).labels)
    return labels, labels


def check_lagrange(model: Model, state: State, sheet: Answers, entries: list[Answer],
                   tol: float) -> tuple[list[tuple[Answer, Diagnosis, str]],
                                        list[tuple[str, str]], int]:
    """The verdicts on the answers' Lagrange equations (module doc): per entry (answer,
    diagnosis, the coordinate's name), the rows no correct equation gave (name, text), and
    how many rows there are (one per coordinate).

    Raises
    ------
    AnswersError
        Coordinates that are not the model's, or not one per degree of freedom; an
        equation that cannot be read, or a name outside the vocabulary.
    """
    names, labels = coordinate_names(model, sheet)
    try:
        truth = _Truth(model, state, names, labels)
    except MbodyError as exc:
        raise AnswersError([Issue(sheet.file, 0, 0, "coordinates", f"the answers' coordinates: "
                                  f"{exc}")]) from None
    vocab = vocabulary(model, state, truth)
    dotted = (*labels, *(f"{lab}_dot" for lab in labels), *(f"{lab}_ddot" for lab in labels),
              *(f"{lab}dot" for lab in labels), *(f"{lab}ddot" for lab in labels),
              *vocab.reactions)
    issues: list[Issue] = []
    parsed: list[tuple[Answer, Row | None, str]] = []
    bodies: dict[str, Vocabulary] = {}  # the bodies' Newton-Euler names, for the hint
    for a in entries:
        if a.coordinate and a.coordinate not in names and a.coordinate not in labels:
            issues.append(sheet.issue(a, f"no coordinate {a.coordinate!r} in the answers' "
                                      f"coordinates ({', '.join(names)})"))
            continue
        read = False
        try:
            eq = parse_equation(a.eq, dotted)
            read = True
            parsed.append((a, linear_row(eq, vocab if hinted(issues) else vocab.quiet), ""))
        except EquationError as exc:
            reason = exc.reason.replace(f" for body {vocab.body!r}", " in a Lagrange equation")
            advice = exc.hint
            if read and hinted(issues):  # a name this vocabulary lacks
                advice = _forgotten_body(model, state, vocab, a.eq, dotted, bodies) or advice
            issues.append(sheet.issue(a, reason, position=exc.position, hint=advice))
        except NotLinear as exc:
            parsed.append((a, None, exc.why))
    if issues:
        raise AnswersError(issues)
    answered: dict[int, Row] = {}
    for _, row, _ in parsed:  # the rows the answers give, for the symmetry test
        if row is None:
            continue
        for k, t in enumerate(truth.rows.rows):
            free = [truth.acc(j) for j in range(len(names)) if j != k]
            f = fit(row, t, free=free)
            if f is not None and f.ok(tol) and k not in answered:
                answered[k] = row
    out: list[tuple[Answer, Diagnosis, str]] = []
    covered: set[int] = set()
    for a, row, why in parsed:
        hint = None
        if a.coordinate:
            hint = names.index(a.coordinate) if a.coordinate in names else \
                labels.index(a.coordinate)
        if row is None:
            d = Diagnosis(NOT_AN_EQUATION_OF_THIS_MODEL, "", "",
                          f"This is not linear in the accelerations: "
                          f"it has {why}. Lagrange's equations are linear in q''.",
                          {"not_linear": why})
            out.append((a, d, a.coordinate))
            continue
        mine = {k: r for k, r in answered.items() if r is not row}
        diagnosis, k, details = _diagnose(row, truth, tol, hint, mine)
        if diagnosis == CORRECT:
            covered.add(k)
        rows = truth.mixed if diagnosis == ANGLES_MIXED and truth.mixed else truth.rows
        expected = truth.rows.text(k) if diagnosis != CORRECT else rows.text(k)
        d = Diagnosis(diagnosis, expected, labels[k], _explain(diagnosis, details, truth.rows, k),
                      {**details, "coordinate": names[k]})
        out.append((a, d, names[k]))
    uncovered = [(names[k], truth.rows.text(k)) for k in range(len(names)) if k not in covered]
    return out, uncovered, len(names)

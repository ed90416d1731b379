"""Which of the course's mistakes turns a body's true row into the student's equation.

Each mistake of the course's misconceptions table is a small change of a true row,
built here in numbers (`variants`): the gyroscopic part of b dropped; one scalar inertia
for the tensor; moments about a joint point or the origin with I_G kept and the
transport term left out; a reaction left out, given the wrong sign, or replaced by a
number; an applied load (or gravity) left out. The student's row is compared with the
true rows first, then with each variant in the order of `DIAGNOSES`; the first that
matches within the tolerance names the mistake. When none does, the closest true row
and the terms that differ are reported.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from mbody import joint_types
from mbody.answers.compare import CONST, Fit, Row, consensus, matches, rounded_off, same
from mbody.answers.kinematics import PutIn, Relation
from mbody.answers.rows import BodyRows, MomentPoint, TrueRow
from mbody.answers.text import differences, rounding, row_text
from mbody.answers.text import num as _num
from mbody.answers.text import terms as _terms

CORRECT = "correct"
MISSING_GYROSCOPIC_TERM = "missing_gyroscopic_term"
GYROSCOPIC_TERM_SIGN = "gyroscopic_term_sign"
WRONG_MOMENT_POINT = "wrong_moment_point"
REACTION_TREATED_AS_KNOWN = "reaction_treated_as_known"
MISSING_REACTION = "missing_reaction"
REACTION_SIGN = "reaction_sign"
SINGLE_INERTIA_IN_SPACE = "single_inertia_in_space"
MISSING_PRODUCTS_OF_INERTIA = "missing_products_of_inertia"
MISSING_APPLIED_LOAD = "missing_applied_load"
APPLIED_LOAD_SIGN = "applied_load_sign"
LEVER_ARM_SIGN = "lever_arm_sign"
ROUNDED_TOO_COARSELY = "rounded_too_coarsely"
SOLVED_VALUE = "solved_value_not_an_equation"
NOT_AN_EQUATION = "not_an_equation_of_this_body"

DIAGNOSES = {
    CORRECT: "equal to one of the body's Newton or Euler rows (up to scale and "
             "rearrangement)",
    MISSING_GYROSCOPIC_TERM: "an Euler row without its ω × Iω part",
    GYROSCOPIC_TERM_SIGN: "an Euler row with ω × Iω of the wrong sign (mind the cyclic "
                          "order 1 → 2 → 3)",
    MISSING_PRODUCTS_OF_INERTIA: "Euler's principal-axes form (I_1 α_1 + (I_3 − I_2) ω_2 "
                                 "ω_3 = M_1) in body axes that are not principal: the "
                                 "tensor's products of inertia left out",
    SINGLE_INERTIA_IN_SPACE: "one scalar inertia where the tensor's principal moments "
                             "differ",
    WRONG_MOMENT_POINT: "moments taken about another point (a joint, the origin) without "
                        "the transport term r × m a_G: with I_G, or with I_P = I_G + m d² "
                        "about a point that moves",
    MISSING_REACTION: "an unknown reaction left out",
    REACTION_SIGN: "a reaction with the wrong sign (the third law: −R on the parent)",
    LEVER_ARM_SIGN: "a reaction's moment about G with the wrong sign (r × F: r from G to "
                    "the joint, in that order)",
    MISSING_APPLIED_LOAD: "an applied force or moment (or gravity) left out",
    APPLIED_LOAD_SIGN: "an applied force or moment (or gravity) with the wrong sign",
    REACTION_TREATED_AS_KNOWN: "an unknown reaction replaced by a number",
    SOLVED_VALUE: "one unknown's value, as the equations of motion give it (a result "
                  "such as alpha = -7.3529), not an equation of the body's free body",
    ROUNDED_TOO_COARSELY: "right but for a number rounded too coarsely (a few percent off, "
                          "beyond the tolerance)",
    NOT_AN_EQUATION: "none of the above explains it",
}
"""The fixed vocabulary of diagnoses, in the order they are tried, with their meaning."""


@dataclass(frozen=True)
class Diagnosis:
    """What one equation is, compared with its body's rows.

    Parameters
    ----------
    diagnosis : str
        A key of `DIAGNOSES`.
    expected : str
        The row it was compared with, as text ('' when there is none to compare with).
    row : str
        That row's coordinate label (``rod.theta``), or ''.
    explanation : str
        One or two sentences in the course's terms.
    details : dict
        What the diagnosis found, for programs: the term, the point, the load, the value
        used for a reaction...
    """

    diagnosis: str
    expected: str
    row: str
    explanation: str
    details: dict = field(default_factory=dict)


AXES = "xyz"


def describe_row(r: TrueRow, planar: bool) -> str:
    """The row in words: "Newton's equation along world y (m a_y = ΣF_y)"...

    Parameters
    ----------
    r : TrueRow
        One of a body's rows.
    planar : bool
        Whether the model is planar.

    Returns
    -------
    str
        The row's name in the course's terms.
    """
    if not r.euler:
        a = AXES[r.axis]
        return f"Newton's equation along world {a} (m a_{a} = ΣF_{a})"
    if planar:
        return "the rotational equation about the mass centre (I_G α = ΣM_G)"
    k = r.axis + 1
    return f"Euler's equation about body axis {k} ((I α + ω × Iω)_{k} = M_{k})"


def diagnose(s: Row, br: BodyRows, tol: float,
             solved: Callable[[], Mapping[str, float] | None] = lambda: None) -> Diagnosis:
    """The diagnosis of the student's row `s` against the body's rows.

    Parameters
    ----------
    s : Row
        The student's equation, ``lhs − rhs``, with the model's numbers put in.
    br : BodyRows
        The body's true rows and what they are made of.
    tol : float
        Relative tolerance on each coefficient (see `mbody.answers.compare`).
    solved : callable, optional
        Returns the values solved at this state, or None: the reactions by label
        (``O.Fx``) and the accelerations by their coordinate's label (``rod.theta``).
        Asked only when reactions may have been replaced by numbers, to tell whether the
        numbers are their values (else the equation is not that mistake) and to say what
        they are, and when an equation of one unknown may be its value.

    Returns
    -------
    Diagnosis
        The first explanation that matches.
    """
    return _Diagnoser(s, br, tol, solved).run()


class _Diagnoser:
    def __init__(self, s: Row, br: BodyRows, tol: float,
                 solved: Callable[[], Mapping[str, float] | None]):
        self.s, self.br, self.tol, self.solved = s, br, tol, solved
        self.planar = br.planar

    def run(self) -> Diagnosis:
        for step in (self.no_unknowns, self.foreign, self.correct, self.gyroscopic,
                     self.gyroscopic_sign, self.products_of_inertia, self.single_inertia,
                     self.moment_point, self.missing_reaction, self.reaction_sign,
                     self.missing_load, self.load_sign, self.treated_as_known):
            found = step()
            if found is not None:
                return found
        kin = self.br.kinematics
        if kin is not None:
            # the same mistakes in an equation that writes accelerations from the joints'
            # kinematics: those that change a reaction or the constant, which the
            # kinematics cannot (the others change acceleration terms, which they do)
            self.kinematic = True
            # (a reaction replaced by its value too: m*0.433013*alpha = -6.3678 is
            # Newton's row along x with a_x from the pin and O.Fx's solved value)
            for step in (self.gyroscopic, self.gyroscopic_sign, self.missing_reaction,
                         self.reaction_sign, self.missing_load, self.load_sign,
                         self.treated_as_known):
                self.last = None
                found = step()
                if found is not None:
                    return self.with_kinematics(found)
            self.kinematic = False
        return self.solved_value() or self.rounded() or self.closest()

    # -- helpers -----------------------------------------------------------------------
    kinematic = False
    """Whether the mistakes are tried with the joints' kinematics put in the rows."""
    last: Row | None = None
    """The variant of the last match in that mode."""
    compared: Row | None = None
    """The row the last `match` compared with (the variant, with the kinematics put in
    in that mode)."""

    def match(self, t: Row, free: tuple[str, ...] = (), anchored: bool = False) -> Fit | None:
        """The fit of the student's row to the variant `t` (with the joints' kinematics
        put in, in that mode), within the tolerance.

        `anchored`: the caller pins the factor and the constant itself (a reaction
        replaced by a number: the scale of a row of one term, the reactions' values), so
        that a variant without reactions may be compared with the kinematics put in."""
        self.compared = t
        if not self.kinematic:
            return matches(self.s, t, self.tol, free)
        if not anchored and not (t.unknowns & set(self.br.joints)):
            # nothing anchors it: with the kinematics put in, a body with one degree of
            # freedom makes every reaction-free row a multiple of its equation of motion
            # (m a_y = 0 would be Newton's x row without O.Fx: 0.866 alpha = 0)
            return None
        if any(k in self.involved() and k not in self.s.unknowns for k in free):
            return None  # a coefficient left open that the kinematics replace
        t2 = self.kinematic_row(t, free)
        if t2 is None:
            return None
        self.compared = t2
        f = matches(self.s, t2, self.tol, free)
        if f is not None:
            self.last = t
        return f

    def kinematic_row(self, t: Row, free: tuple[str, ...] = ()) -> Row | None:
        """`t` written in the accelerations the student wrote, with the joints'
        kinematics put in for the others (`BodyKinematics.put_in`: in whichever
        direction the student used them); None when that cannot be done (m a_y = ... on
        a pendulum is not Newton's row along x with a_x put in: a_x = 1.73205 a_y is
        that row's, and m a_y is not its 3.4641 a_y)."""
        put = self.put_in(t, free)
        return put.row if put is not None else None

    def put_in(self, t: Row, free: tuple[str, ...] = ()) -> PutIn | None:
        kin = self.br.kinematics
        if kin is None:
            return None
        return kin.put_in(t, self.s, free)

    def at_its_scale(self, t: Row, f: Fit) -> bool:
        """Whether a form that is not one of the body's rows (about a fixed pivot, with
        the kinematics put in) matched at factor `f` is that form, and not a result.

        With one acceleration as its only unknown (a body of one degree of freedom:
        I_P alpha = M_P) a form fixes no scale, and every equation c alpha = c alpha*
        matches it, whatever it was made of: ``2*alpha = -14.7059`` (the answer, doubled)
        or the same law with another mass (5 kg for the model's 2 kg: the mass cancels
        where the inertia comes from the shape) would pass at any factor (review R6-1).
        So it is that law only at the two scales people write it at: factor ±1 (as
        written) and ±1/m (divided by the mass: (k_G² + d²) alpha = −g d sin θ); and
        even then not where the scale gives it away as something else: coefficient 1,
        the value itself (``alpha = -7.3529``, `solved_value`); or one of the body's rows
        with its reactions' values put in, at that row's own scale (``I_G*alpha =
        -1.2286``, ``m*0.433013*alpha = -6.3678``: `treated_as_known`)."""
        single = len(t.unknowns) == 1 and not (t.unknowns & set(self.br.joints))
        if not single:
            return True
        if abs(abs(f.k) - 1.0) > self.tol and abs(abs(f.k) * self.br.mass - 1.0) > self.tol:
            return False  # a multiple of the law that says only alpha's value
        if abs(abs(f.k) - 1.0) <= self.tol:
            return True
        (u,) = t.unknowns
        if abs(abs(self.s.get(u)) - 1.0) <= self.tol * max(1.0, self.s.err(u)):
            return False  # the value: "alpha = -7.3529"
        return not self.reaction_put_in()

    def reaction_put_in(self) -> bool:
        """Whether the student's equation is `treated_as_known` of a row, as written or
        with the joints' kinematics put in (state restored)."""
        kinematic, last = self.kinematic, self.last
        try:
            self.kinematic = False
            if self.treated_as_known() is not None:
                return True
            if self.br.kinematics is None:
                return False
            self.kinematic = True
            return self.treated_as_known() is not None
        finally:
            self.kinematic, self.last = kinematic, last

    def with_kinematics(self, d: Diagnosis) -> Diagnosis:
        """`d`, found with the joints' kinematics put in, saying so."""
        if self.last is None:
            return d
        t = self.last
        return Diagnosis(d.diagnosis, d.expected, d.row,
                         f"{d.explanation} Your equation writes the rest of the row "
                         f"right, {self.kinematics_words(t)}.",
                         {**d.details, **self.kinematics_details(t)})

    def words(self, r: TrueRow) -> str:
        return describe_row(r, self.planar)

    def reaction_words(self, label: str) -> str:
        joint, side, other = self.br.joints[label]
        where = "ground" if other == "ground" else f"body {other}"
        return f"{label} (joint {joint}, between {self.br.body} and {where})"

    # -- the steps -----------------------------------------------------------------------
    def no_unknowns(self) -> Diagnosis | None:
        if self.s.unknowns:
            return None
        c = self.s.get(CONST)
        says = ("0 = 0" if c == 0.0 else
                f"a number equal to another (they differ by {_num(abs(c), abs(c))})")
        return Diagnosis(NOT_AN_EQUATION, "", "",
                         f"Once the model's numbers are put in, this says {says}: it has no "
                         "acceleration and no unknown reaction in it. A Newton-Euler "
                         "equation relates the body's accelerations to the forces on it.",
                         {"unknowns": []})

    def foreign(self) -> Diagnosis | None:
        accs = {a for r in self.br.rows for a in r.row.unknowns if "." not in a}
        accs |= {r.acc for r in self.br.rows}
        mine = set(self.br.joints) | accs
        other = sorted(self.s.unknowns - mine)
        if not other:
            return None
        label = other[0]
        if "." in label:
            why = (f"{label} is a reaction of a joint that does not touch {self.br.body}, so "
                   f"it is not a force on this body's free-body diagram.")
        else:
            why = f"{label} is not an unknown of {self.br.body}."
        return Diagnosis(NOT_AN_EQUATION, "", "", why + " Draw the free body of "
                         f"{self.br.body} alone: only its own joints' reactions act on it.",
                         {"foreign": other})

    def correct(self) -> Diagnosis | None:
        for r in self.br.rows:
            f = self.match(r.row)
            if f is not None:
                return Diagnosis(CORRECT, r.text, r.label,
                                 f"This is {self.words(r)}{self.scaled(f)}.", {"scale": f.k})
        kin = self.br.kinematics
        for e in self.br.euler:
            for p in self.br.points:
                t = self.br.transport(e, p, keep_acc=True)
                f = self.match(t)
                if f is not None and self.at_its_scale(t, f):
                    return Diagnosis(
                        CORRECT, row_text(t), e.label,
                        f"These are moments about {_point(p)}, with the transport term "
                        f"r × m a_G: the same law as {self.words(e)}, taken about another "
                        "point.", {"point": p.name, "form": "transport"})
                # the pivot's kinematics are the joint's: only where the joint is held
                if not p.fixed or kin is None:
                    continue
                pivot = self.br.about_fixed_point(e, p)
                f = self.match(pivot)
                if f is not None and self.at_its_scale(pivot, f):
                    return Diagnosis(
                        CORRECT, row_text(pivot), e.label,
                        f"These are moments about {_point(p)}, a fixed pivot, with the "
                        f"inertia about it (I_P = I_G + m d²): {self.words(e)} combined with "
                        "Newton's through the pivot's kinematics.",
                        {"point": p.name, "form": "fixed_pivot"})
        return self.correct_by_kinematics()

    def correct_by_kinematics(self) -> Diagnosis | None:
        """A row, or the moments about a point, plus relations the joints impose on the
        accelerations (`mbody.answers.kinematics`): a_G written from a pivot's
        kinematics. Such relations hold for every motion the joints allow and carry no
        reaction, so the reactions must be the row's and the rest equal once they are
        put in for the accelerations the student did not write."""
        if self.br.kinematics is None:
            return None
        for r in self.br.rows:
            t = self.kinematic_row(r.row)
            if t is None or self.unanchored(r.row, r.acc):
                continue
            f = matches(self.s, t, self.tol)
            if f is not None and self.at_its_scale(t, f):
                return Diagnosis(CORRECT, r.text, r.label,
                                 f"This is {self.words(r)}{self.scaled(f)}, "
                                 f"{self.kinematics_words(r.row)}.",
                                 {"scale": f.k, **self.kinematics_details(r.row)})
        for e in self.br.euler:
            for p in self.br.points:
                written = self.br.transport(e, p, keep_acc=True)
                t = self.kinematic_row(written)
                if t is None or self.unanchored(written, e.acc):
                    continue
                f = matches(self.s, t, self.tol)
                if f is None or not self.at_its_scale(t, f):
                    continue
                return Diagnosis(
                    CORRECT, row_text(written), e.label,
                    f"These are moments about {_point(p)}, with the transport term r × m "
                    f"a_G (the same law as {self.words(e)}, taken about another point), "
                    f"{self.kinematics_words(written)}.",
                    {"point": p.name, "form": "transport",
                     **self.kinematics_details(written)})
        return None

    def unanchored(self, t: Row, acc: str) -> bool:
        """Whether `t` has no unknown reaction and the student's equation lacks its
        acceleration `acc`: then, with the kinematics put in, any true relation of a body
        with one degree of freedom would match it (moments about the pivot leave no
        reaction): a moment equation about the pivot keeps its angular acceleration, as
        I_P α = M_P does."""
        return not (t.unknowns & set(self.br.joints)) and self.s.get(acc) == 0.0

    def scaled(self, f: Fit) -> str:
        return ((", scaled" if abs(abs(f.k) - 1.0) > self.tol else "")
                + (" and rearranged" if f.k < 0 else ""))

    def replaced(self, t: Row, free: tuple[str, ...] = ()) -> list[Relation]:
        """The relations put into `t` (a true row as written) for the student, in
        words: each acceleration of `t` the student did not write, in terms of those
        written."""
        put = self.put_in(t, free)
        return list(put.relations) if put is not None else []

    def kinematics_words(self, t: Row) -> str:
        """"with a_x written from the kinematics of joint O (a_x = 0.433013 alpha at
        this state)"."""
        kin = self.br.kinematics
        assert kin is not None
        used = self.replaced(t) or list(kin.relations)
        accs = ", ".join(rel.acc for rel in used)
        return (f"with {accs} written from the kinematics of {_sources(kin.sources)} "
                f"({'; '.join(rel.text for rel in used)} at this state)")

    def kinematics_details(self, t: Row) -> dict:
        kin = self.br.kinematics
        assert kin is not None
        used = self.replaced(t) or list(kin.relations)
        return {"kinematics": [rel.text for rel in used], "joints": list(kin.sources)}

    def gyroscopic(self) -> Diagnosis | None:
        for e in self.br.euler:
            if e.gyro == 0.0 or abs(e.gyro) <= 1e-12 * e.row.err(CONST):
                continue
            t = e.row.with_term(CONST, e.row.get(CONST) - e.gyro,
                                e.row.err(CONST) - abs(e.gyro))
            if self.match(t) is not None:
                return Diagnosis(
                    MISSING_GYROSCOPIC_TERM, e.text, e.label,
                    f"This is {self.words(e)} without its gyroscopic term "
                    f"{self.gyro_words(e)}. Keep ω × Iω for spatial rotation: it does not "
                    "vanish unless the motion is planar.",
                    {"term": "omega x (I omega)", "value": e.gyro})
        if self.planar:
            return None
        for e in self.br.euler:
            for p in self.br.points:
                if not p.fixed:
                    continue
                t = self.br.about_fixed_point(e, p, gyro=False)
                if same(t, self.br.about_fixed_point(e, p), self.tol) or self.match(t) is None:
                    continue
                full = self.br.about_fixed_point(e, p)
                return Diagnosis(
                    MISSING_GYROSCOPIC_TERM, row_text(full), e.label,
                    f"These are moments about {_point(p)}, a fixed pivot, with the inertia "
                    f"about it, but without the gyroscopic term ω × I_P ω "
                    f"({_num(t.get(CONST) - full.get(CONST))} N m on the left here). Keep "
                    "ω × Iω for spatial rotation, about a fixed pivot as about G.",
                    {"term": "omega x (I_P omega)", "point": p.name,
                     "value": t.get(CONST) - full.get(CONST)})
        return None

    def gyroscopic_sign(self) -> Diagnosis | None:
        """An Euler row with ω × Iω of the wrong sign: the cyclic order 1 → 2 → 3 turned
        (``(I_3 − I_2) w_2 w_3`` on the right side of axis 1 instead of ``(I_2 − I_3)``)."""
        for e in self.br.euler:
            if e.gyro == 0.0 or abs(e.gyro) <= 1e-12 * e.row.err(CONST):
                continue
            t = e.row.with_term(CONST, e.row.get(CONST) - 2.0 * e.gyro, e.row.err(CONST))
            if self.match(t) is None:
                continue
            J = self.br.J
            mind = ("mind the cyclic order 1 → 2 → 3" if np.count_nonzero(J - np.diag(np.diag(J)))
                    == 0 else "mind the order of the cross product, ω × (Iω)")
            return Diagnosis(
                GYROSCOPIC_TERM_SIGN, e.text, e.label,
                f"This is {self.words(e)} with its gyroscopic term of the wrong sign: "
                f"{self.gyro_words(e)} (on the right side it is −(ω × Iω)); {mind}. The row "
                f"reads: {e.text}.",
                {"wrong_sign": "omega x (I omega)", "value": e.gyro})
        return None

    def gyro_words(self, e: TrueRow) -> str:
        k = e.axis
        J, w = self.br.J, self.br.omega
        i, j = (k + 1) % 3, (k + 2) % 3
        if np.count_nonzero(J - np.diag(np.diag(J))) == 0:
            form = (f" = (I_{j + 1} − I_{i + 1}) w_{i + 1} w_{j + 1} = "
                    f"({_num(J[j, j])} − {_num(J[i, i])})·{_num(w[i])}·{_num(w[j])}")
        else:
            form = " (with the full tensor)"
        return (f"(ω × Iω)_{k + 1}{form} = {_num(e.gyro)} N m, which belongs on the left "
                "beside I α")

    def single_inertia(self) -> Diagnosis | None:
        if self.planar:
            return None
        J = self.br.J
        moments = np.linalg.eigvalsh(J)
        if np.ptp(moments) <= 1e-9 * moments.max():
            return None  # equal principal moments: one inertia is right
        for e in self.br.euler:
            a = e.acc
            if self.s.get(a) == 0.0:
                continue
            coef = {k: v for k, v in e.row.coef.items()
                    if not (k.startswith("alpha") and k != a)}
            coef[CONST] = e.row.get(CONST) - e.gyro
            t = Row(coef, {k: e.row.err(k) for k in coef})
            f = self.match(t, free=(a,))
            if f is None:
                continue
            used = self.s.get(a) / f.k
            diagonal = np.count_nonzero(J - np.diag(np.diag(J))) == 0
            if diagonal and abs(used - J[e.axis, e.axis]) <= self.tol * abs(J[e.axis, e.axis]):
                continue  # I_k itself: the gyroscopic step speaks for it
            # one of the body's own inertias, not any number that makes the row fit
            scalars = [*moments, *np.diag(J), float(np.trace(J)) / 3]
            if not any(abs(used - x) <= self.tol * abs(x) for x in scalars):
                continue
            k = e.axis + 1
            pm = ", ".join(_num(x) for x in np.diag(J)) if diagonal else \
                ", ".join(_num(x) for x in moments)
            return Diagnosis(
                SINGLE_INERTIA_IN_SPACE, e.text, e.label,
                f"This treats the body as having one inertia ({_num(used)} kg m²) about every "
                f"axis, so angular momentum is taken parallel to the spin and ω × Iω vanishes; "
                f"but its principal moments differ ({pm} kg m²). Use the full tensor: "
                f"{self.inertia_words(e)}"
                + (f", and keep ω × Iω ({_num(e.gyro)} N m)." if e.gyro else "."),
                {"inertia_used": used, "term": f"I alpha_{k}"})
        return None

    def products_of_inertia(self) -> Diagnosis | None:
        """Euler's principal-axes form, I_k α_k + (I_j − I_i) ω_i ω_j = M_k, written for a
        body whose tensor has products of inertia in its body axes, with its diagonal
        entries or its principal moments (in any order) as I_1, I_2, I_3."""
        J = self.br.J
        products = {f"I_{a + 1}{b + 1}": float(J[a, b]) for a, b in ((0, 1), (0, 2), (1, 2))
                    if abs(J[a, b]) > 1e-12 * np.abs(J).max()}
        if self.planar or not products:
            return None  # principal body axes: the form is right (or the row is planar)
        w = self.br.omega
        moments = np.linalg.eigvalsh(J)
        choices = [("its diagonal entries I_11, I_22, I_33", tuple(np.diag(J).tolist()))]
        choices += [("its principal moments", p)
                    for p in dict.fromkeys(itertools.permutations(moments.tolist()))]
        for e in self.br.euler:
            k = e.axis
            i, j = (k + 1) % 3, (k + 2) % 3
            if self.s.get(e.acc) == 0.0 or any(
                    self.s.get(a) != 0.0 for a in ("alpha_1", "alpha_2", "alpha_3")
                    if a != e.acc):
                continue  # the principal form has this row's angular acceleration alone
            for words, inertia in choices:
                gyro = (inertia[j] - inertia[i]) * w[i] * w[j]
                coef = {key: v for key, v in e.row.coef.items() if not key.startswith("alpha")}
                coef[e.acc] = inertia[k]
                coef[CONST] = e.row.get(CONST) - e.gyro + gyro
                scale = {key: e.row.err(key) for key in coef if key not in (e.acc, CONST)}
                scale[CONST] = max(0.0, e.row.err(CONST) - abs(e.gyro)) + abs(gyro)
                t = Row.of(coef, scale)
                if same(t, e.row, self.tol) or self.match(t) is None:
                    continue
                n = k + 1
                form = (f"I_{n} α_{n} + (I_{j + 1} − I_{i + 1}) ω_{i + 1} ω_{j + 1} = M_{n}")
                used = ", ".join(_num(x) for x in inertia)
                listed = ", ".join(f"{name} = {_num(v)}" for name, v in products.items())
                return Diagnosis(
                    MISSING_PRODUCTS_OF_INERTIA, e.text, e.label,
                    f"This is {self.words(e)} in its principal-axes form, {form}, with "
                    f"{words} ({used} kg m²) as I_1, I_2, I_3. That form holds only along "
                    f"principal axes, and {self.br.body}'s body axes are not: its tensor has "
                    f"products of inertia ({listed} kg m²). In body axes keep the full "
                    f"tensor: {self.inertia_words(e)} on the left, and (ω × Iω)_{n} = "
                    f"{_num(e.gyro)} N m with it; or write Euler's equations along the "
                    "principal axes, with ω and α in those axes.",
                    {"inertia_used": list(inertia), "products": products,
                     "term": f"(I alpha)_{n} and (omega x I omega)_{n}"})
        return None

    def inertia_words(self, e: TrueRow) -> str:
        row = {k: v for k, v in e.row.coef.items() if k.startswith("alpha")}
        return f"(I α)_{e.axis + 1} = {_terms(row)}"

    def moment_point(self) -> Diagnosis | None:
        for e in self.br.euler:
            for p in self.br.points:
                t = self.br.transport(e, p, keep_acc=False)
                if not same(t, e.row, self.tol) and self.match(t) is not None:
                    transport = self.br.transport(e, p, keep_acc=True)
                    term = _terms({k: v - e.row.get(k) for k, v in transport.coef.items()
                                   if k.startswith("a_")})
                    return Diagnosis(
                        WRONG_MOMENT_POINT, e.text, e.label,
                        f"These are moments about {_point(p)}, not about the mass centre, "
                        f"but with I_G α alone. About a point other than G add the transport "
                        f"term r × m a_G ({term} on the left), or take moments about G: "
                        f"{e.text}.", {"point": p.name, "transport_term": term})
                if p.fixed:
                    continue
                t = self.br.about_fixed_point(e, p)
                if not same(t, e.row, self.tol) and self.match(t) is not None:
                    return Diagnosis(
                        WRONG_MOMENT_POINT, e.text, e.label,
                        f"These are moments about {_point(p)} with the inertia about it, as "
                        f"for a fixed pivot; but {p.name.split()[-1]} moves, so I_P α = M_P "
                        f"does not hold there. Take moments about the mass centre: {e.text}.",
                        {"point": p.name, "form": "moving_pivot"})
        return None

    def absent(self, r: TrueRow) -> list[str]:
        """The row's reactions the student's equation does not have."""
        return sorted(k for k in r.row.unknowns if k in self.br.joints
                      and self.s.get(k) == 0.0)

    def missing_reaction(self) -> Diagnosis | None:
        for r in self.br.rows:
            gone = self.absent(r)
            if gone and self.match(r.row.without(gone)) is not None:
                terms = _terms({k: -r.row.get(k) for k in gone})
                names = ", ".join(self.reaction_words(k) for k in gone)
                return Diagnosis(
                    MISSING_REACTION, r.text, r.label,
                    f"This is {self.words(r)} with the reaction{'s' if len(gone) > 1 else ''} "
                    f"{names} left out. Every reaction of the body's joints is on its free "
                    f"body, as an unknown: the right side needs {terms}.",
                    {"reactions": gone, "term": terms})
        return None

    def reaction_sign(self) -> Diagnosis | None:
        for r in self.br.rows:
            present = [k for k in r.row.unknowns if k in self.br.joints and self.s.get(k) != 0]
            groups: dict[str, list[str]] = {}
            for k in present:
                groups.setdefault(self.br.joints[k][0], []).append(k)
            trials = [sorted(g) for g in groups.values()] + [[k] for k in sorted(present)]
            for flip in trials:
                t = r.row
                for k in flip:
                    t = t.with_term(k, -t.get(k), t.err(k))
                if self.match(t) is None:
                    continue
                joint, side, other = self.br.joints[flip[0]]
                rule = ("the reaction acts on the child as +R and on the parent as −R "
                        "(Newton's third law)")
                role = (f"{self.br.body} is the child of joint {joint}, so it feels "
                        f"+{flip[0]}" if side > 0 else
                        f"{self.br.body} is the parent of joint {joint}, so it feels "
                        f"−{flip[0]}")
                label = REACTION_SIGN
                if r.euler and side > 0:
                    # the child feels +R, so a flipped moment is r × F's sign, not the
                    # third law's (telling it "it feels +R" beside "-0.43 O.Fx" confuses)
                    label = LEVER_ARM_SIGN
                    rule = (f"the moment of a force about G is r × F, with r from G to "
                            f"where it acts (joint {joint}), and {self.br.body}, the child "
                            f"of joint {joint}, feels +R there")
                    role = "check the lever arm's direction and the order of the cross product"
                elif r.euler:
                    role += f", whose moment about G is r × (−R), r from G to joint {joint}"
                terms = _terms({k: -r.row.get(k) for k in flip})
                return Diagnosis(
                    label, r.text, r.label,
                    f"{', '.join(flip)} {'has' if len(flip) == 1 else 'have'} the wrong sign "
                    f"in {self.words(r)}: {rule}; {role}. The right side should read "
                    f"{terms}.", {"reactions": flip, "term": terms})
        return None

    def missing_load(self) -> Diagnosis | None:
        for r in self.br.rows:
            shares = list(r.loads)
            trials = [[x] for x in shares] + ([shares] if len(shares) > 1 else [])
            for drop in trials:
                total = sum(x.value for x in drop)
                t = r.row.with_term(CONST, r.row.get(CONST) + total,
                                    max(0.0, r.row.err(CONST) - sum(abs(x.value) for x in drop)))
                if same(t, r.row, self.tol) or self.match(t) is None:
                    continue
                what = "; ".join(_load_words(x, r.euler) for x in drop)
                return Diagnosis(
                    MISSING_APPLIED_LOAD, r.text, r.label,
                    f"This is {self.words(r)} with {what} left out. Every applied load "
                    "(gravity, springs, actuators) is on the free body: " + r.text + ".",
                    {"loads": [x.name for x in drop], "value": total})
        return None

    def treated_as_known(self) -> Diagnosis | None:
        for r in self.br.rows:
            gone = self.absent(r)
            if not gone:
                continue
            t = r.row.without(gone)
            f = self.match(t, free=(CONST,), anchored=True)
            if f is None:
                continue
            compared = self.compared if self.compared is not None else t
            if len(compared.unknowns) == 1 and abs(abs(f.k) - 1.0) > self.tol:
                continue  # one term fixes no scale: ask that it be written as in the row
            # the student's constant, brought to the true row's scale, minus the true one
            # (with the kinematics put in, their velocity terms are the row's too)
            base = compared.get(CONST)
            extra = self.s.get(CONST) / f.k - base
            if not self.stands_for(r, gone, extra, f.k, base):
                continue  # some other number: not these reactions' share of the row
            details: dict = {"reactions": gone}
            if len(gone) == 1:
                k = gone[0]
                value = extra / r.row.get(k)
                details["value_used"] = value
                unit = " N m" if _is_moment(k) else " N"
                text = (f"{self.reaction_words(k)} is replaced by the number {_num(value)}{unit}"
                        if CONST in self.s.coef else
                        # nothing written for it: the static guess, the reaction taken as
                        # what balances the rest of the row
                        f"{self.reaction_words(k)} is left out as if it balanced the rest "
                        f"of the row, a static guess ({k} = {_num(value)}{unit})")
                sol = self.solved()
                if sol is not None and k in sol:
                    details["value_solved"] = sol[k]
                    unit = " N m" if _is_moment(k) else " N"
                    text += (f" (solved with the joints, it is {_num(sol[k])}{unit} at this "
                             "instant; but it is an output, not an input)")
            elif CONST in self.s.coef:
                text = (f"the reactions {', '.join(gone)} are replaced by numbers (they add "
                        f"{_num(-extra)} to the right side)")
            else:
                text = (f"the reactions {', '.join(gone)} are left out as if they balanced "
                        f"the rest of the row, a static guess (together {_num(-extra)} on "
                        "the right side)")
            return Diagnosis(
                REACTION_TREATED_AS_KNOWN, r.text, r.label,
                f"In {self.words(r)}, {text}. A joint reaction is a constraint force: tag it "
                f"as an unknown and keep its symbol, {_terms({k: -r.row.get(k) for k in gone})}"
                " on the right side.", details)
        return None

    def stands_for(self, r: TrueRow, gone: list[str], extra: float, k: float,
                   base: float) -> bool:
        """Whether `extra`, what the student's constant adds to the row `r` (at its scale)
        in place of the reactions `gone`, is what those reactions contribute at this
        state: their solved values, the static guess that they balance the rest of the
        row (the student's constant 0), or each one's static value from the Newton row
        it alone carries (``O.Fy = m g``). Within the tolerance on rounded numbers: the
        student's numbers or the magnitudes of the terms that make the contribution.
        `base` is the constant of the row compared (`r`'s, with the velocity terms of
        the joints' kinematics when they are put in)."""
        own = self.s.err(CONST) / abs(k)

        def near(target: float, size: float) -> bool:
            ref = max(own, r.row.err(CONST) + size)
            return abs(extra - target) <= self.tol * ref

        if near(-base, abs(base)):
            return True
        static = {}
        for n in self.br.rows:
            held = [x for x in n.row.unknowns if x in self.br.joints]
            if not n.euler and len(held) == 1 and held[0] in gone:
                static[held[0]] = -n.row.get(CONST) / n.row.get(held[0])
        guesses = [static] if len(static) == len(gone) else []
        sol = self.solved()
        if sol is not None and all(x in sol for x in gone):
            guesses.append({x: sol[x] for x in gone})
        for values in guesses:
            parts = [r.row.get(x) * values[x] for x in gone]
            if near(sum(parts), sum(abs(p) for p in parts)):
                return True
        return False

    def solved_value(self) -> Diagnosis | None:
        """An equation of one unknown whose value is the one the equations of motion
        give (``alpha = -7.3529``, copied from `mbody solve`): a result, not one of the
        body's equations (one that is, such as a free body's ``alpha_1 = -3``, is
        `correct` before this is asked)."""
        if len(self.s.unknowns) != 1:
            return None
        (u,) = self.s.unknowns
        row = next((r for r in self.br.rows if r.acc == u), None)
        label = row.label if row is not None else u
        sol = self.solved()
        if sol is None or label not in sol:
            return None
        c = self.s.get(u)
        value, target = -self.s.get(CONST) / c, float(sol[label])
        if not (math.isfinite(value) and math.isfinite(target)):
            return None  # a solve that gave no number says nothing of this one
        ref = max(abs(target), self.s.err(CONST) / abs(c))
        if abs(value - target) > max(self.tol * ref, _ZERO):
            return None
        if row is None:  # a reaction: the first row it is in
            row = next((r for r in self.br.rows if u in r.row.unknowns), self.br.rows[0])
            unit = " N m" if _is_moment(u) else " N"
            whose = f" (a reaction of joint {self.br.joints[u][0]})"
        else:
            unit = " rad/s²" if row.euler else " m/s²"
            whose = ""
        pivot = [row_text(self.br.about_fixed_point(e, p)) for e in self.br.euler
                 for p in self.br.points if p.fixed and self.br.kinematics is not None
                 and e.acc == u]
        where = (f"the moment equation about the fixed pivot, I_P α = M_P "
                 f"({pivot[0]}), or " if pivot else "")
        return Diagnosis(
            SOLVED_VALUE, row.text, row.label,
            f"This says {u} = {_num(value)}{unit}{whose}, its value at this state as the "
            f"equations of motion give it ({_num(target)}{unit} solved with the joints): "
            f"a result, not an equation of {self.br.body}'s free body. Write the equation "
            f"it comes from: {where}{self.words(row)} with every force on the free body, "
            f"the reactions as unknowns: {row.text}.",
            {"unknown": u, "value": value, "value_solved": target})

    def candidates(self) -> list[tuple[TrueRow, Row, str, str]]:
        """What an equation that is none of the mistakes is compared with: (the row, the
        row or moment form, its words, its text)."""
        out = [(r, r.row, self.words(r), r.text) for r in self.br.rows]
        if self.s.unknowns & {"a_x", "a_y", "a_z"} and any(
                k.startswith("alpha") for k in self.s.unknowns):
            for e in self.br.euler:
                for p in self.br.points:
                    t = self.br.transport(e, p, keep_acc=True)
                    out.append((e, t, f"the moment equation about {_point(p)} (with "
                                "the transport term r × m a_G)", row_text(t)))
        if any(k.startswith("alpha") for k in self.s.unknowns):
            for e in self.br.euler:
                for p in self.br.points:
                    if p.fixed:
                        t = self.br.about_fixed_point(e, p)
                        out.append((e, t, f"the moment equation about the fixed pivot "
                                    f"{_point(p)} (with I_P = I_G + m d²)", row_text(t)))
        return out

    def comparisons(self) -> list[tuple[TrueRow, Row, Row, str, str, bool]]:
        """Each candidate as (row, candidate compared, candidate as written, words, text,
        with the kinematics put in): as written, then (when the joints relate the body's
        accelerations) with the joints' kinematics put in."""
        out = [(r, t, t, words, text, False) for r, t, words, text in self.candidates()]
        if self.br.kinematics is not None:
            for r, t, _, words, text, _ in list(out):
                put = self.put_in(t)
                if put is not None and put.changed:
                    t2 = put.row
                    out.append((r, t2, t, words, text, True))
        return out

    def rounded(self) -> Diagnosis | None:
        """Every term of a row in place, each coefficient within `compare.ROUNDING` of the row's
        and some beyond the tolerance: a number written with too few figures."""
        best: tuple | None = None
        for r, t, written, words, text, kinematic in self.comparisons():
            f = self.consensus(t, r.acc)
            off = rounded_off(self.s, t, f, self.tol) if f is not None else None
            if off is None:
                continue
            rank = (kinematic, max(off.values()))
            if best is None or rank < best[0]:
                best = (rank, r, t, written, words, text, f, off)
        if best is None:
            return None
        (kinematic, _), r, t, written, words, text, f, off = best
        how = ", " + self.kinematics_words(written) if kinematic else ""
        return Diagnosis(
            ROUNDED_TOO_COARSELY, text, r.label,
            f"This is {words}{how}, with every term in place, but "
            + rounding(self.s, t, f, off, self.tol) + " (m, I_G, g...).",
            {"rounded": {k: {"have": self.s.get(k), "expected": f.times(t.get(k)),
                             "relative": v} for k, v in off.items()}})

    def closest(self) -> Diagnosis:
        best: tuple | None = None
        s = self.s
        for r, t, written, words, text, kinematic in self.comparisons():
            f = self.consensus(t, r.acc, s)
            if f is None:
                continue
            wrong = f.wrong(self.tol)
            if kinematic and (self.mixed(wrong) or self.misread(s, t, f, wrong)):
                continue
            shared = len(s.unknowns & t.unknowns)
            # a row about an acceleration the student did not write comes last: an
            # equation in alpha is a moment equation, however many reactions it shares
            # with a Newton row (with the kinematics put in, the row's acceleration may be
            # one they replace); a row as written before the same with the kinematics
            away = r.acc not in s.unknowns and not (kinematic and r.acc in self.involved())
            key = (away, len(wrong) - shared, len(wrong), kinematic, f.error)
            if best is None or key < best[0]:
                best = (key, r, t, written, words, text, f, wrong)
        if best is None:
            return Diagnosis(NOT_AN_EQUATION, "", "", "This equation shares no term with "
                             f"any of {self.br.body}'s Newton-Euler rows.", {})
        key, r, t, written, words, text, f, wrong = best
        kinematic = key[3]
        combo = self.combination()
        details: dict = {"differs": {k: {"have": s.get(k), "expected": f.times(t.get(k))}
                                     for k in wrong}}
        how = "with every term on the left side"
        if kinematic:
            words += ", " + self.kinematics_words(written)
            how += " and those put in"
            details["kinematics"] = self.kinematics_details(written)["kinematics"]
        return Diagnosis(
            NOT_AN_EQUATION, text, r.label,
            (combo + " " if combo else "")
            + f"Closest is {words}; {how}, at your equation's scale: "
            + differences(s, t, f, wrong) + ".", details)

    def mixed(self, wrong: list[str]) -> bool:
        """Whether the terms that differ are both accelerations and forces (or the
        constant): with the kinematics put in, a row is taken as the closest only when
        one side of it is right, the accelerations written from the kinematics or the
        forces; else a moment equation whose lever arms are wrong would be read as
        Newton's row with a_G from the kinematics (I_G α = -60 - 0.025 O.Fy + 0.025 A.Fy
        has O.Fy and A.Fy in the ratio of the crank's Newton row along y)."""
        acc = [k for k in wrong if k != CONST and k not in self.br.joints]
        return bool(acc) and len(acc) < len(wrong)

    def misread(self, s: Row, t: Row, f: Fit, wrong: list[str]) -> bool:
        """Whether an acceleration term differs in size, not only in sign, with the
        kinematics put in: the student did not write them (I_G α = -0.43 O.Fx is a
        moment equation, not Newton's along x with a_x = 0.433 α), and the row as
        written is the better comparison."""
        for k in wrong:
            if k == CONST or k in self.br.joints:
                continue
            have, want = abs(s.get(k)), abs(f.times(t.get(k)))
            if abs(have - want) > self.tol * max(s.err(k), want):
                return True
        return False

    def involved(self) -> set[str]:
        """The accelerations the joints' relations involve (none without them)."""
        kin = self.br.kinematics
        return kin.involved if kin is not None else set()

    def load_sign(self) -> Diagnosis | None:
        """A row with one applied load or gravity of the wrong sign (the gyroscopic
        term's sign is a diagnosis of its own: `gyroscopic_sign`)."""
        for r in self.br.rows:
            for x in r.loads:
                change = -2.0 * x.value  # Q's share: −value in lhs − rhs
                t = r.row.with_term(CONST, r.row.get(CONST) - change, r.row.err(CONST))
                if same(t, r.row, self.tol) or self.match(t) is None:
                    continue
                return Diagnosis(
                    APPLIED_LOAD_SIGN, r.text, r.label,
                    f"This is {self.words(r)} with {_load_words(x, r.euler)} of the wrong "
                    f"sign: each load acts on the free body in its own direction, gravity "
                    f"downward, whichever way the body moves. The row reads: {r.text}.",
                    {"wrong_sign": x.name, "loads": [x.name], "value": x.value})
        return None

    def consensus(self, t: Row, acc: str, s: Row | None = None) -> Fit | None:
        """`mbody.answers.compare.consensus` of `s` (default: the student's row) and `t`,
        the row's own acceleration `acc` breaking ties."""
        return consensus(self.s if s is None else s, t, self.tol, acc)

    def combination(self) -> str:
        """A sentence when the equation holds but mixes several rows, else ''."""
        keys = sorted(set().union(*(r.row.keys for r in self.br.rows)) | self.s.keys)
        A = np.array([[r.row.get(k) for r in self.br.rows] for k in keys])
        b = np.array([self.s.get(k) for k in keys])
        if not len(keys) or not np.any(b):
            return ""
        x, *_ = np.linalg.lstsq(A, b, rcond=None)
        x[np.abs(x) <= 1e-9 * np.abs(x).max()] = 0.0  # rows it does not use
        t = Row(dict(zip(keys, (A @ x).tolist(), strict=True)),
                {k: sum(abs(x[j]) * r.row.err(k) for j, r in enumerate(self.br.rows))
                 for k in keys})
        if self.match(t) is None:
            return ""
        used = [r.label for j, r in enumerate(self.br.rows) if x[j] != 0.0]
        return (f"This equation holds (it combines the rows {', '.join(used)}), but it is not "
                "one of the body's Newton-Euler rows: write each one on its own.")


_ZERO = 1e-9
"""A value this close to 0 (m/s², rad/s², N) is 0: `solved_value` takes a solved 1e-17
as the 0 a student writes."""


def _is_moment(label: str) -> bool:
    return joint_types.is_moment(label)


def _point(p: MomentPoint) -> str:
    where = ", ".join(_num(c) for c in (p.W_P if abs(p.W_P[2]) > 0 else p.W_P[:2]))
    return f"{p.name} ({where})"


def _sources(sources: tuple[str, ...]) -> str:
    """("joint O", "joint A", "driver motor") -> "joints O and A and driver motor"."""
    kinds: dict[str, list[str]] = {}
    for words in sources:
        kind, _, name = words.partition(" ")
        kinds.setdefault(kind, []).append(name)
    parts = []
    for kind, names in kinds.items():
        listed = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
        parts.append(f"{kind}{'s' if len(names) > 1 else ''} {listed}")
    return " and ".join(parts)


def _load_words(x, euler: bool) -> str:
    name = {"gravity": "gravity, m g", "couple": f"the applied couple '{x.name}'",
            "spring": f"the spring '{x.name}'"}.get(x.kind, f"the applied force '{x.name}'")
    if euler and x.kind != "couple":
        return f"the moment of {name} about G ({_num(x.value)} N m)"
    return f"{name} ({_num(x.value)} {'N m' if euler else 'N'} on this row)"

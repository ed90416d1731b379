"""`verify` for equations in generalized coordinates (`mbody.answers.lagrange`).

A double pendulum (mass centres off the rods' middles) at moving states: a student's
Lagrange equations written by hand in absolute angles (φ1, φ2: the rods' angles from
hanging) and in relative ones (θ1 = φ1, θ2 = φ2 − φ1), with the model's symbols for the
masses, inertias and g. The correct ones are diagnosed correct at every state; each of
the course's mistakes (a velocity-squared term left out, the potential's gradient with the
wrong sign, an inertial coupling left out, a mass matrix that is not symmetric, absolute
and relative angles mixed) is named, and only on its own equation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_generalized import dp_state

import mbody
from mbody.answers import AnswersError
from mbody.answers.compare import CONST
from mbody.answers.lagrange import (
    ANGLES_MIXED,
    LAGRANGE_DIAGNOSES,
    MASS_MATRIX_NOT_SYMMETRIC,
    MISSING_COUPLING_TERM,
    MISSING_PARALLEL_AXIS_TERM,
    MISSING_VELOCITY_TERM,
    NOT_AN_EQUATION_OF_THIS_MODEL,
    POTENTIAL_GRADIENT_SIGN,
)

P = dict(L1=0.62, a1=0.27, a2=0.33)
MODEL = f"""
model: dp
dimension: 2
gravity: [0, -9.81]
bodies:
  - {{name: upper, mass: 1.3, inertia: 0.031, position: [0, {-P['a1']!r}]}}
  - {{name: lower, mass: 0.8, inertia: 0.017, position: [0, {-P['L1'] - P['a2']!r}]}}
joints:
  - {{name: O, type: revolute, parent: ground, child: upper, at: [[0, 0], [0, {P['a1']!r}]]}}
  - {{name: A, type: revolute, parent: upper, child: lower,
      at: [[0, {P['a1'] - P['L1']!r}], [0, {P['a2']!r}]]}}
"""
DP = dict(P, m1=1.3, m2=0.8, I1=0.031, I2=0.017, g=9.81, k=0.0, L0=0.4, tau=0.0, sx=0, sy=0)

# absolute angles phi1, phi2 (upper.theta, lower.theta)
M11 = "(I_upper + m_upper*0.27^2 + m_lower*0.62^2)"
M12 = "m_lower*0.62*0.33*cos(phi1 - phi2)"
M22 = "(I_lower + m_lower*0.33^2)"
ABS1 = (f"{M11}*phi1_ddot + {M12}*phi2_ddot + m_lower*0.62*0.33*sin(phi1 - phi2)*phi2_dot^2"
        " + (m_upper*0.27 + m_lower*0.62)*g*sin(phi1) = 0")
ABS2 = (f"{M12}*phi1_ddot + {M22}*phi2_ddot - m_lower*0.62*0.33*sin(phi1 - phi2)*phi1_dot^2"
        " + m_lower*0.33*g*sin(phi2) = 0")
# relative angles theta1 = phi1, theta2 = phi2 - phi1 (O.angle, A.angle)
R11 = ("(I_upper + I_lower + m_upper*0.27^2 + m_lower*(0.62^2 + 0.33^2 "
       "+ 2*0.62*0.33*cos(theta2)))")
R12 = "(I_lower + m_lower*(0.33^2 + 0.62*0.33*cos(theta2)))"
REL1 = (f"{R11}*theta1_ddot + {R12}*theta2_ddot - m_lower*0.62*0.33*sin(theta2)*"
        "(2*theta1_dot*theta2_dot + theta2_dot^2) + (m_upper*0.27 + m_lower*0.62)*g*sin(theta1)"
        " + m_lower*0.33*g*sin(theta1 + theta2) = 0")
REL2 = (f"{R12}*theta1_ddot + (I_lower + m_lower*0.33^2)*theta2_ddot + m_lower*0.62*0.33*"
        "sin(theta2)*theta1_dot^2 + m_lower*0.33*g*sin(theta1 + theta2) = 0")

ABSOLUTE = {"phi1": "upper.theta", "phi2": "lower.theta"}
RELATIVE = {"theta1": "O.angle", "theta2": "A.angle"}

STATES = [([0.4, -0.9], [1.3, -2.1]), ([2.2, 0.7], [-0.6, 1.7]), ([-1.1, 2.9], [2.4, 0.8])]


def check(coordinates, equations, state):
    model = mbody.loads(MODEL)
    answers = {"coordinates": coordinates, "equations": [{"eq": e} for e in equations]}
    return mbody.verify(model, answers, state=state)


@pytest.mark.parametrize("q, qd", STATES)
def test_correct_equations_are_correct_in_both_coordinates(q, qd):
    state = dp_state(q, qd, DP)
    v = check(ABSOLUTE, [ABS1, ABS2], state)
    assert [c.diagnosis for c in v.checks] == ["correct", "correct"], v.text()
    assert not v.uncovered
    v = check(RELATIVE, [REL1, REL2], state)
    assert [c.diagnosis for c in v.checks] == ["correct", "correct"], v.text()


def test_the_models_own_labels_need_no_mapping():
    state = dp_state([0.4, -0.9], [1.3, -2.1], DP)
    eq = REL2.replace("theta1", "O.angle").replace("theta2", "A.angle")
    model = mbody.loads(MODEL)
    v = mbody.verify(model, {"equations": [{"eq": eq, "coordinate": "A.angle"}]}, state=state)
    assert v.checks[0].correct, v.text()


MISTAKES = [
    # (name, coordinates, the wrong equation, the diagnosis)
    ("velocity term left out", ABSOLUTE,
     ABS1.replace(" + m_lower*0.62*0.33*sin(phi1 - phi2)*phi2_dot^2", ""),
     MISSING_VELOCITY_TERM),
    ("one of two velocity monomials left out", RELATIVE,
     REL1.replace("(2*theta1_dot*theta2_dot + theta2_dot^2)", "theta2_dot^2"),
     MISSING_VELOCITY_TERM),
    ("gravity's sign", ABSOLUTE,
     ABS2.replace("+ m_lower*0.33*g*sin(phi2)", "- m_lower*0.33*g*sin(phi2)"),
     POTENTIAL_GRADIENT_SIGN),
    ("coupling left out", ABSOLUTE, ABS1.replace(f" + {M12}*phi2_ddot", ""),
     MISSING_COUPLING_TERM),
    ("absolute formulas, relative values", RELATIVE,
     ABS1.replace("phi1", "theta1").replace("phi2", "theta2"), ANGLES_MIXED),
    ("relative formulas, absolute values", ABSOLUTE,
     REL2.replace("theta1", "phi1").replace("theta2", "phi2"), ANGLES_MIXED),
]


@pytest.mark.parametrize("q, qd", STATES[:2])
@pytest.mark.parametrize("name, coordinates, wrong, diagnosis", MISTAKES,
                         ids=[m[0] for m in MISTAKES])
def test_each_mistake_is_named(name, coordinates, wrong, diagnosis, q, qd):
    state = dp_state(q, qd, DP)
    right = [ABS1, ABS2] if coordinates is ABSOLUTE else [REL1, REL2]
    v = check(coordinates, [*right, wrong], state)
    assert [c.diagnosis for c in v.checks] == ["correct", "correct", diagnosis], v.text()
    assert v.checks[2].expected  # the row it should have been


def test_a_mass_matrix_that_is_not_symmetric():
    """The φ1 equation's coupling coefficient differs from the φ2 equation's: named on the
    equation whose coefficient is off (the other is the true one), and only there."""
    state = dp_state([0.4, -0.9], [1.3, -2.1], DP)
    wrong = ABS1.replace(M12, "m_lower*0.62*0.33*1.5*cos(phi1 - phi2)")
    v = check(ABSOLUTE, [wrong, ABS2], state)
    assert [c.diagnosis for c in v.checks] == [MASS_MATRIX_NOT_SYMMETRIC, "correct"], v.text()
    d = v.checks[0].details
    assert d["here"] == pytest.approx(1.5 * d["there"], rel=1e-9)


def test_velocity_terms_at_rest_cannot_be_told_apart():
    """At rest the velocity terms are 0: an equation without them is then the model's."""
    state = dp_state([0.4, -0.9], [0.0, 0.0], DP)
    v = check(ABSOLUTE, [ABS1.replace(" + m_lower*0.62*0.33*sin(phi1 - phi2)*phi2_dot^2", "")],
              state)
    assert v.checks[0].correct


def test_bad_names_are_located_with_a_did_you_mean():
    model = mbody.loads(MODEL)
    with pytest.raises(AnswersError, match="did you mean 'theta1_ddot'|theta1_ddot"):
        mbody.verify(model, {"coordinates": RELATIVE,
                             "equations": [{"eq": "theta1_dddot = 0"}]})
    with pytest.raises(AnswersError, match="coordinates"):
        mbody.verify(model, {"coordinates": {"x": "O.angel", "y": "A.angle"},
                             "equations": [{"eq": "x_ddot = 0"}]})
    with pytest.raises(AnswersError, match="no coordinate 'theta3'"):
        mbody.verify(model, {"coordinates": RELATIVE,
                             "equations": [{"eq": REL1, "coordinate": "theta3"}]})


def test_answers_file_reads_coordinates(tmp_path):
    path = tmp_path / "answers.yaml"
    path.write_text("student: A. Student\ncoordinates: {theta1: O.angle, theta2: A.angle}\n"
                    "equations:\n"
                    f"  - {{coordinate: theta2, eq: \"{REL2}\"}}\n")
    model = mbody.loads(MODEL)
    state = dp_state([0.4, -0.9], [1.3, -2.1], DP)
    v = mbody.verify(model, path, state=state)
    assert v.checks[0].correct and v.checks[0].line == 4
    assert [u.row for u in v.uncovered] == ["theta1"]
    assert np.isclose(v.rows, 2)


# == review R4, F6: the feedback a Newton-Euler equation gets ==============================

PENDULUM = Path(__file__).resolve().parent.parent / "models" / "pendulum.yaml"


def pendulum(eq: str):
    answers = {"coordinates": {"th": "O.angle"}, "equations": [{"eq": eq}]}
    return mbody.verify(mbody.load(PENDULUM), answers).checks[0]


def test_i_g_for_i_o_is_the_missing_parallel_axis_term():
    # the review's equation: the rod's inertia about G (1/6 kg m²) where the inertia
    # about the pin, I_G + m d² = 1/6 + 2·0.5² = 2/3, belongs
    c = pendulum("I_rod*th_ddot + m_rod*g*0.5*sin(th) = 0")
    assert (c.diagnosis, c.row) == (MISSING_PARALLEL_AXIS_TERM, "O.angle"), c.explanation
    assert c.details["bodies"] == ["rod"]
    assert c.details["term"] == pytest.approx(2 * 0.5**2, rel=1e-9)
    assert "rod's m d² = 2·0.5² = 0.5 kg m²" in " ".join(c.explanation.split())
    assert c.meaning == LAGRANGE_DIAGNOSES[MISSING_PARALLEL_AXIS_TERM]


@pytest.mark.parametrize("coordinates, right, wrong, bodies", [
    # absolute angles: each rod's own term in its own coordinate's mass
    (ABSOLUTE, 0, ABS1.replace(" + m_upper*0.27^2", ""), ["upper"]),
    (ABSOLUTE, 1, ABS2.replace(M22, "I_lower"), ["lower"]),
    # relative angles: theta1 turns both rods about O; theta2 the lower about A
    (RELATIVE, 0, REL1.replace(" + m_upper*0.27^2", ""), ["upper"]),
    (RELATIVE, 0, REL1.replace(R11, "(I_upper + I_lower + m_upper*0.27^2)"), ["lower"]),
    (RELATIVE, 1, REL2.replace("(I_lower + m_lower*0.33^2)*theta2_ddot",
                               "I_lower*theta2_ddot"), ["lower"]),
])
def test_the_parallel_axis_term_of_each_body(coordinates, right, wrong, bodies):
    state = dp_state([0.4, -0.9], [1.3, -2.1], DP)
    equations = [ABS1, ABS2] if coordinates is ABSOLUTE else [REL1, REL2]
    v = check(coordinates, [equations[right], wrong], state)
    assert [c.diagnosis for c in v.checks] == ["correct", MISSING_PARALLEL_AXIS_TERM], v.text()
    assert v.checks[1].details["bodies"] == bodies
    assert v.checks[1].details["coordinate"] == list(coordinates)[right]


def test_a_term_the_coordinate_only_moves_is_not_a_parallel_axis():
    # in absolute angles phi1 moves the lower rod's G (by 0.62 m) without turning it:
    # m_lower*0.62^2 is its translation, not a parallel-axis term
    state = dp_state([0.4, -0.9], [1.3, -2.1], DP)
    v = check(ABSOLUTE, [ABS1.replace(" + m_lower*0.62^2", "")], state)
    assert v.checks[0].diagnosis == NOT_AN_EQUATION_OF_THIS_MODEL, v.text()
    assert "phi1_ddot has" in " ".join(v.checks[0].explanation.split())


def test_an_equation_nothing_explains_gets_its_terms_compared():
    # sin(th) taken as th at 30 degrees: the constant is named, at the equation's scale
    c = pendulum("(I_rod + m_rod*0.5^2)*th_ddot + m_rod*g*0.5*th = 0")
    assert c.diagnosis == NOT_AN_EQUATION_OF_THIS_MODEL and c.row == "O.angle"
    text = " ".join(c.explanation.split())
    assert "Closest is the equation of th" in text
    assert f"the constant has {2 * 9.81 * 0.5 * np.pi / 6:.6g} where 4.905 is expected" in text
    assert c.details["differs"][CONST]["expected"] == pytest.approx(4.905, rel=1e-9)
    # the label says no body: the entry has none
    assert "body" not in c.meaning
    assert pendulum("th_dot = 3").diagnosis == NOT_AN_EQUATION_OF_THIS_MODEL
    c = pendulum("th_ddot^2 = 3")
    assert c.diagnosis == NOT_AN_EQUATION_OF_THIS_MODEL and "squared" in c.meaning


def test_a_number_rounded_too_coarsely_in_a_lagrange_equation():
    # two terms: at the scale of the coordinate's own acceleration, as written, the
    # constant is 1 % off (4.905 where 0.66/0.666667 of it is expected)
    c = pendulum("0.66*th_ddot + m_rod*g*0.5*sin(th) = 0")
    assert c.diagnosis == "rounded_too_coarsely", c.explanation
    mass = float(mbody.load(PENDULUM).J[0][2, 2]) + 2 * 0.5**2  # I_O = I_G + m d²
    assert f"the constant has 4.905 where {4.905 * 0.66 / mass:.6g} is expected (1.1 % off)" \
        in " ".join(c.explanation.split())
    assert pendulum("0.6671*th_ddot + m_rod*g*0.5*sin(th) = 0").correct


def _chain_yaml(n: int) -> str:
    """A hanging planar chain of n rods (0.1 m, 1 kg), each pinned to the one above."""
    bodies = "".join(f"  - {{name: l{i}, mass: 1, inertia: 0.001, "
                     f"position: [0, {-0.1 * i - 0.05!r}]}}\n" for i in range(n))
    joints = "".join(f"  - {{name: j{i}, type: revolute, parent: "
                     f"{'ground' if i == 0 else f'l{i - 1}'}, child: l{i}, "
                     f"at: [0, {-0.1 * i!r}]}}\n" for i in range(n))
    return (f"model: chain\ndimension: 2\ngravity: [0, -9.81]\nbodies:\n{bodies}"
            f"joints:\n{joints}")


def test_thousands_of_entries_without_body_are_refused_with_the_first_explained(tmp_path):
    # a class's sheet pasted without body: on a large model: every entry is a problem
    # (Newton-Euler names in a Lagrange equation), each counted; the message shows the
    # first AnswersError.SHOWN, each located with what is wrong and the body it was meant
    # for (the did-you-mean, a pass over thousands of names, is for those alone), and
    # lists the names it takes up to SUMMARY_NAMES, then how many more
    from mbody.answers.vocabulary import SUMMARY_NAMES

    n, entries = 400, 2000
    (tmp_path / "chain.yaml").write_text(_chain_yaml(n), encoding="utf-8")
    sheet = tmp_path / "answers.yaml"
    sheet.write_text("equations:\n" + "".join(
        f'  - {{eq: "m*a_x = j{i % n}.Fx - j{i % n + 1}.Fx"}}\n' for i in range(entries)),
        encoding="utf-8")
    model = mbody.load(tmp_path / "chain.yaml")
    with pytest.raises(AnswersError) as info:
        mbody.verify(model, sheet)
    err = info.value
    assert len(err.issues) == entries
    shown = AnswersError.SHOWN
    lines = str(err).splitlines()
    assert lines[0] == f"{entries} problems in the answers:"
    assert lines[-1] == f"... and {entries - shown} more"
    assert len(lines) == shown + 2
    # every entry's problem at its line and column: the 'm' of its equation
    for k, issue in enumerate(err.issues):
        assert (issue.line, issue.column, issue.key) == (k + 2, 11, f"equations[{k}].eq")
        assert issue.message.startswith("unknown name 'm' in a Lagrange equation (the names: ")
    # the names: the coordinates' accelerations, t, g and each body's m_, I_ (not more
    # than SUMMARY_NAMES of them written out)
    names = n + 2 + 2 * n
    assert all(i.message.endswith(f", … {names - SUMMARY_NAMES} more)") for i in err.issues)
    written = err.issues[0].message.split("(the names: ")[1].split(", …")[0].split(", ")
    assert written[:3] == ["j0.angle_ddot", "j1.angle_ddot", "j2.angle_ddot"]
    assert len(written) == SUMMARY_NAMES
    # the shown ones say which body's equation it is: j_i.Fx and j_(i+1).Fx both act on
    # rod l_i alone
    for k, issue in enumerate(err.issues[:shown]):
        assert issue.hint.startswith(f"did you forget body: l{k % n}? "), issue.hint
        assert str(issue) == lines[k + 1]
    assert not any(i.hint for i in err.issues[shown:])

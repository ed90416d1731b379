"""`mbody.verify` with a_G written from the joints' kinematics (review R4, F1).

A student who writes a pinned body's Newton rows with a_G = α × r − ω² r put in writes a
true equation: the row plus relations the joints impose at acceleration level (Gᵀ v̇ =
γ), which hold for every motion the joints allow and carry no reaction. These tests
check the relations against closed forms and against solved motions, accept every row
of every shipped model written that way (naming the row it is), and keep every usual
mistake diagnosed as it was without the relations.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.answers import verify
from mbody.answers.compare import CONST, Row
from mbody.answers.diagnose import diagnose
from mbody.answers.rows import body_rows

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
DATA = Path(__file__).resolve().parent / "data"

# the reviewer's pendulum (/tmp/r4x/s/pend.yaml): 2 kg, 1 m rod pinned at O, at 30 deg
# from the downward vertical, turning at 3 rad/s (its velocity is ω × r_OG)
MOVING = (DATA / "review_pendulum.yaml").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def moving() -> mbody.Model:
    return mbody.loads(MOVING)


def one(model, body: str, eq: str):
    return verify(model, [{"body": body, "eq": eq}]).checks[0]


# == the review's reproductions ===========================================================

def test_newton_rows_with_a_g_from_the_pin_at_rest_are_correct():
    # the shipped pendulum at rest: a_x = 0.433013 alpha, a_y = 0.25 alpha
    v = verify(MODELS / "pendulum.yaml", [
        {"body": "rod", "eq": "m*0.433013*alpha = O.Fx"},
        {"body": "rod", "eq": "m*0.25*alpha = O.Fy - m*g"}])
    assert [c.diagnosis for c in v.checks] == ["correct", "correct"]
    assert [c.row for c in v.checks] == ["rod.x", "rod.y"]  # the grader's rows
    assert "Newton's equation along world x" in v.checks[0].explanation
    assert "a_x written from the kinematics of joint O" in v.checks[0].explanation
    assert v.checks[0].details["kinematics"] == ["a_x = 0.433013 alpha"]
    assert v.checks[0].details["joints"] == ["joint O"]
    # the equations hold: the solution's a_x is 0.433013 alpha
    sol = mbody.assemble(mbody.load(MODELS / "pendulum.yaml")).solve()
    assert sol["rod.x"] == pytest.approx(0.4330127 * sol["rod.theta"], rel=1e-6)


def test_newton_rows_with_the_centripetal_term_are_correct(moving):
    v = verify(moving, [
        {"body": "rod", "eq": "m*(0.433013*alpha - w^2*0.25) = O.Fx"},
        {"body": "rod", "eq": "m*(0.25*alpha + w^2*0.433013) = O.Fy - m*g"},
        {"body": "rod", "eq": "(I_G + m*0.25)*alpha = -m*g*0.5*sin(theta)"}])
    assert [c.diagnosis for c in v.checks] == ["correct"] * 3
    assert [c.row for c in v.checks] == ["rod.x", "rod.y", "rod.theta"]
    # a_G = α × r − ω² r with r = G − O = (0.25, −0.433013): the relations' numbers
    assert v.checks[0].details["kinematics"] == ["a_x = 0.433013 alpha - 2.25"]
    assert v.checks[1].details["kinematics"] == ["a_y = 0.25 alpha + 3.89711"]
    assert v.checks[2].details["form"] == "fixed_pivot"  # as before: its own words
    assert not v.uncovered


def test_the_class_summary_counts_them_correct(moving, tmp_path):
    from mbody.answers.summary import grade

    f = tmp_path / "cleo.yaml"
    f.write_text("student: Cleo\nequations:\n"
                 '  - {body: rod, eq: "m*(0.433013*alpha - w^2*0.25) = O.Fx"}\n'
                 '  - {body: rod, eq: "m*(0.25*alpha + w^2*0.433013) = O.Fy - m*g"}\n'
                 '  - {body: rod, eq: "(I_G + m*0.25)*alpha = -m*g*0.5*sin(theta)"}\n')
    g = grade(moving, [f]).graded[0]
    assert (g.equations, g.correct, g.wrong) == (3, 3, [])


# == the relations themselves =============================================================

def test_the_pendulums_relations_are_a_g_of_a_fixed_pivot(moving):
    br = body_rows(mbody.assemble(moving), "rod")
    rel = {r.acc: r for r in br.kinematics.relations}
    d = br.W_x[:2]                     # G − O, O at the origin
    w = 3.0
    # a_G = α × d − ω² d: a_x = −d_y α − ω² d_x, a_y = d_x α − ω² d_y
    assert rel["a_x"].coef == {"alpha": pytest.approx(-d[1], rel=1e-12)}
    assert rel["a_x"].const == pytest.approx(-w * w * d[0], rel=1e-12)
    assert rel["a_y"].coef == {"alpha": pytest.approx(d[0], rel=1e-12)}
    assert rel["a_y"].const == pytest.approx(-w * w * d[1], rel=1e-12)


def _models_with_joints():
    for path in sorted(MODELS.glob("*.yaml")):
        m = mbody.load(path)
        if len(m.reactions):
            yield path.name, m


@pytest.mark.parametrize("name", [n for n, _ in _models_with_joints()])
def test_every_relation_holds_for_two_different_motions(name):
    """The relations are the joints' kinematics, not the loads': they hold for the
    solved accelerations at the model's state, and again with gravity tripled (another
    motion the joints allow from the same positions and velocities)."""
    m = mbody.load(MODELS / name)
    g = [3.0 * x + 1.0 for x in np.asarray(m.gravity)[: m.dimension]]
    for model in (m, m.with_values({"gravity": g})):
        asm = mbody.assemble(model, m.initial)
        sol = asm.solve()
        for b in model.body_names:
            br = body_rows(asm, b)
            if br.kinematics is None:
                continue
            coordinate = {r.acc: r.label for r in br.rows}
            for rel in br.kinematics.relations:
                lhs = sol[coordinate[rel.acc]]
                rhs = rel.const + sum(c * sol[coordinate[z]] for z, c in rel.coef.items())
                size = abs(rel.const) + sum(abs(c * sol[coordinate[z]])
                                            for z, c in rel.coef.items())
                assert lhs == pytest.approx(rhs, abs=1e-9 * max(1.0, size)), (name, b,
                                                                              rel.text)


def _written(row: Row, fmt: str = ".6g") -> str:
    parts = [f"({format(v, fmt)})" + ("" if key == CONST else f"*{key}")
             for key, v in row.coef.items() if v != 0.0]
    return " + ".join(parts or ["0"]) + " = 0"


@pytest.mark.parametrize("name", [n for n, _ in _models_with_joints()])
def test_every_row_with_the_kinematics_put_in_is_correct_and_that_row(name):
    """Each Newton-Euler row of every shipped model with joints, every acceleration the
    joints relate replaced by its relation and the numbers rounded to six figures, is
    `correct`, attributed to the row it came from."""
    m = mbody.load(MODELS / name)
    asm = mbody.assemble(m)
    answers, rows = [], []
    for b in m.body_names:
        br = body_rows(asm, b)
        if br.kinematics is None:
            continue
        for r in br.rows:
            t = br.kinematics.substitute(r.row)
            if not (t.unknowns & set(br.joints)) or t.keys == r.row.keys:
                continue  # nothing replaced, or nothing left that says which row
            answers.append({"body": b, "eq": _written(t)})
            rows.append(r.label)
    if not answers:
        pytest.skip("no row that the joints' kinematics change")
    v = verify(m, answers, asm=asm)
    for c, label in zip(v.checks, rows, strict=True):
        assert c.correct and c.row == label, (name, c.eq, c.diagnosis, c.explanation)


# == what must not become correct =========================================================

def _mistakes(br):
    """(what, the student's row) for the usual mistakes made on each row of `br`."""
    for r in br.rows:
        row = r.row
        if r.euler and r.gyro:
            yield f"{r.label} without gyro", row.with_term(CONST, row.get(CONST) - r.gyro)
            yield f"{r.label} gyro sign", row.with_term(CONST, row.get(CONST) - 2 * r.gyro)
        for x in r.loads:
            yield f"{r.label} without {x.name}", row.with_term(CONST, row.get(CONST) + x.value)
            yield f"{r.label} {x.name} sign", row.with_term(CONST,
                                                           row.get(CONST) + 2 * x.value)
        for k in sorted(row.unknowns & set(br.joints)):
            yield f"{r.label} without {k}", row.without([k])
            yield f"{r.label} {k} sign", row.with_term(k, -row.get(k))
        if r.euler:
            for p in br.points:
                yield f"{r.label} about {p.name} with I_G", br.transport(r, p, keep_acc=False)


def _holds(model: mbody.Model, body: str, s: Row) -> bool:
    """Whether row `s` of `body` holds at the model's solution (accelerations and
    reactions from `Assembly.solve`, not from the checker)."""
    asm = mbody.assemble(model)
    coordinate = {r.acc: r.label for r in body_rows(asm, body).rows}
    sol = asm.solve()
    terms = [v * (1.0 if k == CONST else sol.reactions[k] if k in sol.reactions
                  else sol[coordinate[k]]) for k, v in s.coef.items()]
    return abs(sum(terms)) <= 1e-9 * max(1.0, sum(map(abs, terms)))


@pytest.mark.parametrize("name", [n for n, _ in _models_with_joints()])
def test_the_usual_mistakes_stay_diagnosed_as_without_the_kinematics(name):
    """Every usual mistake on every row of a shipped model with joints gets the same
    diagnosis and row with the joints' kinematics known as without them. One becomes
    `correct` only where the term it changes is zero for every motion the joints allow
    (the transport term r × m a_G where the joints hold a_G at 0 or along r; a fixed
    pivot's row that says I_P alpha_2 = 0, as before): the equation then holds at the
    solved state."""
    m = mbody.load(MODELS / name)
    asm = mbody.assemble(m)
    seen = now_true = 0
    for b in m.body_names:
        br = body_rows(asm, b)
        if br.kinematics is None:
            continue
        bare = dataclasses.replace(br, kinematics=None)
        for what, s in _mistakes(br):
            before, after = diagnose(s, bare, 1e-3), diagnose(s, br, 1e-3)
            if before.diagnosis == "correct":
                continue  # a "mistake" that changes nothing here (a zero term)
            seen += 1
            if after.diagnosis == "correct":
                assert "kinematics" in after.details or \
                    after.details.get("form") == "fixed_pivot", (name, what)
                assert _holds(m, b, s), (name, what, after.explanation)
                # and it is a moment equation about a point (the mistake's, or one on
                # the same axis), whose transport term the joints hold at 0: only a
                # moment taken about a point with I_G, or a reaction left out (one
                # through that point); never a Newton row, a sign, a load, the gyroscopic
                # term
                dropped = what.partition(" without ")[2]
                assert after.details.get("form") in ("transport", "fixed_pivot") and (
                    what.endswith(" with I_G") or dropped in br.joints
                ), (name, what, after.explanation)
                now_true += 1
            elif before.diagnosis != "not_an_equation_of_this_body":
                assert (after.diagnosis, after.row) == (before.diagnosis, before.row), (
                    name, what, after.explanation)
    if not seen:
        pytest.skip("no body whose accelerations the joints relate")
    assert now_true < seen


def test_a_reversed_reaction_where_the_joints_hold_the_acceleration_at_zero():
    # the flyball governor's arm: the joints hold a_y at 0, so Newton's row along y
    # says hinge_a.Fz = 0; writing a_y with the reaction reversed is still that mistake
    m = mbody.load(MODELS / "flyball_governor.yaml")
    br = body_rows(mbody.assemble(m), "arm_a")
    assert "a_y = 0" in [r.text for r in br.kinematics.relations]
    row = next(r for r in br.rows if r.label == "arm_a.y").row
    c = one(m, "arm_a", _written(row.with_term("hinge_a.Fz", -row.get("hinge_a.Fz"))))
    assert c.diagnosis == "reaction_sign", c.explanation
    # leaving the zero acceleration out is right: the joints hold it
    c = one(m, "arm_a", _written(row.without(["a_y"])))
    assert c.correct and c.details["kinematics"] == ["a_y = 0"], c.explanation


def test_kinematics_with_a_wrong_term_are_diagnosed_with_them(moving):
    # the sign of alpha x r: not correct, and compared with Newton's row along x
    c = one(moving, "rod", "m*(-alpha*0.433013 - w^2*0.25) = O.Fx")
    assert c.diagnosis == "not_an_equation_of_this_body" and c.row == "rod.x"
    assert "alpha has -0.866026 where 0.866025 is expected" in " ".join(c.explanation.split())
    assert c.details["kinematics"] == ["a_x = 0.433013 alpha - 2.25"]
    # the centripetal term left out: the constant is what is missing
    c = one(moving, "rod", "m*0.433013*alpha = O.Fx")
    assert c.diagnosis == "not_an_equation_of_this_body" and c.row == "rod.x"
    assert "the constant is missing (expected -4.5)" in " ".join(c.explanation.split())
    # a mistake of the table made with the kinematics right: named, and the rest said
    c = one(moving, "rod", "m*(0.433013*alpha - w^2*0.25) = -O.Fx")
    assert c.diagnosis == "reaction_sign" and c.row == "rod.x"
    assert "writes the rest of the row right, with a_x written" in \
        " ".join(c.explanation.split())
    c = one(moving, "rod", "m*(0.25*alpha + w^2*0.433013) = O.Fy + m*g")
    assert c.diagnosis == "applied_load_sign" and c.row == "rod.y"


def test_a_reaction_replaced_by_its_solved_value_is_not_made_a_pivot_equation():
    # without the pivot's angular acceleration, a reaction-free equation of a body
    # with one degree of freedom is not taken as the moment about the pivot
    c = one(mbody.load(MODELS / "pendulum.yaml"), "rod", "2*a_y = 15.9435 - 19.62")
    assert c.diagnosis == "reaction_treated_as_known", c.explanation


# == review R5-2: numbers put in for reactions, or the answer, are not a pivot equation ===

def _pendulum_solution():
    m = mbody.load(MODELS / "pendulum.yaml")
    return m, mbody.assemble(m).solve()


def test_both_pin_forces_replaced_by_their_values_are_treated_as_known():
    # the review's [1]: the Euler row about G with O.Fx and O.Fy replaced by their solved
    # values (from Assembly.solve, written to six figures) was `correct`, "moments about
    # joint O, a fixed pivot"
    m, sol = _pendulum_solution()
    fx, fy = sol.reactions["O.Fx"], sol.reactions["O.Fy"]
    for eq in (f"I_G*alpha = -0.433013*({fx:.6g}) - 0.25*({fy:.6g})",
               f"I_G*alpha = {-0.4330127 * fx - 0.25 * fy:.6g}"):
        c = one(m, "rod", eq)
        assert (c.diagnosis, c.row) == ("reaction_treated_as_known", "rod.theta"), eq
        assert c.details["reactions"] == ["O.Fx", "O.Fy"]
        assert "I_P" not in c.explanation


def test_a_pin_force_replaced_by_its_value_with_a_g_from_the_pin_is_treated_as_known():
    # the review's [5]: Newton's row along x with a_x = 0.433013 alpha and O.Fx's value,
    # the case docs/verify.md promises stays reaction_treated_as_known, written in alpha
    m, sol = _pendulum_solution()
    fx, fy = sol.reactions["O.Fx"], sol.reactions["O.Fy"]
    c = one(m, "rod", f"m*0.433013*alpha = {fx:.6g}")
    assert (c.diagnosis, c.row) == ("reaction_treated_as_known", "rod.x"), c.explanation
    assert c.details["value_used"] == pytest.approx(fx, rel=1e-5)
    assert c.details["kinematics"] == ["a_x = 0.433013 alpha"]
    c = one(m, "rod", f"m*0.25*alpha = {fy:.6g} - m*g")
    assert (c.diagnosis, c.row) == ("reaction_treated_as_known", "rod.y"), c.explanation
    assert c.details["value_used"] == pytest.approx(fy, rel=1e-5)


def test_the_answer_copied_is_a_solved_value_and_covers_no_row():
    # alpha = -7.3529, copied from `mbody solve`, was `correct` and covered rod.theta
    m, sol = _pendulum_solution()
    alpha = sol["rod.theta"]
    eqs = [f"alpha = {alpha:.6g}", f"-alpha = {-alpha:.6g}", f"{alpha:.6g} = alpha",
           "alpha = -m*g*0.5*sin(theta)/(I_G + m*0.5^2)"]
    v = verify(m, [{"body": "rod", "eq": eq} for eq in eqs])
    for c in v.checks:
        assert (c.diagnosis, c.row) == ("solved_value_not_an_equation", "rod.theta"), c.eq
        assert c.details["value_solved"] == pytest.approx(alpha, rel=1e-12)
        assert "I_P α = M_P" in c.explanation
    assert {u.row for u in v.uncovered} == {"rod.x", "rod.y", "rod.theta"}
    # a reaction's value alone, and a value on a body with no fixed pivot
    c = one(m, "rod", f"O.Fx = {sol.reactions['O.Fx']:.6g}")
    assert (c.diagnosis, c.row) == ("solved_value_not_an_equation", "rod.x"), c.explanation
    dp = mbody.load(MODELS / "double_pendulum.yaml")
    c = one(dp, "lower", f"alpha = {mbody.assemble(dp).solve()['lower.theta']:.6g}")
    assert c.diagnosis == "solved_value_not_an_equation", c.explanation
    # a value that is not the solution is no solved value
    assert one(m, "rod", f"alpha = {2 * alpha:.6g}").diagnosis == \
        "not_an_equation_of_this_body"


@pytest.mark.parametrize("moving_rod", [False, True], ids=["at rest", "at 3 rad/s"])
def test_the_moment_about_the_fixed_pin_stays_correct_written_any_way(moving_rod, moving):
    """I_P alpha = M_P about the pin (the pin's forces pass through it), I_P = I_G +
    m d², d = 0.5 m, M_P = -m g d sin(theta): as written, with numbers, or divided by m
    ((k_G² + d²) alpha = -g d sin theta), it is `correct`; it holds at the solution. Any
    other multiple says no more than alpha's value (the answer doubled, or the law with
    another mass, would pass too: review R6-1) and is `solved_value_not_an_equation`."""
    m = moving if moving_rod else mbody.load(MODELS / "pendulum.yaml")
    mass, inertia = 2.0, float(m.J[0][2, 2])
    i_p, m_p = inertia + mass * 0.25, -mass * 9.81 * 0.5 * math.sin(math.radians(30))
    assert mbody.assemble(m).solve()["rod.theta"] * i_p == pytest.approx(m_p, rel=1e-9)
    eqs = ["(I_G + m*0.5^2)*alpha = -m*g*0.5*sin(theta)",
           "(I_G/m + 0.5^2)*alpha = -g*0.5*sin(theta)",
           f"{i_p:.6g}*alpha = {m_p:.6g}", f"{m_p:.6g} = {i_p:.6g}*alpha",
           f"{-i_p:.6g}*alpha = {-m_p:.6g}", f"{i_p / mass:.6g}*alpha = {m_p / mass:.6g}"]
    v = verify(m, [{"body": "rod", "eq": eq} for eq in eqs])
    for c in v.checks:
        assert c.correct and c.row == "rod.theta", (c.eq, c.diagnosis, c.explanation)
        assert c.details["form"] == "fixed_pivot"
    # other multiples: the answer scaled, the law with a 5 kg rod for the model's 2 kg
    # (its inertia comes from its shape: the mass cancels), or divided by g
    k_g2 = (0.05**2 + 1.0**2) / 12.0
    others = [f"{2 * i_p:.6g}*alpha = {2 * m_p:.6g}", f"{i_p / 9.81:.6g}*alpha = -m*0.5*0.5",
              f"10*alpha = {10 * m_p / i_p:.6g}",
              f"5*({k_g2:.8g} + 0.5^2)*alpha = -5*9.81*0.5*sin(theta)"]
    wrong = verify(m, [{"body": "rod", "eq": eq} for eq in others], require="rod.theta")
    for c in wrong.checks:
        assert not c.correct and c.diagnosis == "solved_value_not_an_equation", \
            (c.eq, c.diagnosis)
    assert wrong.covered == 0 and not wrong.all_correct


def test_a_moment_equation_is_not_read_as_a_newton_row_with_kinematics():
    c = one(mbody.load(MODELS / "slider_crank.yaml"), "crank",
            "I_G*alpha = -60 - 0.025*O.Fy + 0.025*A.Fy")
    assert c.row == "crank.theta" and "kinematics" not in c.details


def test_a_reaction_the_model_gives_holds_no_joint():
    # the spinning disc's bearings A and B have their forces given: the disc is free,
    # and its rows are compared as written
    br = body_rows(mbody.assemble(mbody.load(MODELS / "spinning_disc_bearings.yaml")), "disc")
    assert br.kinematics is None


def test_beyond_the_bound_fewer_relations_never_a_wrong_one(monkeypatch):
    from mbody.answers import kinematics

    m = mbody.load(MODELS / "double_pendulum.yaml")
    asm = mbody.assemble(m)
    full = body_rows(asm, "lower").kinematics
    assert full is not None and full.sources == ("joint O", "joint A")
    monkeypatch.setattr(kinematics, "MAX_COORDINATES", 3)  # the lower rod alone
    assert body_rows(asm, "lower").kinematics is None
    assert body_rows(asm, "upper").kinematics.sources == ("joint O",)


def test_a_fast_cranks_moment_about_its_pivot_keeps_the_constants_tolerance():
    """About a fixed pivot the centripetal terms' moments cancel (d x (w x (w x d)) = 0 in
    the plane); their sizes once widened the constant's tolerance with w² (review R6-2):
    at 600 rad/s a constant 0.2 % off passed. Now the constant is compared at its own
    magnitude, as about G."""
    from mbody.answers.rows import body_rows

    model = mbody.load(MODELS / "slider_crank.yaml").with_values(
        {"bodies.crank.angular_velocity": 600})
    rows = body_rows(mbody.assemble(model), "crank")
    (pivot,) = [p for p in rows.points if p.name == "joint O"]
    t = rows.about_fixed_point(rows.euler[0], pivot)
    assert t.err("1") == pytest.approx(abs(t.get("1")), rel=1e-12)

    def written(off: float) -> str:
        c = t.coef
        return (f"{c['alpha']:.6g}*alpha = {-c['1'] * off:.6g} + {-c['A.Fx']:.6g}*A.Fx"
                f" + {-c['A.Fy']:.6g}*A.Fy")

    v = verify(model, [{"body": "crank", "eq": written(off)} for off in (1.0, 1.002)])
    assert [c.diagnosis for c in v.checks] == ["correct", "rounded_too_coarsely"]

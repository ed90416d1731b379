"""`mbody.verify` with a_G written from the joints' kinematics in every direction (review
R5, R5-1 and R5-7).

A joint's relation may be put into a row either way: the screw's a_z = h alpha_3 written
for a_z in Newton's row, or as alpha_3 = a_z / h in Euler's. Whichever acceleration the
student writes, a true equation is `correct` and counted for the row it came from.

The equations here are built without the checker: from closed forms (a_z = h alpha_3 of
a screw of lead p, h = p / 2 pi; a_y = -0.75 a_x on an incline along (0.8, -0.6);
a_G = alpha x r - w^2 r of a pinned rod) and, for every shipped model, from the
accelerations `Assembly.solve` gives at several motions the joints allow (the model's
gravity changed: the relations are the joints', not the loads'), never from
`mbody.answers.kinematics`. Each is checked to hold at the solved state before it is
given to the checker, and each has a wrong twin that must stay wrong.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.answers import verify

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"


def one(model, body: str, eq: str):
    return verify(model, [{"body": body, "eq": eq}]).checks[0]


def holds(model: mbody.Model, body: str, lhs_minus_rhs: dict[str, float]) -> bool:
    """Whether Σ c_k k = 0 at the model's solution (`Assembly.solve`); keys are the
    answers' names (a_x, alpha_3, a reaction's label) and '1' for the constant."""
    asm = mbody.assemble(model)
    sol = asm.solve()
    coord = {"a_x": "x", "a_y": "y", "a_z": "z", "alpha": "theta", "alpha_1": "w1",
             "alpha_2": "w2", "alpha_3": "w3"}
    terms = [c * (1.0 if k == "1" else sol.reactions[k] if k in sol.reactions
                  else sol[f"{body}.{coord[k]}"]) for k, c in lhs_minus_rhs.items()]
    return abs(sum(terms)) <= 1e-9 * max(1.0, sum(map(abs, terms)))


def text(coef: dict[str, float]) -> str:
    """``Σ c_k k = 0`` with 12 significant figures."""
    return " + ".join(f"({c:.12g})" + ("" if k == "1" else f"*{k}")
                      for k, c in coef.items() if c != 0.0) + " = 0"


# == the screw jack: a_z = h alpha_3 ====================================================

LEAD = 0.005                      # m per turn (models/screw_jack.yaml)
H = LEAD / (2 * math.pi)          # m per rad
J3 = 4.0 * 0.02**2 / 2            # the screw about its axis, m r^2 / 2 (kg m^2)
TAU = 2.0                         # N m


@pytest.fixture(scope="module")
def jack() -> mbody.Model:
    return mbody.load(MODELS / "screw_jack.yaml")


def test_the_screw_jacks_relation_is_the_lead(jack):
    sol = mbody.assemble(jack).solve()
    assert sol["screw.z"] == pytest.approx(H * sol["screw.w3"], rel=1e-9)
    assert sol["platform.z"] == pytest.approx(sol["screw.z"], rel=1e-9)


def test_the_screws_rows_with_the_lead_put_in_either_way_are_correct(jack):
    # Euler's row about the axis, J alpha_3 = tau - h N.Wz, with alpha_3 = a_z / h: the
    # review's equation, rejected before (the checker solved for a_z only)
    euler = {"a_z": J3 / H, "1": -TAU, "N.Wz": H}
    # Newton's row along z, m a_z = -m g + N.Wz - T.Fz, with a_z = h alpha_3
    newton = {"alpha_3": 4.0 * H, "1": 4.0 * 9.81, "N.Wz": -1.0, "T.Fz": 1.0}
    for coef in (euler, newton):
        assert holds(jack, "screw", coef)
    v = verify(jack, [{"body": "screw", "eq": text(euler)},
                      {"body": "screw", "eq": text(newton)},
                      {"body": "screw", "eq": "0.0008*a_z/0.000795775 = 2 - "
                       "0.000795775*N.Wz"}])
    assert [c.diagnosis for c in v.checks] == ["correct"] * 3, v.checks[0].explanation
    assert [c.row for c in v.checks] == ["screw.w3", "screw.z", "screw.w3"]
    assert "alpha_3 written from the kinematics of joint N" in \
        " ".join(v.checks[0].explanation.split())
    # the relation as the student used it: alpha_3 = a_z / h
    (rel,) = v.checks[0].details["kinematics"]
    assert rel.startswith("alpha_3 = ") and rel.endswith(" a_z")
    assert float(rel.split()[2]) == pytest.approx(1 / H, rel=1e-5)


def test_the_screws_rows_with_a_mistake_stay_wrong_either_way(jack):
    # the nut's moment reversed, with alpha_3 = a_z / h
    c = one(jack, "screw", text({"a_z": J3 / H, "1": -TAU, "N.Wz": -H}))
    assert not c.correct and c.row == "screw.w3", c.explanation
    # the relation the wrong way round: alpha_3 = h a_z
    c = one(jack, "screw", text({"a_z": J3 * H, "1": -TAU, "N.Wz": H}))
    assert not c.correct
    # the motor torque left out
    c = one(jack, "screw", text({"a_z": J3 / H, "N.Wz": H}))
    assert c.diagnosis == "missing_applied_load" and c.row == "screw.w3", c.explanation
    # the platform's weight left out of Newton's row written with alpha_3
    c = one(jack, "screw", text({"alpha_3": 4.0 * H, "1": 4.0 * 9.81, "N.Wz": -1.0}))
    assert c.diagnosis == "missing_reaction" and c.row == "screw.z", c.explanation


# == a block on an incline: a_y = -0.75 a_x =============================================

INCLINE = """\
model: incline
dimension: 2
gravity: [0, -9.81]
bodies:
  - {name: block, mass: 2.0, inertia: 0.1, position: [0, 0], angle: 0}
joints:
  - {name: P, type: prismatic, parent: ground, child: block, at: [0, 0], axis: [0.8, -0.6]}
"""
# the normal force P.Fy acts along (0.6, 0.8), the slide's normal: m a_x = 0.6 P.Fy,
# m a_y = 0.8 P.Fy - m g; the block slides along (0.8, -0.6): a_y = -0.75 a_x, alpha = 0
ROWS = {"block.x": ({"a_x": 2.0, "P.Fy": -0.6}, "a_x"),
        "block.y": ({"a_y": 2.0, "P.Fy": -0.8, "1": 19.62}, "a_y")}
WRITTEN_AS = {("a_x", "a_y"): -1 / 0.75, ("a_y", "a_x"): -0.75}  # (row's, written) -> factor


@pytest.fixture(scope="module")
def incline() -> mbody.Model:
    return mbody.loads(INCLINE)


def _other(coef: dict[str, float], acc: str, written: str) -> dict[str, float]:
    out = {k: v for k, v in coef.items() if k != acc}
    out[written] = coef[acc] * WRITTEN_AS[(acc, written)]
    return out


def test_the_inclines_relation_is_the_slope(incline):
    sol = mbody.assemble(incline).solve()
    assert sol["block.y"] == pytest.approx(-0.75 * sol["block.x"], rel=1e-9)
    assert sol["block.theta"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("label", sorted(ROWS))
def test_each_incline_row_written_in_either_acceleration_is_correct(incline, label):
    coef, acc = ROWS[label]
    for written in ("a_x", "a_y"):
        eq = coef if written == acc else _other(coef, acc, written)
        assert holds(incline, "block", eq)
        c = one(incline, "block", text(eq))
        assert c.correct and c.row == label, (written, c.explanation)
        if written != acc:
            assert c.details["kinematics"] == [f"{acc} = {WRITTEN_AS[(acc, written)]:.6g} "
                                               f"{written}"]


@pytest.mark.parametrize("label", sorted(ROWS))
def test_each_incline_row_with_a_mistake_stays_that_mistake_in_either_acceleration(
        incline, label):
    coef, acc = ROWS[label]
    for written in ("a_x", "a_y"):
        eq = coef if written == acc else _other(coef, acc, written)
        c = one(incline, "block", text({**eq, "P.Fy": -eq["P.Fy"]}))
        assert (c.diagnosis, c.row) == ("reaction_sign", label), (written, c.explanation)
        if "1" in eq:  # gravity left out of the row along y
            c = one(incline, "block", text({k: v for k, v in eq.items() if k != "1"}))
            assert (c.diagnosis, c.row) == ("missing_applied_load", label), c.explanation
    # the row's forces with the other acceleration as if it were the row's own
    swapped = {("a_y" if k == "a_x" else "a_x" if k == "a_y" else k): v
               for k, v in coef.items()}
    assert not one(incline, "block", text(swapped)).correct


def test_the_inclines_euler_row_with_the_slides_alpha_0(incline):
    c = one(incline, "block", "0 = P.Mz")
    assert c.correct and c.row == "block.theta" and c.details["kinematics"] == ["alpha = 0"]


# == a pinned rod: a_G = alpha x r - w^2 r ================================================

MOVING = """\
model: moving-pendulum
dimension: 2
gravity: [0, -9.81]
bodies:
  - name: rod
    mass: 2
    inertia: 0.1666666667
    angle: 30 deg
    position: [0.25, -0.4330127019]
    angular_velocity: 3
    velocity: [1.299038106, 0.75]
joints:
  - {name: O, type: revolute, parent: ground, child: rod, at: [0, 0]}
"""


def _pendulum_cases():
    """(what, model, w, r, I_G): the shipped pendulum at rest, and a rod turning at
    3 rad/s; r = G - O, O at the origin, at 30 degrees from the downward vertical."""
    r = (0.25, -0.4330127019)
    shipped = mbody.load(MODELS / "pendulum.yaml")
    return [("at rest", shipped, 0.0, r, float(shipped.J[0][2, 2])),
            ("at 3 rad/s", mbody.loads(MOVING), 3.0, r, 0.1666666667)]


def _affine(w: float, r: tuple[float, float]) -> dict[str, tuple[float, float]]:
    """Each acceleration as p alpha + q: a_G = alpha x r - w^2 r."""
    return {"a_x": (-r[1], -w * w * r[0]), "a_y": (r[0], -w * w * r[1]), "alpha": (1.0, 0.0)}


def _written_from(coef: dict[str, float], acc: str, written: str,
                  aff: dict[str, tuple[float, float]]) -> dict[str, float]:
    """`coef` with `acc` replaced by its value in terms of `written`:
    acc = (p_acc / p_w)(written - q_w) + q_acc."""
    (pa, qa), (pw, qw) = aff[acc], aff[written]
    c = coef[acc]
    out = {k: v for k, v in coef.items() if k != acc}
    out[written] = out.get(written, 0.0) + c * pa / pw
    out["1"] = out.get("1", 0.0) + c * (qa - pa * qw / pw)
    return out


def _pendulum_rows(m: float = 2.0, inertia: float = 0.1666666667,
                   r=(0.25, -0.4330127019)) -> dict[str, tuple[dict[str, float], str]]:
    # Newton: m a_x = O.Fx, m a_y = O.Fy - m g; Euler about G: I_G alpha = (O - G) x F_O
    return {"rod.x": ({"a_x": m, "O.Fx": -1.0}, "a_x"),
            "rod.y": ({"a_y": m, "O.Fy": -1.0, "1": m * 9.81}, "a_y"),
            "rod.theta": ({"alpha": inertia, "O.Fx": -r[1], "O.Fy": r[0]}, "alpha")}


@pytest.mark.parametrize("case", [0, 1], ids=["at rest", "at 3 rad/s"])
def test_each_pendulum_row_written_in_any_of_its_accelerations_is_correct(case):
    what, model, w, r, inertia = _pendulum_cases()[case]
    aff = _affine(w, r)
    sol = mbody.assemble(model).solve()
    for acc, (p, q) in aff.items():  # the closed form holds for the solver's motion
        lab = {"a_x": "rod.x", "a_y": "rod.y", "alpha": "rod.theta"}[acc]
        assert sol[lab] == pytest.approx(p * sol["rod.theta"] + q, rel=1e-8, abs=1e-9)
    answers, expect = [], []
    for label, (coef, acc) in _pendulum_rows(inertia=inertia).items():
        for written in aff:
            eq = coef if written == acc else _written_from(coef, acc, written, aff)
            assert holds(model, "rod", eq), (what, label, written)
            answers.append({"body": "rod", "eq": text(eq)})
            expect.append((label, written))
            # and a wrong twin: the row's first pin force reversed
            k = next(k for k in eq if k.startswith("O."))
            answers.append({"body": "rod", "eq": text({**eq, k: -eq[k]})})
            expect.append((label, None))
    v = verify(model, answers)
    for c, (label, written) in zip(v.checks, expect, strict=True):
        if written is None:
            assert not c.correct and c.row == label and c.diagnosis in (
                "reaction_sign", "lever_arm_sign"), (what, c.eq, c.explanation)
        else:
            assert c.correct and c.row == label, (what, written, c.eq, c.explanation)


@pytest.mark.parametrize("case", [0, 1], ids=["at rest", "at 3 rad/s"])
def test_the_moment_about_the_pin_with_a_y_written_from_alpha_or_from_a_x(case):
    """Moments about O with the transport term, I_G alpha + m (r x a_G) = -m g r_x, with
    a_y put in and a_x and alpha written: the student may have used a_y = r_x alpha - w^2
    r_y or the same relation in a_x. Both are the moment about O (the joints relate
    the two accelerations written, so either way of writing a_y is true)."""
    what, model, w, r, inertia = _pendulum_cases()[case]
    m = 2.0
    aff = _affine(w, r)
    about_o = {"alpha": inertia, "a_y": m * r[0], "a_x": -m * r[1], "1": m * 9.81 * r[0]}
    for written in ("alpha", "a_x"):
        eq = _written_from(about_o, "a_y", written, aff)
        assert set(eq) >= {"alpha", "a_x"} and "a_y" not in eq
        assert holds(model, "rod", eq)
        c = one(model, "rod", text(eq))
        assert c.correct and c.row == "rod.theta", (what, written, c.explanation)
        assert c.details["form"] == "transport" and c.details["point"] == "joint O"
        # without the transport term's a_x part: not the moment about O
        c = one(model, "rod", text({k: v for k, v in eq.items() if k != "a_x"}))
        assert not c.correct, (what, written, c.explanation)


# == every shipped model: relations from the solver's motions =============================

def _motions(model: mbody.Model) -> list:
    """Solutions at the model's state under four gravities: the accelerations of four
    motions the joints allow from the same positions and velocities."""
    g = np.asarray(model.gravity, dtype=float)[: model.dimension]
    kicks = [np.zeros_like(g), 2.0 * g + 1.0, -g + np.arange(1, len(g) + 1),
             0.5 * g - np.arange(len(g), 0, -1)]
    out = []
    for k in kicks:
        changed = model.with_values({"gravity": (g + k).tolist()}) if k.any() else model
        out.append(mbody.assemble(changed, model.initial).solve())
    return out


_NAMES = {"x": "a_x", "y": "a_y", "z": "a_z", "theta": "alpha", "w1": "alpha_1",
          "w2": "alpha_2", "w3": "alpha_3"}


def _one_freedom_bodies(model: mbody.Model):
    """(body, {acceleration name: (slope, value)}) for each body whose accelerations move
    along one line over the four motions (each acceleration = value + slope s): a body
    the joints leave one degree of freedom, its relations a = value_a + slope_a/slope_b
    (b - value_b) between any two that move."""
    sols = _motions(model)
    for b in model.body_names:
        labels = [c for c in model.coordinates if c.rpartition(".")[0] == b]
        A = np.array([[s[lab] for lab in labels] for s in sols])
        D = A[1:] - A[0]
        sv = np.linalg.svd(D, compute_uv=False)
        if sv[0] <= 1e-9 * max(1.0, float(np.abs(A).max())) or sv[1] > 1e-9 * sv[0]:
            continue  # fixed by a driver, or more than one freedom
        _, _, vt = np.linalg.svd(D)
        slope = vt[0]
        yield b, {_NAMES[lab.rpartition(".")[2]]: (float(slope[j]), float(A[0, j]))
                  for j, lab in enumerate(labels)}


def _models_with_joints():
    for path in sorted(MODELS.glob("*.yaml")):
        m = mbody.load(path)
        if len(m.reactions) and not m.known_reactions_at(m.initial.t):
            yield path.name


@pytest.mark.parametrize("name", list(_models_with_joints()))
def test_every_row_with_its_accelerations_written_from_any_other_is_correct(name):
    """Each row of each body with one degree of freedom, its accelerations written in
    terms of another of the body's (each other one that moves, in turn) through the
    relation the solver's motions give, numbers to 12 figures, is `correct` and that row;
    the same with a reaction reversed is not."""
    from mbody.answers.rows import body_rows  # only the rows, not the relations

    m = mbody.load(MODELS / name)
    asm = mbody.assemble(m)
    answers, expect = [], []
    for b, line in _one_freedom_bodies(m):
        big = max(abs(s) for s, _ in line.values())
        moving = [a for a, (s, _) in line.items() if abs(s) > 1e-6 * big]
        br = body_rows(asm, b)
        for r in br.rows:
            reactions = sorted(k for k in r.row.unknowns if k in br.joints)
            accs = [k for k in r.row.unknowns if k not in br.joints]
            if not reactions or not accs:
                continue
            for w in moving:
                if accs == [w]:
                    continue  # nothing to put in
                sw, vw = line[w]
                coef = {k: v for k, v in r.row.coef.items() if k not in accs}
                size = abs(coef.get("1", 0.0))
                for a in accs:
                    if a == w:
                        coef[w] = coef.get(w, 0.0) + r.row.get(a)
                        continue
                    sa, va = line[a]
                    c = r.row.get(a)
                    coef[w] = coef.get(w, 0.0) + c * sa / sw
                    coef["1"] = coef.get("1", 0.0) + c * (va - sa / sw * vw)
                    size += abs(c) * (abs(va) + abs(sa / sw * vw))
                if abs(coef.get("1", 0.0)) <= 1e-9 * size:
                    coef["1"] = 0.0  # the solver's rounding: a student writes no constant
                if abs(coef.get(w, 0.0)) <= 1e-9 * max(map(abs, coef.values())):
                    continue  # the row's accelerations cancel in w: no term to write
                answers.append({"body": b, "eq": text(coef)})
                expect.append((b, r.label, w, True))
                k = reactions[0]
                answers.append({"body": b, "eq": text({**coef, k: -coef[k]})})
                expect.append((b, r.label, w, False))
    if not answers:
        pytest.skip("no body of one degree of freedom with a row to write another way")
    v = verify(m, answers, asm=asm)
    for c, (_, label, w, right) in zip(v.checks, expect, strict=True):
        if right:
            assert c.correct and c.row == label, (name, label, w, c.eq, c.explanation)
        else:
            assert not c.correct, (name, label, w, c.eq, c.explanation)

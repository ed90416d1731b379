"""Batched evaluation: `mbody.solve_many` and the compiled core's loops over states
(``Unknowns.solve_many``, ``kinematics_many``) against one solve, one kinematic analysis
at a time; many values of one structure (`mbody.solve.family.Family`) against models
read afresh with `Model.with_values`."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.equations.pack import pack_model
from mbody.kernel import _core
from mbody.solve.batch import Evaluator, closed
from mbody.solve.family import Family, pack

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
SHIPPED = ["slider_crank", "fourbar_planar", "fourbar_spatial", "bricard", "heavy_top",
           "point_pendulum", "triple_pendulum", "rotor_gyroscopic_bearings",
           "spring_mass_damper", "seed_example_1"]


def driven(speed: str = "100") -> mbody.Model:
    """The shipped slider-crank without its loads, its crank driven at `speed`."""
    text = (MODELS / "slider_crank.yaml").read_text()
    text = "\n".join(line for line in text.splitlines()
                     if "{name: gas" not in line and "{name: load" not in line)
    text += f"\ndrivers:\n  - {{name: motor, joint: O, speed: {speed}}}\n"
    return mbody.loads(text, "driven.yaml")


def moved(model: mbody.Model, rng: np.random.Generator, k: int) -> list[mbody.State]:
    """k states near the initial one (off the joints too: a solve is defined anywhere)."""
    s0 = model.initial
    out = []
    for i in range(k):
        q = s0.quaternion + 0.05 * rng.standard_normal(s0.quaternion.shape)
        if model.dimension == 2:
            q[:, 1:3] = 0.0
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        vel = s0.velocity + rng.standard_normal(s0.velocity.shape)
        om = s0.omega + rng.standard_normal(s0.omega.shape)
        if model.dimension == 2:
            vel[:, 2] = 0.0
            om[:, :2] = 0.0
        out.append(mbody.State(s0.position + 0.01 * rng.standard_normal(s0.position.shape),
                               q, vel, om, t=0.01 * i))
    return out


@pytest.mark.parametrize("name", SHIPPED)
def test_solve_many_is_each_solve_bit_for_bit(name):
    """The same C function on the same input: accelerations and every reaction value
    equal those of Assembly.solve at each state, to the last bit."""
    model = mbody.load(MODELS / f"{name}.yaml")
    states = [model.initial, *moved(model, np.random.default_rng(7), 12)]
    sols = mbody.solve_many(model, states)
    assert sols.errors == (None,) * len(states)
    for k, s in enumerate(states):
        one = mbody.assemble(model, s).solve()
        assert np.array_equal(sols.accelerations[k], one.accelerations), (name, k)
        assert np.array_equal(sols.values[k], np.array([one.reactions[r]
                                                        for r in model.reactions])), (name, k)


def test_the_core_loop_checks_its_arguments():
    model = driven()
    ev = Evaluator(model)
    solver = ev.plan.solver
    y = ev.ws.pack_state(model.initial)
    out = np.empty((2, ev.width))
    t = np.zeros(2)
    Y = np.stack([y, y])
    F, _ = pack_model(model)
    with pytest.raises(ValueError, match="Y: expected 2 states"):
        solver.solve_many(t, np.ascontiguousarray(Y[:, :-1]), ev.unknowns.lam, out, None,
                          None, None)
    with pytest.raises(ValueError, match="lam: expected"):
        solver.solve_many(t, Y, np.zeros(3), out, None, None, None)
    with pytest.raises(ValueError, match="rows\\[1\\] = 1: F has 1 rows"):
        solver.solve_many(t, Y, ev.unknowns.lam, out, F[None], np.array([0, 1]), None)
    with pytest.raises(ValueError, match="F and rows: give both"):
        solver.solve_many(t, Y, ev.unknowns.lam, out, F[None], None, None)
    with pytest.raises(ValueError, match="F: expected rows of"):
        solver.solve_many(t, Y, ev.unknowns.lam, out, F[:-1][None], np.zeros(2, np.int64), None)
    solver.solve_many(t, Y, ev.unknowns.lam, out, np.stack([F, F]), np.array([1, 0]), None)
    assert np.array_equal(out[0], ev.solve(t[:1], Y[:1])[0])
    # states index Y: one stored state solved twice, with each F
    again = ev.solve(t, Y[:1], np.stack([F, F]), np.array([1, 0]), np.array([0, 0]))
    assert np.array_equal(again, out)
    with pytest.raises(ValueError, match="states\\[1\\] = 3: Y holds 2 states"):
        solver.solve_many(t, Y, ev.unknowns.lam, out, None, None, np.array([0, 3]))


def test_kinematics_many_takes_the_python_steps():
    """Exact mode: the Python loop's steps (project one step at a time), chained from the
    previous instant as mbody.kinematics(model, t, start=previous) is; fast mode (the
    mechanism is fully driven: Newton to the position, one velocity projection, started
    from the previous instant moved along its velocities) within the kinematic tolerance."""
    model = driven()
    ev = Evaluator(model)
    assert ev.fully_driven and ev.needs_assembly
    t = np.linspace(0.0, 2 * math.pi / 100, 73)
    ref, s = [], model.initial
    for tk in t:
        s = mbody.kinematics(model, float(tk), start=s)
        ref.append(ev.ws.state_vector(s))
    ref = np.array(ref)
    chain = np.ones(len(t), np.int64)
    chain[0] = 0
    for fast, predict, tol in ((False, False, 1e-15), (True, False, 1e-12), (True, True, 1e-12)):
        Y = np.tile(ev.ws.state_vector(model.initial), (len(t), 1))
        info = ev.kinematics(t, Y, chain=chain, fast=fast, predict=predict)
        assert closed(info).all()
        n = model.n
        size = ev.size
        assert np.abs(Y[:, :3 * n] - ref[:, :3 * n]).max() <= tol * size * 10
        assert np.abs(Y[:, 3 * n:7 * n] - ref[:, 3 * n:7 * n]).max() <= tol * 10
        speed = np.abs(ref[:, 7 * n:13 * n]).max()
        assert np.abs(Y[:, 7 * n:13 * n] - ref[:, 7 * n:13 * n]).max() <= 1e3 * tol * speed
        if predict:  # the predictor saves a step at every instant after the first
            assert np.median(info[1:, _core.KN_ITERS]) < 3


def test_kinematics_many_reports_a_loop_that_cannot_close():
    """A rod (0.043 m) shorter than the crank (0.05 m): near a crank angle of 90 degrees
    its pin cannot reach the cylinder's line. The loop's distance left stays above
    `CLOSED` exactly where mbody.kinematics raises."""
    model = driven().with_values({"joints.B.at.0": 0.06})
    ev = Evaluator(model)
    for t, can in ((0.0005, True), (0.00785, False)):
        Y = np.tile(ev.ws.state_vector(model.initial), (1, 1))
        info = ev.kinematics(np.array([t]), Y)
        assert closed(info)[0] == can
        if can:
            mbody.kinematics(model, t)
        else:
            with pytest.raises(mbody.MbodyError, match="cannot all close"):
                mbody.kinematics(model, t)


def values_grid():
    return [{"bodies.rod.mass": m, "drivers.motor.speed": w}
            for m in (0.3, 0.6, 1.1) for w in (50.0, 100.0, 240.0)]


def test_many_values_equal_models_read_afresh():
    """Each case composed from its probes is, bit for bit, F, the file's state and the
    extras of the model `with_values` builds; its solve at its own initial state equals
    that model's solve."""
    model = driven()
    values = values_grid()
    family = Family(model, ["bodies.rod.mass", "drivers.motor.speed"])
    cases = family.cases(values)
    assert family.separable and all(c.shared for c in cases)
    for v, c in zip(values, cases, strict=True):
        full = model.with_values(v)
        p = pack(full)
        assert np.array_equal(c.F, p.F) and np.array_equal(c.start, p.start)
        assert np.array_equal(c.extras, p.extras)
        assert c.extras[0] == v["drivers.motor.speed"]
    sols = mbody.solve_many(model, values=values)
    for k, v in enumerate(values):
        one = mbody.assemble(model.with_values(v)).solve()
        assert np.array_equal(sols.accelerations[k], one.accelerations)
        assert np.array_equal(sols.values[k], [one.reactions[r] for r in model.reactions])


def test_overlapping_paths_are_built_in_full():
    """A body's mass and its shape both set its inertia: the two paths touch the same
    entries, so each case is read in full (and still equals a fresh model)."""
    model = driven()
    values = [{"bodies.rod.mass": m, "bodies.rod.shape.box.0": a}
              for m in (0.5, 0.9) for a in (0.16, 0.2)]
    family = Family(model, ["bodies.rod.mass", "bodies.rod.shape.box.0"])
    cases = family.cases(values)
    for v, c in zip(values, cases, strict=True):
        assert np.array_equal(c.F, pack_model(model.with_values(v))[0])


def test_a_composition_that_differs_from_a_full_build_falls_back():
    """The safety net: if the probes' entries were incomplete (paths that do not act
    apart in a way the probes cannot see), the case read in full disagrees, and every
    case is then built in full."""
    model = driven()
    values = values_grid()
    family = Family(model, ["bodies.rod.mass", "drivers.motor.speed"])
    family.cases(values)  # every value probed
    assert family.separable
    family._touched["bodies.rod.mass"][0][:] = False  # pretend the mass touches nothing
    cases = family.cases(values)
    assert not family.separable
    for v, c in zip(values, cases, strict=True):
        assert np.array_equal(c.F, pack_model(model.with_values(v))[0])


def test_a_value_of_another_structure_and_a_refused_value():
    """A load that becomes an expression of t changes the packed programs (I): that case
    is solved on its own model; a refused value is that case's error, the others solve."""
    model = mbody.load(MODELS / "slider_crank.yaml")
    values = [{"loads.gas.force.0": -3000.0}, {"loads.gas.force.0": "-2000*exp(-100*t)"},
              {"loads.gas.force.0": "-2000*exp(-100*t"}]
    sols = mbody.solve_many(model, values=values)
    for k in (0, 1):
        one = mbody.assemble(model.with_values(values[k])).solve()
        assert np.array_equal(sols.accelerations[k], one.accelerations)
    assert sols.errors[0] is None and sols.errors[1] is None
    assert "loads.gas.force.0" in sols.errors[2] and np.isnan(sols.values[2]).all()


def test_states_and_values_pair_up():
    model = driven()
    states = [mbody.kinematics(model, t) for t in (0.0, 0.01, 0.02)]
    values = [{"bodies.rod.mass": m} for m in (0.4, 0.8, 1.6)]
    sols = mbody.solve_many(model, states, values=values)
    for k in range(3):
        one = mbody.assemble(model.with_values(values[k]), states[k]).solve()
        assert np.array_equal(sols.values[k], [one.reactions[r] for r in model.reactions])
    with pytest.raises(mbody.MbodyError, match="2 states for 3 sets"):
        mbody.solve_many(model, states[:2], values=values)


def test_values_of_the_wrong_form_are_refused_by_name():
    """One mapping where a list of them goes (a case per mapping): a TypeError naming
    `values` and the list of one that was meant (before: 'dictionary update sequence
    element #0 has length 1; 2 is required'); a case that is not a mapping, by its index."""
    model = mbody.load(MODELS / "pendulum.yaml")
    with pytest.raises(TypeError) as err:
        mbody.solve_many(model, values={"bodies.rod.mass": 2.0})
    msg = str(err.value)
    assert msg.startswith("values must be a list of mappings, one per case")
    assert "got dict" in msg and "values=[{...}]" in msg
    with pytest.raises(TypeError, match=r"^values\[1\] must be a mapping path -> value"):
        mbody.solve_many(model, values=[{"bodies.rod.mass": 2.0}, "bodies.rod.mass=3"])
    with pytest.raises(TypeError, match=r"^values must be a list of mappings"):
        mbody.solve_many(model, values="bodies.rod.mass=3")
    one = mbody.solve_many(model, values=({"bodies.rod.mass": 2.0},))   # any sequence
    assert np.array_equal(one.accelerations[0], mbody.assemble(
        model.with_values({"bodies.rod.mass": 2.0})).solve().accelerations)


def test_a_heavier_rod_needs_a_larger_torque_in_proportion():
    """Physics, not just agreement: with gravity off, the reactions and motor torque of a
    fully driven mechanism are linear in the masses and inertias; doubling every mass of
    the shipped shapes doubles them (inertias follow from the shapes)."""
    model = driven().with_values({"gravity": [0, 0]})
    paths = ["bodies.crank.mass", "bodies.rod.mass", "bodies.piston.mass"]
    base = [0.4, 0.6, 0.5]
    values = [dict(zip(paths, [f * m for m in base], strict=True)) for f in (1.0, 2.0)]
    state = mbody.kinematics(model, 0.013)
    sols = mbody.solve_many(model, state, values=values)
    assert np.allclose(sols.values[1], 2.0 * sols.values[0], rtol=1e-12, atol=1e-9)


def test_peaks_many_folds_the_same_solves():
    """The core's per-segment peaks are the largest |value| of solve_many's outputs over
    each segment, bit for bit (three cases of a mass each, 40 instants)."""
    model = driven()
    ev = Evaluator(model)
    family = Family(model, ["bodies.rod.mass"])
    F = np.stack([c.F for c in family.cases([{"bodies.rod.mass": m} for m in (0.3, 0.7, 1.9)])])
    t = np.linspace(0.0, 0.05, 40)
    Y = np.ascontiguousarray(np.tile(ev.ws.state_vector(model.initial), (40, 1)))
    chain = np.ones(40, np.int64)
    chain[0] = 0
    assert closed(ev.kinematics(t, Y, chain=chain, fast=True, predict=True)).all()
    T, S, R = np.tile(t, 3), np.tile(np.arange(40), 3), np.repeat(np.arange(3), 40)
    full = ev.solve(T, Y, F, R, S).reshape(3, 40, -1)[:, :, ev.o_lam:ev.o_lam + ev.m]
    peaks = ev.peaks(T, Y, S, 40, F, R)
    assert np.array_equal(peaks[:, :ev.m], np.abs(full).max(axis=1))
    assert not peaks[:, ev.m].any()
    with pytest.raises(ValueError, match="segment: expected a divisor"):
        ev.peaks(T, Y, S, 7, F, R)

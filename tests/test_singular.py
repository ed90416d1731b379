"""The constrained solve at and near singular positions, at extreme scales, and the
error for a motion without mass (mbody.nullspace, and the same in mbody.compiled)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fourbar_chain import FourbarChain

import mbody
from mbody import plan as planmod
from mbody.nullspace import NullSpaceSolve, SingularMassError

# Lengths that are powers of two: every crank's joint vectors are then the same numbers,
# so the data are those of an exact parallelogram and the solve alone is tested (with
# other lengths, rounding the positions tilts each crank by ~1e-16 rad, and 1e-9 rad from
# the flat position that changes the exact answer by ~1e-8).
CHAIN = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)


@pytest.fixture(params=["off", "on"])
def path(request):
    previous = planmod.set_jit(request.param)
    yield request.param
    planmod.set_jit(previous)


def rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b)))


@pytest.mark.parametrize("theta", [0.3, 1e-3, 1e-5, 1e-7, 1e-9, -1e-9, math.pi - 1e-9])
def test_fourbar_chain_near_flat_gives_the_exact_accelerations(path, theta):
    """Within 1.5e-5 rad of flat the Schur complement called 3 constraints redundant and
    returned accelerations 5 % wrong; the accelerations are unique there."""
    model = mbody.loads(CHAIN.yaml(theta, 2.0))
    sol = mbody.assemble(model).solve()
    assert rel(sol.accelerations, CHAIN.accelerations(theta, 2.0)) <= 1e-9
    assert sol.redundant == 0 and not sol.not_unique
    assert sol.warnings == []


def test_fourbar_chain_exactly_flat_is_named_redundant(path):
    """At the flat position itself G_U loses rank 3 (one per loop): Gauss's principle
    gives unique accelerations, and the reactions it leaves open are named."""
    model = mbody.loads(CHAIN.yaml(0.0, 2.0))
    sol = mbody.assemble(model).solve()
    assert sol.redundant == 3
    assert set(sol.not_unique) == {f"{j}{i}.Fx" for j in "AB" for i in range(3)} | {
        f"O{i}.Fx" for i in range(4)}


def double_bar(m1: float, m2: float, *, length: float = 1.0, mass: float = 1.0,
               time: float = 1.0, th1: float = 0.5, th2: float = 0.9) -> str:
    """Two bars hanging from a pin, in units of `length` m, `mass` kg and `time` s
    (numbers written in those units)."""
    l1 = l2 = 1.0 / length
    w = 0.05 / length
    g = 9.81 / length * time ** 2
    s1, c1, s2, c2 = math.sin(th1), math.cos(th1), math.sin(th2), math.cos(th2)
    G1 = (l1 / 2 * s1, -l1 / 2 * c1)
    P = (l1 * s1, -l1 * c1)
    G2 = (P[0] + l2 / 2 * s2, P[1] - l2 / 2 * c2)
    M1, M2 = m1 / mass, m2 / mass
    return f"""model: scale
dimension: 2
gravity: [0, {-g!r}]
bodies:
  - {{name: light, mass: {M1!r}, shape: {{box: [{w!r}, {l1!r}]}}, angle: {th1!r},
     position: [{G1[0]!r}, {G1[1]!r}]}}
  - {{name: heavy, mass: {M2!r}, shape: {{box: [{w!r}, {l2!r}]}}, angle: {th2!r},
     position: [{G2[0]!r}, {G2[1]!r}]}}
joints:
  - {{name: O, type: revolute, parent: ground, child: light, at: [0, 0]}}
  - {{name: P, type: revolute, parent: light, child: heavy, at: [{P[0]!r}, {P[1]!r}]}}
"""


def lagrange(m1: float, m2: float, th1: float = 0.5, th2: float = 0.9) -> np.ndarray:
    """θ̈₁, θ̈₂ of the same double pendulum in joint coordinates (SI units)."""
    l1 = l2 = 1.0
    w, g = 0.05, 9.81
    i1, i2 = m1 * (w * w + l1 * l1) / 12, m2 * (w * w + l2 * l2) / 12
    c = math.cos(th1 - th2)
    M = np.array([[i1 + m1 * l1 * l1 / 4 + m2 * l1 * l1, m2 * l1 * l2 / 2 * c],
                  [m2 * l1 * l2 / 2 * c, i2 + m2 * l2 * l2 / 4]])
    f = np.array([-(m1 * l1 / 2 + m2 * l1) * g * math.sin(th1),
                  -m2 * l2 / 2 * g * math.sin(th2)])
    return np.linalg.solve(M, f)


@pytest.mark.parametrize("m1, m2", [(1.0, 2.0), (1e-12, 1e12), (1e12, 1e-12), (1e-6, 1e6)])
def test_mass_ratios_up_to_1e24(path, m1, m2):
    """A 1e12 kg bar hanging from a 1e-12 kg one: the pin was called redundant (0 N)
    and the heavy bar fell freely."""
    sol = mbody.assemble(mbody.loads(double_bar(m1, m2))).solve()
    assert rel(sol.accelerations[[2, 5]], lagrange(m1, m2)) <= 1e-10
    assert sol.redundant == 0 and sol.warnings == []
    # the pin under the heavy bar carries about its weight
    assert abs(sol.reactions["P.Fy"]) > 0.1 * 9.81 * m2


UNITS = [(1e-3, 1e-3, 1.0), (1e3, 1e3, 1.0), (1.0, 1.0, 1e-3), (1e3, 1e3, 60.0),
         (1e-3, 1e-3, 3600.0)]  # (length, mass, time) units: mm·g, km·t, ms, ...


@pytest.mark.parametrize("m1, m2", [(1.0, 2.0), (1e-12, 1e12)])
@pytest.mark.parametrize("unit", UNITS)
def test_answers_scale_as_dimensional_analysis_says(path, unit, m1, m2):
    """The same system written in other units: accelerations and reactions are the SI
    ones converted, so no decision of the solve depends on the units."""
    length, mass, time = unit
    si = mbody.assemble(mbody.loads(double_bar(m1, m2))).solve()
    other = mbody.assemble(mbody.loads(double_bar(m1, m2, length=length, mass=mass,
                                                  time=time))).solve()
    acc_si = si.accelerations.reshape(-1, 3)
    acc = other.accelerations.reshape(-1, 3)
    assert rel(acc[:, :2] * length / time ** 2, acc_si[:, :2]) <= 1e-11
    assert rel(acc[:, 2] / time ** 2, acc_si[:, 2]) <= 1e-11
    force = mass * length / time ** 2
    for label in ("O.Fx", "O.Fy", "P.Fx", "P.Fy"):
        assert other.reactions[label] * force == pytest.approx(si.reactions[label],
                                                               rel=1e-10)


def test_compiled_and_numpy_agree_near_singular_positions():
    for theta in (1e-4, 1e-6, 1e-8, 0.0):
        model = mbody.loads(CHAIN.yaml(theta, 1.5))
        planmod.set_jit("off")
        a = mbody.assemble(model).solve()
        planmod.set_jit("on")
        try:
            b = mbody.assemble(model).solve()
        finally:
            planmod.set_jit("auto")
        assert "null-space" in a.method and "null-space" in b.method
        # the numpy path refines with long-double residuals (products rounded to 64
        # bits), the compiled one with exact products: 1e-8 rad from flat that is 1e-12
        assert rel(b.accelerations, a.accelerations) <= 1e-11
        assert a.not_unique == b.not_unique


def test_a_motion_without_mass_is_an_error_naming_body_and_direction():
    """Body 1's rotation about z carries no inertia and nothing holds it."""
    G = np.zeros((12, 3))
    G[0:3, :] = np.eye(3)  # body 0 pinned in translation
    mass = np.array([1.0, 2.0])
    J = np.array([np.eye(3), np.diag([1.0, 1.0, 0.0])])
    with pytest.raises(SingularMassError) as e:
        NullSpaceSolve(G, mass, J, 1.0)
    assert (e.value.body, e.value.row) == (1, 5)
    from mbody.kkt import singular_mass_error

    model = mbody.loads(CHAIN.yaml(0.3))
    msg = str(singular_mass_error(model, 1, 5))
    assert msg == ("the accelerations are not unique: body 'crank1' has no mass or inertia "
                   "for the rotation about its body z axis, and no joint constrains that "
                   "motion; give it mass or inertia there, or a joint that holds it")

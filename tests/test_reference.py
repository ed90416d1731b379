"""The contract's reference answers (model-format.md, section 7), on shipped models.

Each answer is exact in real arithmetic; the tolerance (1e-12 relative) only allows for
the last bit of floating-point rounding (0.4 is not a binary fraction).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mbody

MODELS = Path(__file__).resolve().parent.parent / "models"
EXACT = {"rel": 1e-12, "abs": 1e-12}


def test_seed_example_1_planar_offset_force():
    """m = 10, I_G = 0.5, 50 N whose line passes 0.4 m below G: a_G = 5, α = 40."""
    model = mbody.load(MODELS / "seed_example_1.yaml")
    asm = mbody.assemble(model)
    assert asm.coordinates == ["plate.x", "plate.y", "plate.theta"]
    np.testing.assert_allclose(asm.M.toarray(), np.diag([10.0, 10.0, 0.5]))
    np.testing.assert_allclose(asm.Q, [50.0, 0.0, 20.0], rtol=1e-12, atol=1e-12)  # r × F = 20
    assert np.all(asm.b == 0.0)
    acc = asm.solve().accelerations
    assert acc == pytest.approx([5.0, 0.0, 40.0], **EXACT)
    sol = asm.solve()
    assert sol["plate.x"] == pytest.approx(5.0, **EXACT)
    assert sol["plate.theta"] == pytest.approx(40.0, **EXACT)
    # The free-body diagram carries the same moment about G.
    push = [f for f in asm.bodies["plate"].fbd.forces if f.name == "push"]
    assert len(push) == 1
    assert push[0].B_moment[2] == pytest.approx(20.0, **EXACT)
    np.testing.assert_allclose(push[0].W_vector, [50.0, 0.0, 0.0])


def test_seed_example_2_torque_free_euler():
    """I = (2, 3, 4), ω = (1, 2, 3), no torque: ω̇ = (−3, 2, −0.5)."""
    model = mbody.load(MODELS / "seed_example_2.yaml")
    asm = mbody.assemble(model)
    assert asm.coordinates[3:] == ["body.w1", "body.w2", "body.w3"]
    # ω × Jω = (1, 2, 3) × (2, 6, 12) = (6, −6, 2)
    assert asm.b == pytest.approx([0, 0, 0, 6.0, -6.0, 2.0], **EXACT)
    assert np.all(asm.Q == 0.0)
    acc = asm.solve().accelerations
    assert acc == pytest.approx([0, 0, 0, -3.0, 2.0, -0.5], **EXACT)


def _single_body(dimension: int, mass: float, inertia, **loads) -> dict:
    body = {"name": "b", "mass": mass, "inertia": inertia}
    return {"model": "ref", "dimension": dimension, "bodies": [body],
            "loads": [dict(name=k, body="b", **v) for k, v in loads.items()]}


@pytest.mark.parametrize("dimension", [2, 3])
def test_four_kilogram_body_24_newton(dimension):
    """4 kg, net force 24 N: a = 6 m/s², along the force (here (3, 4)/5 of 24 N)."""
    F = [14.4, 19.2] + ([0.0] if dimension == 3 else [])
    model = mbody.load(_single_body(dimension, 4.0, 1.0 if dimension == 2 else [1, 1, 1],
                                    push={"type": "force", "force": F}))
    acc = mbody.assemble(model).solve().accelerations
    d = 2 if dimension == 2 else 3
    a = acc[:d]
    assert np.linalg.norm(a) == pytest.approx(6.0, **EXACT)
    assert a[:2] == pytest.approx([3.6, 4.8], **EXACT)
    assert np.all(acc[d:] == 0.0)


@pytest.mark.parametrize("dimension", [2, 3])
def test_flywheel_10_newton_metre(dimension):
    """Flywheel I = 0.25 kg m², net moment 10 N m about its axis: α = 40 rad/s².

    In 3-D the flywheel spins at 7 rad/s about its symmetry axis (ω × Jω = 0 there)."""
    if dimension == 2:
        model = mbody.load(_single_body(2, 3.0, 0.25,
                                        motor={"type": "torque", "torque": 10.0}))
        acc = mbody.assemble(model).solve().accelerations
        assert acc == pytest.approx([0.0, 0.0, 40.0], **EXACT)
    else:
        spec = _single_body(3, 3.0, [0.15, 0.15, 0.25],
                            motor={"type": "torque", "torque": [0, 0, 10.0], "frame": "body"})
        spec["bodies"][0]["angular_velocity"] = [0, 0, 7.0]
        asm = mbody.assemble(mbody.load(spec))
        assert asm.b == pytest.approx(np.zeros(6), **EXACT)
        assert asm.solve().accelerations == pytest.approx([0, 0, 0, 0, 0, 40.0], **EXACT)


# -- the same answers on the shipped practice ladder ---------------------------------------

def test_practice_1_translation():
    """4 kg crate, 30 N push and 6 N drag through G: a = 24/4 = 6, α = 0."""
    asm = mbody.assemble(mbody.load(MODELS / "practice_1_translation.yaml"))
    np.testing.assert_allclose(asm.Q, [24.0, 0.0, 0.0], rtol=0, atol=1e-12)
    assert asm.solve().accelerations == pytest.approx([6.0, 0.0, 0.0], **EXACT)


def test_practice_2_flywheel():
    """I = 0.25, motor 10 N m, bearing reactions known (Fy carries the weight): α = 40."""
    asm = mbody.assemble(mbody.load(MODELS / "practice_2_flywheel.yaml"))
    assert asm.reactions == ["bearing.Fx", "bearing.Fy"]
    assert asm.solve().accelerations == pytest.approx([0.0, 0.0, 40.0], **EXACT)
    # without the file's known weight the bearing leaves the wheel falling at g
    acc = asm.solve(known={"bearing.Fy": 0.0}).accelerations
    assert acc == pytest.approx([0.0, -9.81, 40.0], **EXACT)


def test_practice_3_euler():
    """I = (2, 3, 4), ω = (1, 2, 3), no torque: ω̇ = (−3, 2, −0.5); the mass plays no part."""
    asm = mbody.assemble(mbody.load(MODELS / "practice_3_euler.yaml"))
    assert asm.solve().accelerations == pytest.approx([0, 0, 0, -3.0, 2.0, -0.5], **EXACT)

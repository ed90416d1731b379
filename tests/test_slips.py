"""Slips a student makes that still make a valid model: warned about with their place,
never changed (docs/model-format.md, "Angles and rates" and "Joints").

- a bare angle beyond one turn (`angle: 45`, `euler: [90, 0, 30]`): degrees meant?
- a joint point beyond every body it joins (`validate.body_reach`).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.model import fast
from mbody.model.checks import BARE_ANGLE_LIMIT
from mbody.model.validate import JOINT_REACH_GYRATION, JOINT_REACH_SHAPE

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
from fourbar_chain import FourbarChain  # noqa: E402


def mark_of(text: str, needle: str, nth: int = 1) -> tuple[int, int]:
    """1-based (line, column) of the `nth` occurrence of `needle` in `text`."""
    at = -1
    for _ in range(nth):
        at = text.index(needle, at + 1)
    return text.count("\n", 0, at) + 1, at - (text.rfind("\n", 0, at) + 1) + 1


def slips(model: mbody.Model) -> list:
    """The warnings of these two checks (others, such as a normalised quaternion, aside)."""
    return [w for w in model.warnings
            if w.message.startswith(("the angle ", "the joint point "))]


PENDULUM = """\
model: pendulum
dimension: 2
gravity: [0, -9.81]
bodies:
  - name: rod
    mass: 1
    shape: {box: [0.05, 1.0]}
    angle: ANGLE
    position: [0.3536, -0.3536]
joints:
  - {name: O, type: revolute, parent: ground, child: rod, at: [0, 0]}
"""


def test_a_planar_angle_in_degrees_is_warned_about_at_its_place(tmp_path):
    path = tmp_path / "pendulum.yaml"
    text = PENDULUM.replace("ANGLE", "45")
    path.write_text(text)
    model = mbody.load(path)
    [w] = slips(model)
    assert (w.file, w.line, w.column) == (str(path), *mark_of(text, "45"))
    assert w.key == "bodies[0].angle"
    assert w.message == ("the angle 45 is read as 45 rad, 7.16 turns (a number without a "
                         "unit is in radians)")
    assert w.hint == "did you mean '45 deg'?"
    # the model is what the file says: 45 rad
    assert model.initial.quaternion[0] == pytest.approx([math.cos(22.5), 0, 0, math.sin(22.5)],
                                                        abs=1e-15)


def test_the_warning_on_the_command_line(tmp_path, capsys):
    path = tmp_path / "pendulum.yaml"
    text = PENDULUM.replace("ANGLE", "45")
    path.write_text(text)
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    line, col = mark_of(text, "45")
    assert (f"warning: {path}:{line}:{col}: bodies[0].angle: the angle 45 is read as 45 rad"
            in out)
    assert "(did you mean '45 deg'?)" in out
    assert f"OK: {path} is a valid model." in out
    assert main(["solve", str(path)]) == 0  # other commands: on stderr, once
    err = capsys.readouterr().err
    assert err.count("did you mean '45 deg'?") == 1
    assert err.startswith(f"mbody: warning: {path}:{line}:{col}: ")


def test_euler_angles_in_degrees_each_at_its_place(tmp_path):
    text = ("dimension: 3\nbodies:\n  - name: plate\n    mass: 2\n    inertia: [1, 2, 3]\n"
            "    orientation: {euler: [90, 0, 30]}\n")
    path = tmp_path / "plate.yaml"
    path.write_text(text)
    model = mbody.load(path)
    w90, w30 = slips(model)
    assert (w90.line, w90.column, w90.key) == (*mark_of(text, "90"),
                                               "bodies[0].orientation.euler[0]")
    assert (w30.line, w30.column, w30.key) == (*mark_of(text, "30"),
                                               "bodies[0].orientation.euler[2]")
    assert w90.hint == "did you mean '90 deg'?" and w30.hint == "did you mean '30 deg'?"
    meant = mbody.loads(text.replace("[90, 0, 30]", "[90 rad, 0, 30 rad]"))
    assert slips(meant) == []  # a unit says what is meant
    np.testing.assert_array_equal(model.initial.quaternion, meant.initial.quaternion)


@pytest.mark.parametrize("angle, warned", [
    ("6.28", False), ("-6.28", False), ("6.3", True), ("-7", True), ("3.14159", False),
    ("'45 deg'", False), ("'720 deg'", False), ("'7 rad'", False), ("1e3", True)])
def test_the_limit_is_one_turn_and_only_for_bare_numbers(angle, warned):
    assert 2 * math.pi == BARE_ANGLE_LIMIT
    model = mbody.loads(PENDULUM.replace("ANGLE", angle).replace("at: [0, 0]",
                                                                 "at: [0.3536, -0.3536]"))
    assert bool(slips(model)) is warned


def test_angular_velocities_are_never_warned_about():
    text = PENDULUM.replace("ANGLE", "0.5").replace("    position",
                                                    "    angular_velocity: 100\n    position")
    assert slips(mbody.loads(text)) == []
    spatial = ("dimension: 3\nbodies:\n  - {name: w, mass: 1, inertia: [1, 1, 2], "
               "angular_velocity: [0, 0, 300]}\n")
    assert mbody.loads(spatial).warnings == ()


# -- joint points ------------------------------------------------------------------------

DOUBLE = """\
model: double
dimension: 2
bodies:
  - {name: upper, mass: 1, shape: {box: [0.05, 1.0]}, position: [0, -0.5]}
  - {name: lower, mass: 1, inertia: 0.08354, position: [0, -1.5]}
joints:
  - {name: O, type: revolute, parent: ground, child: upper, at: [0, 0]}
  - {name: A, type: revolute, parent: upper, child: lower, at: AT}
"""
RHO = math.sqrt(0.08354)  # the lower rod's radius of gyration (a 1 m rod: 1/√12)


def test_a_joint_point_off_both_bodies_is_warned_about_at_its_place(tmp_path):
    """The sign of y slipped: [0, 1] for [0, -1]."""
    path = tmp_path / "double.yaml"
    text = DOUBLE.replace("AT", "[0, 1]")
    path.write_text(text)
    model = mbody.load(path)
    [w] = slips(model)
    assert (w.line, w.column, w.key) == (*mark_of(text, "[0, 1]"), "joints[1].at")
    # the upper rod's box: its inertia's 4 ρ (1.156 m) is farther than twice its
    # half-diagonal (1.001 m)
    assert w.message == (
        "the joint point (0, 1) lies off both bodies it joins: 1.5 m from the mass centre "
        f"of 'upper' (beyond {4 * RHO:.3g} m, 4 radii of gyration) and 2.5 m from the "
        f"mass centre of 'lower' (beyond {4 * RHO:.3g} m, 4 radii of gyration)")
    assert "'at' is in world coordinates" in w.hint
    assert model.joints[1].at == pytest.approx([0, 1, 0])  # kept as written


def test_at_the_end_of_the_rods_nothing_is_said():
    assert slips(mbody.loads(DOUBLE.replace("AT", "[0, -1]"))) == []


def test_near_one_body_is_enough():
    """Beyond the upper rod's reach but within the lower one's (4 ρ = 1.156 m)."""
    model = mbody.loads(DOUBLE.replace("AT", "[0, -2.6]"))
    assert slips(model) == []
    assert len(slips(mbody.loads(DOUBLE.replace("AT", "[0, -2.7]")))) == 1


@pytest.mark.parametrize("factor, warned", [(0.99, False), (1.01, True)])
def test_the_reach_without_a_shape_is_four_radii_of_gyration(factor, warned):
    assert JOINT_REACH_GYRATION == 4.0
    d = factor * JOINT_REACH_GYRATION * RHO
    text = ("dimension: 2\nbodies:\n  - {name: lower, mass: 1, inertia: 0.08354}\n"
            f"joints:\n  - {{name: A, type: revolute, parent: ground, child: lower, "
            f"at: [{d!r}, 0]}}\n")
    assert bool(slips(mbody.loads(text))) is warned


@pytest.mark.parametrize("factor, warned", [(0.99, False), (1.01, True)])
def test_the_reach_with_a_shape_is_twice_its_extent(factor, warned):
    """A uniform body's 4 ρ is always beyond twice its shape (a rod: 1.15 L against L);
    a shape counts where the inertia given is smaller than its own: here a 1 m bar drawn
    around a 2 kg mass with I_G = 0.002 (4 ρ = 0.126 m), whose ends are 0.5025 m out."""
    assert JOINT_REACH_SHAPE == 2.0
    extent = math.hypot(0.5, 0.05)
    bar = "  - {name: bar, mass: 2, inertia: 0.002, shape: {box: [1.0, 0.1]}}\n"
    joint = ("joints:\n  - {name: A, type: revolute, parent: ground, child: bar, "
             f"at: [{factor * JOINT_REACH_SHAPE * extent!r}, 0]}}\n")
    assert bool(slips(mbody.loads("dimension: 2\nbodies:\n" + bar + joint))) is warned
    undrawn = bar.replace(", shape: {box: [1.0, 0.1]}", "")
    assert slips(mbody.loads("dimension: 2\nbodies:\n" + undrawn
                             + joint.replace(f"{factor * JOINT_REACH_SHAPE * extent!r}", "0.5")))


def test_a_particle_on_a_light_link_is_not_counted():
    """A joint away from a particle is a massless link to it (docs: Particles)."""
    text = ("dimension: 2\nbodies:\n  - {name: bob, mass: 1, inertia: 0, position: [0, -3]}\n"
            "joints:\n  - {name: O, type: revolute, parent: ground, child: bob, at: [0, 0]}\n")
    model = mbody.loads(text)
    assert model.joints[0].particle_joint == "link" and slips(model) == []


def test_in_millimetres_the_joint_and_the_position_disagree():
    text = DOUBLE.replace("AT", "[0, -1000]")
    [w] = slips(mbody.loads(text))
    assert "999.5 m from the mass centre of 'upper'" in w.message


# -- never a false warning ---------------------------------------------------------------

SHIPPED = sorted([*(ROOT / "models").glob("*.yaml"), *(ROOT / "models" / "robots").iterdir(),
                  *(ROOT / "tests").glob("*.yaml")])


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_no_shipped_or_test_model_is_warned_about(path):
    assert slips(mbody.load(path)) == []


@pytest.mark.parametrize("theta", [0.3, 0.0, -math.pi + 1e-9])
def test_the_fourbar_chain_is_not_warned_about(theta):
    chain = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)
    assert slips(mbody.loads(chain.yaml(theta, 2.0))) == []


# -- the fast path for large files says the same ----------------------------------------

def _chain(n: int, at_offset: float, angle: float) -> str:
    bodies = "".join(f"- name: b{i}\n  mass: 1.0\n  inertia: 0.08354\n"
                     f"  position: [{i + 0.5!r}, 0.0]\n  angle: {angle!r}\n" for i in range(n))
    joints = "".join(f"- name: j{i}\n  type: revolute\n  parent: "
                     f"{'ground' if i == 0 else f'b{i - 1}'}\n  child: b{i}\n"
                     f"  at: [{i + at_offset!r}, 0.0]\n" for i in range(n))
    return f"model: chain\ndimension: 2\nbodies:\n{bodies}joints:\n{joints}"


@pytest.mark.parametrize("at_offset, angle, warned", [
    (0.0, 0.0, False), (0.0, 7.0, True), (5.0, 0.0, True)])
def test_large_files_are_warned_about_as_small_ones(at_offset, angle, warned):
    text = _chain(1500, at_offset, angle)
    assert len(text) > fast.MIN_BYTES
    assert (fast.fast_spec(text, "chain.yaml") is None) is warned  # the located path warns
    model = mbody.loads(text, "chain.yaml")
    assert bool(slips(model)) is warned
    if warned:
        assert len(slips(model)) == 1500  # each body's angle, or each joint

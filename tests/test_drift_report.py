"""The run's report of energy, linear and angular momentum (mbody.simulate.summary, the
notebook's table): a drift figure where the model conserves the quantity, else "not
conserved here (reason)" (docs/simulation.md, "The drift report").

A quantity the model conserves changes only by integration error, so its drift falls
with the tolerance; one it does not conserve changes by the physics, whatever the
tolerance. Both are checked on the shipped models and on small ones written here.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.simulate.simulation import conservation, summary
from mbody.util.spatial import quat_to_matrix

MODELS = Path(__file__).resolve().parent.parent / "models"
QUANTITIES = ("energy", "momentum", "angular_momentum")


def run(model: mbody.Model, rtol: float = 1e-10, t_end: float = 1.0) -> mbody.Trajectory:
    return mbody.simulate(model, t_end, 30, rtol=rtol, atol=rtol * 1e-2)


def lines_of(traj: mbody.Trajectory) -> dict[str, str]:
    """The summary's conservation lines by quantity."""
    out = {}
    for line in summary(traj).splitlines():
        for key, start in (("energy", "energy T + V"), ("momentum", "linear momentum"),
                           ("angular_momentum", "angular momentum")):
            if line.startswith(start):
                out[key] = line
    return out


def assert_conserved_by_the_physics(model: mbody.Model, key: str) -> None:
    """The drift is integration error: 1e4 times tighter tolerances make it at least 100
    times smaller (DOP853's error falls about as the tolerance), unless both are at
    rounding level (1e-13)."""
    loose = run(model, 1e-6).info[f"{key}_drift"]
    tight = run(model, 1e-10).info[f"{key}_drift"]
    assert tight <= loose / 100 or max(loose, tight) <= 1e-13, (key, loose, tight)


def assert_changed_by_the_physics(model: mbody.Model, key: str) -> None:
    """The change is the model's: it is large and the same at both tolerances."""
    loose = run(model, 1e-6).info[f"{key}_drift"]
    tight = run(model, 1e-10).info[f"{key}_drift"]
    assert tight > 1e-3 and tight == pytest.approx(loose, rel=1e-3), (key, loose, tight)


# -- the shipped models -------------------------------------------------------------------

def test_pendulum_conserves_energy_only():
    model = mbody.load(MODELS / "pendulum.yaml")
    traj = run(model)
    said = lines_of(traj)
    assert re.fullmatch(r"energy T \+ V: E\(0\) = -8\.49571 J, relative drift \S+",
                        said["energy"])
    assert said["momentum"] == ("linear momentum: not conserved here (gravity; joints to "
                                "ground: O)")
    assert said["angular_momentum"] == (
        "angular momentum (total, about the world origin): not conserved here (gravity; "
        "joints to ground: O)")
    assert "relative change" not in summary(traj) and "1.00e+00" not in summary(traj)
    assert_conserved_by_the_physics(model, "energy")
    assert_changed_by_the_physics(model, "momentum")
    assert_changed_by_the_physics(model, "angular_momentum")


def test_torque_free_body_conserves_all_three():
    model = mbody.load(MODELS / "torque_free_asymmetric.yaml")
    traj = run(model)
    said = lines_of(traj)
    assert said["momentum"].startswith("linear momentum: |p(0)| = 0 kg m/s, relative drift ")
    assert said["angular_momentum"].startswith(
        "angular momentum (total, about the world origin): |H(0)| = 2.55314 kg m^2/s, "
        "relative drift ")
    for key in QUANTITIES:
        assert traj.info[f"{key}_conserved"] and traj.info[f"{key}_not_conserved"] == ""
        assert_conserved_by_the_physics(model, key)


@pytest.mark.parametrize("name, reason", [
    ("planar_time_varying_force", "applied loads do work: push, twist"),
    ("spring_mass_damper", "dampers dissipate: suspension"),
    ("spinning_disc_bearings", "given reaction values act as loads: A.Fx, A.Fy, A.Fz and 3 "
                               "more"),
    ("slider_crank", "applied loads do work: gas, load"),
])
def test_energy_not_conserved_says_why(name, reason):
    traj = run(mbody.load(MODELS / f"{name}.yaml"))
    assert lines_of(traj)["energy"] == f"energy T + V: not conserved here ({reason})"
    assert not traj.info["energy_conserved"]


def test_a_motor_doing_work_changes_energy_by_the_physics():
    assert_changed_by_the_physics(mbody.load(MODELS / "planar_time_varying_force.yaml"),
                                  "energy")


def test_every_shipped_claim_of_conservation_holds():
    """Where the report says conserved, the drift falls with the tolerance."""
    claims = 0
    for path in sorted(MODELS.glob("*.yaml")):
        model = mbody.load(path)
        why = conservation(model, ideal_joints=bool(model.reactions) and any(
            r not in model.known_reactions for r in model.reactions))
        for key in QUANTITIES:
            if not why[key]:
                assert_conserved_by_the_physics(model, key)
                claims += 1
    assert claims >= 15


# -- small models: the other cases ---------------------------------------------------------

SPRING_PAIR = """\
dimension: 2
bodies:
  - {name: a, mass: 1, inertia: 0.1, velocity: [1, 0.5], angular_velocity: 2}
  - {name: b, mass: 2, inertia: 0.2, position: [1, 0], velocity: [-0.5, 0], angular_velocity: -1}
loads:
  - {name: k, type: spring, bodies: [a, b], at: [[0.1, 0], [-0.1, 0]], stiffness: 50,
     rest_length: 0.5}
"""


def test_a_spring_between_free_bodies_conserves_all_three_about_the_origin():
    model = mbody.loads(SPRING_PAIR)
    traj = run(model)
    assert traj.info["momentum_initial"] == pytest.approx([0.0, 0.5, 0.0])
    assert traj.info["angular_momentum_kind"] == "total, about the world origin"
    assert lines_of(traj)["momentum"].startswith(
        "linear momentum: |p(0)| = 0.5 kg m/s, relative drift ")
    for key in QUANTITIES:
        assert traj.info[f"{key}_conserved"]
        assert_conserved_by_the_physics(model, key)


def test_a_couple_leaves_linear_momentum_alone():
    model = mbody.loads("dimension: 2\nbodies:\n  - {name: a, mass: 1, inertia: 0.1, "
                        "velocity: [1, 2]}\nloads:\n  - {name: twist, type: torque, "
                        "body: a, torque: 0.3}\n")
    traj = run(model)
    said = lines_of(traj)
    assert traj.info["momentum_conserved"]
    assert said["energy"] == "energy T + V: not conserved here (applied loads do work: twist)"
    assert said["angular_momentum"].endswith("not conserved here (applied couples: twist)")
    assert_conserved_by_the_physics(model, "momentum")
    assert_changed_by_the_physics(model, "energy")


PINNED_PAIR = """\
dimension: 2
gravity: [0, -9.81]
bodies:
  - {name: a, mass: 1, shape: {box: [1, 0.05]}, angular_velocity: 3}
  - {name: b, mass: 2, shape: {box: [1, 0.05]}, position: [1, 0], velocity: [0, 1],
     angular_velocity: -1}
joints:
  - {name: P, type: revolute, parent: a, child: b, at: [0.5, 0]}
"""


def test_a_free_falling_jointed_pair_conserves_its_angular_momentum_about_its_mass_centre():
    """Uniform gravity has no moment about the system's mass centre; the pin is internal."""
    model = mbody.loads(PINNED_PAIR)
    traj = run(model)
    info = traj.info
    assert info["angular_momentum_kind"] == "total, about the system's mass centre"
    assert info["angular_momentum_conserved"] and info["energy_conserved"]
    assert lines_of(traj)["momentum"] == "linear momentum: not conserved here (gravity)"
    # H about the system's mass centre, computed here from the samples
    m = np.array([1.0, 2.0])
    x, q, v, w = traj.spatial()
    xc = np.einsum("n,kni->ki", m, x) / 3
    vc = np.einsum("n,kni->ki", m, v) / 3
    Jw = np.einsum("nij,knj->kni", np.array(model.J), w)  # body axes
    spin = np.einsum("knij,knj->kni", quat_to_matrix(q), Jw)
    H = (np.cross(x - xc[:, None], m[None, :, None] * (v - vc[:, None])) + spin).sum(axis=1)
    assert info["angular_momentum_initial"] == pytest.approx(H[0].tolist(), abs=1e-12)
    np.testing.assert_allclose(traj.series["angular_momentum"], H, atol=1e-12)
    assert_conserved_by_the_physics(model, "angular_momentum")
    assert_conserved_by_the_physics(model, "energy")


def test_free_bodies_under_gravity_conserve_their_spins():
    model = mbody.loads("dimension: 3\ngravity: [0, 0, -9.81]\nbodies:\n"
                        "  - {name: a, mass: 1, inertia: [1, 2, 3], "
                        "angular_velocity: [0.1, 3, 0.1], velocity: [1, 0, 2]}\n"
                        "  - {name: b, mass: 2, inertia: [2, 2, 1], position: [3, 0, 0], "
                        "angular_velocity: [1, 0, 4]}\n")
    traj = run(model)
    assert traj.info["angular_momentum_kind"] == "spin, about the mass centres"
    assert_conserved_by_the_physics(model, "angular_momentum")
    assert_conserved_by_the_physics(model, "energy")


def test_known_reactions_given_on_the_command_line_count(tmp_path):
    """`--known` values act as loads: energy is not promised."""
    why = conservation(mbody.load(MODELS / "pendulum.yaml"), ideal_joints=True,
                       known={"O.Fx": 1.0})
    assert why["energy"] == "given reaction values act as loads: O.Fx"


# -- where the report is shown -------------------------------------------------------------

def test_the_command_prints_no_drift_figure_for_what_is_not_conserved(capsys, tmp_path):
    assert main(["simulate", str(MODELS / "planar_time_varying_force.yaml"), "--t-end", "1",
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "energy T + V: not conserved here (applied loads do work: push, twist)" in out
    assert "relative change" not in out and "e+00" not in out


def test_the_notebook_table_says_the_same(monkeypatch):
    from mbody.present import rich

    monkeypatch.setattr(rich, "EMBED_ANIMATION", False)
    html = rich.trajectory_html(run(mbody.load(MODELS / "pendulum.yaml"), t_end=0.3))
    assert "<td>linear momentum</td><td>not conserved here (gravity; joints to ground: O)</td>" \
        in html
    assert re.search(r"<td>energy T \+ V</td><td>E\(0\) = -8\.49571 J, relative drift "
                     r"\d\.\d\de-\d\d</td>", html)
    assert "1.00e+00" not in html


def test_a_run_saved_before_the_reasons_were_kept_still_displays():
    from mbody.simulate.simulation import conserved_lines

    old = {"energy_conserved": False, "energy_drift": 1.0, "energy_initial": 2.0,
           "angular_momentum_conserved": True, "angular_momentum_drift": 1e-12,
           "angular_momentum_kind": "total, about the world origin",
           "angular_momentum_initial": [0.0, 0.0, 3.0]}
    assert conserved_lines(old) == [
        ("energy T + V", "not conserved here"),
        ("angular momentum (total, about the world origin)",
         "|H(0)| = 3 kg m^2/s, relative drift 1.00e-12")]

"""`mbody kinematics`, `mbody equilibrium` and `--axes world`, run as a user runs them (a
subprocess), their numbers against closed forms and Newton's law."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
G0 = 9.81


def mbody(*args: str | Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mbody", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)


def test_equilibrium_of_the_shipped_spring_loaded_arm():
    """tan θ = k a / m g; at rest the pin carries what the spring and gravity leave:
    R = −k (P − x_G) − m g (world axes); ω² = (k a l sin θ + m g l cos θ) / I_O."""
    m, k, a, l, I_G = 2.0, 30.0, 1.2, 0.5, 0.1
    p = mbody("equilibrium", "models/spring_loaded_arm.yaml", "--axes", "world", "--json")
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    theta = math.atan(k * a / (m * G0))
    x_G = np.array(out["position"][0][:2])
    assert np.allclose(x_G, [l * math.sin(theta), -l * math.cos(theta)], atol=1e-9)
    assert out["found"] and out["stable"] is True
    R = -k * (np.array([a, 0.0]) - x_G) - m * np.array([0.0, -G0])
    assert np.allclose([out["reactions"]["O.Fx"], out["reactions"]["O.Fy"]], R,
                       rtol=1e-8, atol=1e-8 * m * G0)
    omega2 = (k * a * l * math.sin(theta) + m * G0 * l * math.cos(theta)) / (I_G + m * l**2)
    # the stiffness comes from central differences of step 1e-6 of the size: O(h^2) error
    assert out["stiffness"] == [pytest.approx(omega2, rel=1e-6)]
    text = mbody("equilibrium", "models/spring_loaded_arm.yaml")
    assert text.returncode == 0 and "stable" in text.stdout and "61.4" in text.stdout


def test_no_equilibrium_is_exit_1_with_a_hint(tmp_path):
    """A wheel on a pin with a constant torque never rests."""
    f = tmp_path / "wheel.yaml"
    f.write_text("model: wheel\ndimension: 2\nbodies:\n  - {name: w, mass: 1, inertia: 0.1}\n"
                 "loads:\n  - {name: T, type: torque, body: w, torque: 1}\n"
                 "joints:\n  - {name: O, type: revolute, parent: ground, child: w, "
                 "at: [0, 0]}\n")
    p = mbody("equilibrium", f)
    assert p.returncode == 1, p.stdout + p.stderr
    # the hint is one 'mbody: cannot solve:' message (it was a bare 'hint:' line)
    assert "no equilibrium" in p.stdout and p.stderr.startswith("mbody: cannot solve: ")
    assert "start from a pose nearer one" in p.stderr
    assert "Traceback" not in p.stderr
    # the constant torque cancels nothing: the residual, relative to its terms, stays 1
    assert "the loads never balanced" in p.stdout
    assert "generalized force was 1 of the size of the terms it sums" in p.stdout


def test_solve_in_world_axes_satisfies_each_bodys_newton_law():
    """slider_crank.yaml at t = 0: with the joints' world forces, m a = m g + Σ F on each
    body (+F where it is the child, −F where it is the parent) + the applied forces."""
    p = mbody("solve", "models/slider_crank.yaml", "--axes", "world", "--json")
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["reaction_axes"] == "world"
    R = out["reactions"]
    F = {j: np.array([R[f"{j}.Fx"], R[f"{j}.Fy"]]) for j in "OABP"}
    gas = np.array([-4000.0, 0.0])
    on = {"crank": F["O"] - F["A"], "rod": F["A"] - F["B"], "piston": F["B"] + F["P"] + gas}
    mass = {"crank": 0.4, "rod": 0.6, "piston": 0.5}
    for body, force in on.items():
        acc = out["by_body"][body]
        a = np.array([acc[f"{body}.x"], acc[f"{body}.y"]])
        scale = 4000.0
        assert np.allclose(mass[body] * a, mass[body] * np.array([0, -G0]) + force,
                           atol=1e-10 * scale), body
    joint_frame = json.loads(mbody("solve", "models/slider_crank.yaml", "--json").stdout)
    assert joint_frame["reaction_axes"] == "joint"
    text = mbody("solve", "models/slider_crank.yaml", "--axes", "world")
    assert "in world axes" in text.stdout and "on piston" in text.stdout


def test_kinematics_of_the_shipped_driven_slider_crank(tmp_path):
    """One revolution by default (one sample a degree); the saved run reads back with the
    motor's torque among its reactions, the torque's peak matches the run's series, a
    followed point is where its body carries it, and the energy balances."""
    from mbody.simulate.trajectory import Trajectory

    out = tmp_path / "run.npz"
    p = mbody("kinematics", "models/slider_crank_driven.yaml", "-o", out,
              "--point", "pin=rod:0.08,0")
    assert p.returncode == 0, p.stderr
    assert "peaks over the run" in p.stdout and "motor.M" in p.stdout
    traj = Trajectory.load(out)
    assert len(traj) == 361 and traj.t[-1] == pytest.approx(0.1, rel=1e-12)
    M = traj.reactions[:, traj.reaction_labels.index("motor.M")]
    assert f"{M[np.argmax(np.abs(M))]:.6g} N m" in p.stdout
    # the rod's end (B on the rod) rides on the cylinder's axis y = 0 through the run
    assert np.abs(traj.series["point:pin"][:, 1]).max() < 1e-12
    j = json.loads(mbody("kinematics", "models/slider_crank_driven.yaml", "--json",
                         "--axes", "world").stdout)
    assert j["samples"] == 361 and j["power_balance_residual"] < 1e-12
    assert {p["label"] for p in j["peaks"]} >= {"O.Fx", "O.Fy", "P.Fx", "motor.M"}


def test_kinematics_refuses_bad_points_and_a_partly_driven_model(tmp_path):
    p = mbody("kinematics", "models/slider_crank_driven.yaml", "--point", "pin=rod")
    assert p.returncode == 2 and "NAME=BODY:X,Y" in p.stderr
    p = mbody("kinematics", "models/slider_crank_driven.yaml", "--point", "pin=rodd:0,0")
    assert p.returncode == 2 and "did you mean 'rod'" in p.stderr
    p = mbody("kinematics", "models/flyball_governor.yaml")
    assert p.returncode == 2 and "mbody simulate" in p.stderr
    assert "Traceback" not in p.stderr


def test_plot_of_a_driven_run_against_the_crank_angle_and_time(tmp_path):
    """The drivers' figure by default (against the driver's angle), against time on
    request, the motion's figure with --motion; a misspelt driver gets a hint."""
    from PIL import Image

    run = tmp_path / "run.npz"
    assert mbody("kinematics", "models/slider_crank_driven.yaml", "-o", run).returncode == 0
    for extra, name in (((), "a.png"), (("--against", "time"), "b.png"),
                        (("--motion",), "c.png")):
        p = mbody("plot", run, "-o", tmp_path / name, *extra)
        assert p.returncode == 0, p.stderr
        with Image.open(tmp_path / name) as im:
            assert im.size[0] > 600 and im.size[1] > 400
    p = mbody("plot", run, "-o", tmp_path / "d.png", "--against", "motr")
    assert p.returncode == 2 and "did you mean 'motor'" in p.stderr
    assert not (tmp_path / "d.png").exists()


def test_simulate_on_driven_models(tmp_path):
    """Fully driven: simulate is the kinematic run (no integrator); partly driven: the
    integrated run's summary has the drivers' peaks and energy check, and its plot is
    the drivers' figure."""
    p = mbody("simulate", "models/slider_crank_driven.yaml", "--t-end", "0.1")
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("kinematic run of 'slider-crank-driven'")
    run = tmp_path / "fly.npz"
    p = mbody("simulate", "models/flyball_governor.yaml", "--t-end", "1", "-o", run)
    assert p.returncode == 0, p.stderr
    assert "integrator DOP853" in p.stdout and "motor.M" in p.stdout
    assert "energy T + V: not conserved here (drivers do work: motor)" in p.stdout
    assert "energy check: the drivers' power" in p.stdout
    p = mbody("plot", run, "-o", tmp_path / "fly.png")
    assert p.returncode == 0 and (tmp_path / "fly.png").stat().st_size > 10_000


def test_check_says_which_velocities_the_drivers_rates_set(tmp_path):
    """The double pendulum at rest in its file, its top pin driven by θ₁ = 30° + 0.5 sin 3t:
    the assembly gives the upper rod θ₁' = 1.5 rad/s, and the lower rod the rate of least
    kinetic energy, θ₂' = −M₁₂/M₂₂ θ₁' with M₁₂ = m L (L/2) cos(θ₁ − θ₂) and
    M₂₂ = I_G + m (L/2)² = m L²/3 (uniform 1 kg, 0.5 m rods at 30° and 45°)."""
    text = (ROOT / "models/double_pendulum.yaml").read_text()
    f = tmp_path / "shaken.yaml"
    f.write_text(text.rstrip() + "\ndrivers:\n  - {name: shake, joint: O, "
                 "angle: \"30 deg + 0.5*sin(3*t)\"}\n")
    p = mbody("check", f)
    assert p.returncode == 0, p.stderr
    line = next(x for x in p.stdout.splitlines() if x.startswith("assembled velocities"))
    m, L, w1 = 1.0, 0.5, 1.5
    w2 = -(m * L * L / 2 * math.cos(math.radians(30 - 45))) / (m * L * L / 3) * w1
    assert f"upper {L / 2 * w1:g} m/s, {w1:g} rad/s (the file's 0 m/s, 0 rad/s)" in line
    shown = float(line.split("lower ")[1].split(" rad/s")[0].split(", ")[1])
    assert shown == pytest.approx(w2, rel=1e-5)  # printed to 6 digits
    # without drivers nothing changes, and no such line is printed
    plain = mbody("check", "models/double_pendulum.yaml")
    assert "assembled velocities" not in plain.stdout


@pytest.mark.parametrize("name", ["slider_crank_driven", "scotch_yoke", "flyball_governor"])
def test_equilibrium_of_a_speed_driven_model_holds_its_drivers_without_a_warning(name):
    """Review R7-5: the equilibrium holds each driver at its pose, at rest; its reactions
    were solved with the file's speeds, so the state at rest 'broke' every speed driver
    (warning: G^T v -62.8 rad/s). The values are those of either assembly: at rest no
    velocity term acts."""
    import mbody as api
    from mbody.solve.equilibrium import find_equilibrium, held

    text = mbody("equilibrium", f"models/{name}.yaml")
    assert text.returncode == 0 and "motor" in text.stdout
    assert "breaks joint constraints" not in text.stdout + text.stderr, text.stdout
    p = mbody("equilibrium", f"models/{name}.yaml", "--json")
    out = json.loads(p.stdout)
    model = api.load(ROOT / "models" / f"{name}.yaml")
    state = find_equilibrium(model).state
    for route in (model, held(model, 0.0)):
        sol = api.assemble(route, state).solve()
        for label, value in out["reactions"].items():
            scale = max(abs(v) for v in out["reactions"].values()) or 1.0
            assert abs(sol.reactions[label] - value) <= 1e-9 * scale, label


def test_simulate_of_a_fully_driven_model_refuses_integrator_options():
    """Review R7-17: a fully driven model's run is kinematic; --method, --rtol, --max-steps
    were ignored without a word. They are refused; without them the run is made."""
    p = mbody("simulate", "models/scotch_yoke.yaml", "--method", "Radau", "--rtol", "1e-6",
              "--t-end", "0.1")
    assert p.returncode == 2 and "--method, --rtol do not apply" in p.stderr, p.stderr
    assert "fully driven" in p.stderr and "Traceback" not in p.stderr
    p = mbody("simulate", "models/scotch_yoke.yaml", "--max-wall", "5", "--t-end", "0.1")
    assert p.returncode == 2 and "--max-wall does not apply" in p.stderr
    p = mbody("simulate", "models/scotch_yoke.yaml", "--t-end", "0.1", "--no-progress")
    assert p.returncode == 0 and "kinematic run" in p.stdout
    p = mbody("simulate", "models/pendulum.yaml", "--rtol", "1e-6", "--t-end", "0.1",
              "--no-progress")
    assert p.returncode == 0, p.stderr

"""Simulation against closed forms: torque-free bodies, time-varying loads, spring-damper."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipj, ellipkinc

import mbody
from mbody.cli import main
from mbody.simulate import summary
from mbody.util.spatial import quat_to_matrix

MODELS = Path(__file__).resolve().parent.parent / "models"


def _model(name: str) -> mbody.Model:
    return mbody.load(MODELS / f"{name}.yaml")


def test_intermediate_axis_matches_jacobi_elliptic_solution():
    """Torque-free asymmetric body, I1 < I2 < I3, with M² > 2 E I2 (Landau & Lifshitz,
    Mechanics, §37, eq. 37.10):

        ω1 = sqrt((2E I3 − M²) / (I1 (I3 − I1))) cn τ
        ω2 = sqrt((2E I3 − M²) / (I2 (I3 − I2))) sn τ
        ω3 = sqrt((M² − 2E I1) / (I3 (I3 − I1))) dn τ
        τ = t sqrt((I3 − I2)(M² − 2E I1) / (I1 I2 I3)),
        k² = (I2 − I1)(2E I3 − M²) / ((I3 − I2)(M² − 2E I1)),

    shifted by τ0 = F(φ0 | k²), φ0 = atan2(sn, cn) at t = 0, to match the initial ω.
    """
    model = _model("intermediate_axis_flip")
    I1, I2, I3 = np.diag(model.J[0])
    w0 = model.initial.omega[0]
    E2 = float(np.sum(np.array([I1, I2, I3]) * w0**2))  # 2E
    M2 = float(np.sum((np.array([I1, I2, I3]) * w0) ** 2))
    assert I1 < I2 < I3 and M2 > E2 * I2  # the case of the formula
    A1 = np.sqrt((E2 * I3 - M2) / (I1 * (I3 - I1)))
    A2 = np.sqrt((E2 * I3 - M2) / (I2 * (I3 - I2)))
    A3 = np.sqrt((M2 - E2 * I1) / (I3 * (I3 - I1)))
    rate = np.sqrt((I3 - I2) * (M2 - E2 * I1) / (I1 * I2 * I3))
    m = (I2 - I1) * (E2 * I3 - M2) / ((I3 - I2) * (M2 - E2 * I1))
    tau0 = ellipkinc(np.arctan2(w0[1] / A2, w0[0] / A1), m)

    traj = mbody.simulate(model, t_end=10.0, fps=30)
    sn, cn, dn, _ = ellipj(tau0 + rate * traj.t, m)
    exact = np.stack((A1 * cn, A2 * sn, A3 * dn), axis=1)
    w = traj.angular_velocity[:, 0]
    assert np.abs(exact[0] - w0).max() < 1e-10  # the phase really matches the start
    assert np.sign(w[:, 1]).min() < 0  # it flipped within the run
    np.testing.assert_allclose(w, exact, rtol=0, atol=1e-7 * np.abs(w0).max())


def test_symmetric_top_torque_free_precession():
    """I1 = I2: ω1 + i ω2 = a e^{iλt}, λ = (I3 − I1) ω3 / I1 (the body cone, body axes);
    the symmetry axis cones around the fixed H at |H| / I1 (the space cone), at the
    constant half-angle atan(I1 a / (I3 ω3))."""
    model = _model("torque_free_symmetric")
    I1, _, I3 = np.diag(model.J[0])
    a, _, w3 = model.initial.omega[0]
    lam = (I3 - I1) * w3 / I1
    traj = mbody.simulate(model, t_end=20.0, fps=20)
    t, w = traj.t, traj.angular_velocity[:, 0]
    np.testing.assert_allclose(w[:, 0], a * np.cos(lam * t), atol=1e-9)
    np.testing.assert_allclose(w[:, 1], a * np.sin(lam * t), atol=1e-9)
    np.testing.assert_allclose(w[:, 2], w3, atol=1e-9)

    H = traj.angular_momentum()[0]
    h = H / np.linalg.norm(H)
    e3 = quat_to_matrix(traj.orientation[:, 0])[:, :, 2]  # symmetry axis, world
    np.testing.assert_allclose(np.degrees(np.arccos(e3 @ h)),
                               np.degrees(np.arctan2(I1 * a, I3 * w3)), atol=1e-7)
    # Azimuth of the axis about H: it must grow at |H| / I1.
    u = np.cross(h, [1.0, 0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(h, u)
    phi = np.unwrap(np.arctan2(e3 @ v, e3 @ u))
    rate = np.linalg.norm(H) / I1
    np.testing.assert_allclose(phi - phi[0], rate * t, atol=1e-7)
    assert rate == pytest.approx(3.00167, abs=1e-5)  # the number in the model's comment


@pytest.mark.parametrize("name", ["torque_free_asymmetric", "torque_free_symmetric",
                                  "intermediate_axis_flip"])
def test_torque_free_drift_over_100_s(name):
    traj = mbody.simulate(_model(name), t_end=100.0, fps=10)
    info = traj.info
    assert info["energy_conserved"] and info["angular_momentum_conserved"]
    assert info["energy_drift"] < 1e-8
    assert info["angular_momentum_drift"] < 1e-8
    # Recompute independently of the reported figures.
    T = traj.kinetic_energy()
    H = traj.angular_momentum()
    assert np.abs(T / T[0] - 1).max() < 1e-8
    assert np.linalg.norm(H - H[0], axis=1).max() / np.linalg.norm(H[0]) < 1e-8
    # Unit quaternions at every output sample.
    np.testing.assert_allclose(np.linalg.norm(traj.orientation, axis=2), 1.0, atol=1e-15)


def test_planar_body_under_time_varying_force_matches_its_integral():
    """F_x = 50 sin 2t at G, couple 0.5 cos 3t, gravity; m = 2, I_G = 0.1, v0 = (1, 0.5):
    x = t + 12.5 t − 6.25 sin 2t, y = 0.5 t − 9.81 t²/2, θ = (5/9)(1 − cos 3t)."""
    traj = mbody.simulate(_model("planar_time_varying_force"), t_end=4.0, fps=25)
    t = traj.t
    np.testing.assert_allclose(traj.position[:, 0, 0], t + 12.5 * t - 6.25 * np.sin(2 * t),
                               atol=1e-8)
    np.testing.assert_allclose(traj.position[:, 0, 1], 0.5 * t - 9.81 * t**2 / 2, atol=1e-8)
    np.testing.assert_allclose(traj.orientation[:, 0], 5 / 9 * (1 - np.cos(3 * t)), atol=1e-9)
    np.testing.assert_allclose(traj.angular_velocity[:, 0], 5 / 3 * np.sin(3 * t), atol=1e-9)
    np.testing.assert_allclose(traj.velocity[:, 0, 0], 1 + 12.5 * (1 - np.cos(2 * t)),
                               atol=1e-8)
    assert traj.position[25, 0, 0] == pytest.approx(7.81689108, abs=1e-8)  # model comment


def test_spinning_satellite_with_decaying_thrust_and_spin_up_couple():
    """Body-frame loads along the spin axis of a symmetric body: v_z = 2.4 (1 − e^{−t/4}),
    z = 2.4 (t − 4 (1 − e^{−t/4})), ω3 = 2 + (1/30)(t/2 − sin(2at)/(4a)), a = π/10."""
    traj = mbody.simulate(_model("satellite_thruster"), t_end=10.0, fps=10)
    t = traj.t
    a = np.pi / 10
    np.testing.assert_allclose(traj.velocity[:, 0, 2], 2.4 * (1 - np.exp(-t / 4)), atol=1e-9)
    np.testing.assert_allclose(traj.position[:, 0, 2], 2.4 * (t - 4 * (1 - np.exp(-t / 4))),
                               atol=1e-8)
    np.testing.assert_allclose(traj.angular_velocity[:, 0, 2],
                               2 + (t / 2 - np.sin(2 * a * t) / (4 * a)) / 30, atol=1e-9)
    np.testing.assert_allclose(traj.position[:, 0, :2], 0.0, atol=1e-9)
    # The spin axis stays along world z: the rotation is about z by ∫ω3 dt.
    R = quat_to_matrix(traj.orientation[:, 0])
    np.testing.assert_allclose(R[:, :, 2], np.tile([0, 0, 1.0], (len(t), 1)), atol=1e-9)


def test_spring_mass_damper_matches_damped_oscillator():
    """m ü + c u̇ + k u = 0 about the static sag: u = e^{−ζωt}(u0 cos ω_d t +
    (u̇0 + ζω u0)/ω_d sin ω_d t), ω = sqrt(k/m) = 20, ζ = c / (2 sqrt(k m)) = 0.1."""
    model = _model("spring_mass_damper")
    m, k, c, L0, g = 2.0, 800.0, 8.0, 0.5, 9.81
    y_eq = -(L0 + m * g / k) - 0.05  # the spring ends 0.05 m above the mass centre
    u0, du0 = -0.6 - y_eq, 0.2
    wn = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta**2)
    traj = mbody.simulate(model, t_end=3.0, fps=100)
    t = traj.t
    u = np.exp(-zeta * wn * t) * (u0 * np.cos(wd * t)
                                  + (du0 + zeta * wn * u0) / wd * np.sin(wd * t))
    np.testing.assert_allclose(traj.position[:, 0, 1] - y_eq, u, atol=1e-10)
    np.testing.assert_allclose(traj.position[:, 0, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(traj.orientation[:, 0], 0.0, atol=1e-12)
    # Damped: energy falls, by exactly what the damper dissipated (c ∫ u̇² dt, > 0).
    E = traj.series["energy"]
    assert E[-1] < E[0] and not traj.info["energy_conserved"]


def test_undamped_spring_conserves_energy():
    text = (MODELS / "spring_mass_damper.yaml").read_text().replace(
        "damping: 8 ", "damping: 0 ")
    model = mbody.loads(text)
    assert model.springs.damping[0] == 0
    traj = mbody.simulate(model, t_end=5.0, fps=50)
    assert traj.info["energy_conserved"]
    assert traj.info["energy_drift"] < 1e-9
    V = traj.series["potential_energy"]
    assert V.max() - V.min() > 0.1  # the spring and gravity potentials really change


def test_rotor_precesses_on_its_known_bearing_reactions():
    """Steady precession: the shaft turns about z at Ω = 0.2 rad/s, horizontal, the mass
    centre at rest, the spin component ω3 = 200 rad/s constant (model comment)."""
    model = _model("rotor_gyroscopic_bearings")
    traj = mbody.simulate(model, t_end=0.5, fps=20)
    t = traj.t
    shaft = quat_to_matrix(traj.orientation[:, 0])[:, :, 2]
    expected = np.stack((np.cos(0.2 * t), np.sin(0.2 * t), 0 * t), axis=1)
    np.testing.assert_allclose(shaft, expected, atol=1e-10)
    np.testing.assert_allclose(traj.position[:, 0], 0.0, atol=1e-10)
    np.testing.assert_allclose(traj.angular_velocity[:, 0, 2], 200.0, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(traj.angular_velocity[:, 0, :2], axis=1), 0.2,
                               rtol=1e-9)
    assert traj.reaction_labels == tuple(model.reactions)
    np.testing.assert_allclose(traj.reactions[:, 2:], [[196.2, 16.0]] * len(t))


def test_known_reaction_as_expression_of_time():
    """A body pushed by a known reaction A.Fx = 3 t (N): x = t³ / (2 m), m = 0.5."""
    model = mbody.loads("""
dimension: 3
bodies: [{name: b, mass: 0.5, inertia: [1, 1, 1]}]
joints: [{name: A, type: spherical, parent: ground, child: b, at: [0, 0, 0]}]
reactions: {A.Fx: "3*t", A.Fy: 0, A.Fz: 0}
""")
    traj = mbody.simulate(model, t_end=2.0, fps=10)
    np.testing.assert_allclose(traj.position[:, 0, 0], traj.t**3, atol=1e-10)
    np.testing.assert_allclose(traj.reactions[:, 0], 3 * traj.t)
    # The API's `known` overrides the file: a constant 1 N gives x = t².
    traj = mbody.simulate(model, t_end=2.0, fps=10, known={"A.Fx": 1.0})
    np.testing.assert_allclose(traj.position[:, 0, 0], traj.t**2, atol=1e-10)


def test_pendulum_with_unknown_pin_reactions_is_simulated_with_its_reactions():
    """Unknown reactions are solved at every step; the stored pin force at every sample
    is the closed form R = m a_G − m g, a_G = α ẑ × r − θ̇² r, α = −m g d sin θ / I_O;
    energy is conserved (ideal joint) and the joint stays assembled."""
    model = _model("pendulum")
    traj = mbody.simulate(model, t_end=1.0, fps=20)
    m, I_G = model.mass[0], model.J[0, 2, 2]
    g = -model.gravity[1]
    r = traj.position[:, 0, :]  # pin at the origin
    d = np.linalg.norm(r, axis=1)
    theta = np.arctan2(r[:, 0], -r[:, 1])
    w = traj.angular_velocity[:, 0]
    alpha = -m * g * d * np.sin(theta) / (I_G + m * d**2)
    a_G = alpha[:, None] * np.stack((-r[:, 1], r[:, 0]), axis=1) - w[:, None] ** 2 * r
    R = m * a_G - m * np.array([0.0, -g])
    got = traj.reactions[:, [traj.reaction_labels.index("O.Fx"),
                             traj.reaction_labels.index("O.Fy")]]
    np.testing.assert_allclose(got, R, rtol=1e-8, atol=1e-8)
    assert traj.info["energy_conserved"] and traj.info["energy_drift"] < 1e-9
    assert traj.info["joint_position_drift"] < 1e-9
    assert traj.info["joint_velocity_drift"] < 1e-8
    assert "coordinate projection" in traj.info["joint_stabilisation"]
    assert not traj.info["angular_momentum_conserved"]  # the pin exerts a moment


def test_pluggable_dynamics_and_samples():
    model = _model("seed_example_2")
    calls = []

    def f(model, state):  # constant angular acceleration about body 3, no rotation rates
        calls.append(state.t)
        out = np.zeros((model.n, 6))
        out[:, 5] = 2.0
        return out

    traj = mbody.simulate(model, t_end=1.0, fps=4, dynamics=f)
    np.testing.assert_allclose(traj.t, [0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(traj.angular_velocity[:, 0, 2], 3 + 2 * traj.t, atol=1e-12)
    assert len(calls) == traj.info["evaluations"] > 0
    assert not traj.info["energy_conserved"]  # foreign dynamics: nothing is promised


def test_fast_planar_wheel_keeps_its_turns():
    """θ is integrated, not read back from the quaternion: a wheel at 100 rad/s sampled
    at 10 fps (10 rad per frame) still reports θ = 100 t."""
    model = mbody.loads("""
dimension: 2
bodies: [{name: w, mass: 1, inertia: 0.1, angular_velocity: 100}]
""")
    traj = mbody.simulate(model, t_end=1.0, fps=10)
    np.testing.assert_allclose(traj.orientation[:, 0], 100 * traj.t, atol=1e-9)


@pytest.mark.parametrize("kwargs, match", [
    ({"t_end": -1}, "t_end"), ({"fps": 0}, "fps"), ({"rtol": 0}, "rtol"),
    ({"method": "dop853"}, "DOP853"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(mbody.MbodyError, match=match):
        mbody.simulate(_model("seed_example_2"), **kwargs)


def test_cli_simulate_and_plot(tmp_path, capsys):
    run = tmp_path / "run.npz"
    assert main(["simulate", str(MODELS / "torque_free_asymmetric.yaml"), "--t-end", "2",
                 "--fps", "30", "-o", str(run)]) == 0
    out = capsys.readouterr().out
    assert "61 samples" in out and "relative drift" in out and f"wrote {run}" in out
    traj = mbody.Trajectory.load(run)
    assert traj.t[-1] == 2.0 and traj.body_names == ("block",)
    png = tmp_path / "run.png"
    assert main(["plot", str(run), "-o", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    assert main(["simulate", str(MODELS / "pendulum.yaml"), "--t-end", "0.5",
                 "-o", str(tmp_path / "pendulum.npz")]) == 0
    out = capsys.readouterr().out
    assert "joints: reactions solved at every step (coordinate projection" in out
    assert "O.Fx" in mbody.Trajectory.load(tmp_path / "pendulum.npz").reaction_labels
    with pytest.raises(SystemExit) as exc:  # refused by the parser, with the range
        main(["simulate", str(MODELS / "seed_example_2.yaml"), "--fps", "-3"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "argument --fps: expected a number of samples per second above 0 up to 1e6, " \
        "got '-3'" in err and "Traceback" not in err


def _panel_titles(traj: mbody.Trajectory) -> list[str]:
    from mbody.present.plot import plot_trajectory

    return [a.get_title() for a in plot_trajectory(traj).axes]


def test_plot_leaves_out_panels_with_nothing_to_show(tmp_path, capsys):
    """A planar revolute joint has force components only: the figure has no empty
    'no joint reaction moments' axes, just the five panels that show something (the
    lone last one spanning its row); a run without joints keeps its four panels."""
    import dataclasses

    traj = mbody.simulate(_model("double_pendulum"), t_end=0.2, fps=30)
    assert traj.reaction_labels and not any(".M" in lab for lab in traj.reaction_labels)
    titles = _panel_titles(traj)
    assert len(titles) == 5 and not any(t.startswith("no ") for t in titles)
    assert titles[-1] == "joint reaction forces, joint axes"
    run, png = tmp_path / "dp.npz", tmp_path / "dp.png"
    traj.save(run)
    assert main(["plot", str(run), "-o", str(png)]) == 0
    assert capsys.readouterr().out == f"wrote {png}\n"
    # moments only (forces known): the force panel is the one left out
    moments = dataclasses.replace(
        traj, reaction_labels=tuple(lab.replace(".F", ".M") for lab in traj.reaction_labels))
    titles = _panel_titles(moments)
    assert len(titles) == 5 and titles[-1] == "joint reaction moments, joint axes"
    free = mbody.simulate(_model("torque_free_asymmetric"), t_end=0.2, fps=30)
    assert len(_panel_titles(free)) == 4


def test_a_known_reaction_of_t_on_a_mechanism_is_the_cores():
    """`known` values that vary in time join the model's known reactions, which the core
    evaluates at every stage (once refused for mechanisms): the same run as the value
    written in the file's `reactions:`, the stored series the expression itself, and the
    other components solved."""
    import yaml

    path = Path(__file__).resolve().parents[1] / "models" / "double_pendulum.yaml"
    given = mbody.simulate(mbody.load(path), 1.0, 30, known={"A.Fx": "0.5*sin(3*t)"})
    spec = yaml.safe_load(path.read_text())
    spec["reactions"] = {"A.Fx": "0.5*sin(3*t)"}
    written = mbody.simulate(mbody.load(spec), 1.0, 30)
    np.testing.assert_array_equal(given.position, written.position)
    np.testing.assert_array_equal(given.reactions, written.reactions)
    i = given.reaction_labels.index("A.Fx")
    np.testing.assert_allclose(given.reactions[:, i], 0.5 * np.sin(3 * given.t), rtol=0,
                               atol=1e-15)
    free = mbody.simulate(mbody.load(path), 1.0, 30)  # A.Fx solved: another motion
    assert np.max(np.abs(free.position - given.position)) > 1e-3


def test_initial_joint_errors_are_the_runs_own_start_each_time():
    """A model's own start is checked once and kept (`Workspace.memo`); a run from another
    state reports that state's errors, and neither changes what the next run reports."""
    model = mbody.load(MODELS / "pendulum.yaml")
    s0 = model.initial
    off = mbody.State(s0.position + [0.0, 0.1, 0.0], s0.quaternion.copy(),
                      s0.velocity.copy(), s0.omega.copy(), 0.0)
    first = mbody.simulate(model, 0.1, 10).info["initial_joint_errors"]
    assert first == []
    run = mbody.simulate(model, 0.1, 10, initial=off)
    moved = run.info["initial_joint_errors"]
    assert moved and all("phi" in e for e in moved)
    # said among the run's warnings too (Python users read those), once in the summary
    assert run.info["warnings"][0].startswith("the initial state breaks joint constraints")
    assert summary(run).count("the initial state breaks joint constraints") == 1
    first.append("changed by the caller")
    again = mbody.simulate(model, 0.1, 10).info["initial_joint_errors"]
    assert again == []
    assert mbody.simulate(model, 0.1, 10, initial=off).info["initial_joint_errors"] == moved


def test_a_file_start_off_its_joints_is_described_whatever_the_gate():
    """The file's own start is described (`joint_errors`) only when the core's count
    (`Workspace.breaks_joints`) says it may break a joint. A file whose rod starts moving
    along its pin is described; and over states near the shipped models' starts, on
    both sides of the thresholds, the gate says False only where `joint_errors` finds
    nothing (the core's scales are never larger)."""
    from mbody.equations.joints import joint_errors
    from mbody.equations.workspace import workspace

    text = (MODELS / "pendulum.yaml").read_text().replace(
        "position: [0.25, -0.4330127018922193]",
        "position: [0.25, -0.4330127018922193]\n    velocity: [0, 1e-3]")
    moving = mbody.loads(text)
    run = mbody.simulate(moving, 0.1, 10)
    assert run.info["initial_joint_errors"] == joint_errors(moving, moving.initial) != []
    assert run.info["warnings"][0].startswith("the initial state breaks joint constraints")

    rng = np.random.default_rng(7)
    seen = set()
    for name in ("pendulum", "double_pendulum", "fourbar_planar", "fourbar_spatial",
                 "slider_crank", "heavy_top", "gyroscope_gimbals", "screw_jack", "bricard"):
        model = mbody.load(MODELS / f"{name}.yaml")
        ws, s0 = workspace(model), model.initial
        for _ in range(30):
            scale = 10.0 ** rng.uniform(-12, -3)
            state = s0.replace(
                position=s0.position + scale * rng.standard_normal(s0.position.shape),
                velocity=s0.velocity + scale * rng.standard_normal(s0.velocity.shape))
            described = joint_errors(model, state)
            gate = ws.breaks_joints(state)
            assert gate or not described, (name, scale, described)
            seen.add(bool(described))
    assert seen == {True, False}  # both sides of the thresholds were tried


def test_a_run_keeps_the_model_text_after_the_file_is_gone(tmp_path):
    """The trajectory keeps the text the model was read from (line ends as a text file
    reads them), with the file since removed: it can still be drawn and checked."""
    text = (MODELS / "pendulum.yaml").read_text(encoding="utf-8")
    path = tmp_path / "pendulum.yaml"
    path.write_bytes(text.replace("\n", "\r\n").encode("utf-8"))
    model = mbody.load(path)
    path.unlink()
    traj = mbody.simulate(model, 0.1, 10)
    assert traj.model_yaml == text
    assert mbody.simulate(model, 0.1, 10).model_yaml == text


@pytest.mark.parametrize("name", ["fourbar_planar", "torque_free_asymmetric"])
def test_a_repeated_run_is_the_first_one_again(name):
    """What a run keeps of its model (the start moved onto the joints, the sample times)
    changes nothing: the second run equals the first bit for bit, even after the caller
    wrote into the first one's arrays."""
    model = mbody.load(MODELS / f"{name}.yaml")
    first = mbody.simulate(model, 0.5, 30)
    kept = {k: getattr(first, k).copy() for k in ("t", "position", "orientation",
                                                   "velocity", "angular_velocity")}
    for array in kept:
        getattr(first, array)[...] = np.nan
    second = mbody.simulate(model, 0.5, 30)
    for k, v in kept.items():
        np.testing.assert_array_equal(getattr(second, k), v)
    other = mbody.simulate(model, 0.25, 20)
    assert other.t[-1] == 0.25 and len(other.t) == 6


def test_a_method_named_in_the_wrong_case_gets_its_name_suggested():
    model = mbody.load(MODELS / "pendulum.yaml")
    with pytest.raises(mbody.MbodyError, match=r"unknown integrator 'dop853'; did you mean "
                                               r"'DOP853'\?"):
        mbody.simulate(model, 1.0, method="dop853")
    with pytest.raises(mbody.MbodyError, match=r"did you mean 'LSODA'\?"):
        mbody.simulate(model, 1.0, method="lsoda")

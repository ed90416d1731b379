"""Simulations that cannot silently run away: step and wall-time budgets, cost and aliasing
warnings, the evaluations spent on sampling, and bounded motion of every shipped model."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.simulate import DEFAULT_MAX_STEPS, summary

MODELS = Path(__file__).resolve().parent.parent / "models"
SHIPPED = sorted(MODELS.glob("*.yaml"))

# A plate shaken ever faster (the load turns at e^t rad/s): the step size collapses.
CHIRP = """
dimension: 2
bodies: [{name: plate, mass: 1, inertia: 0.1}]
loads: [{name: shake, type: force, body: plate, force: ["sin(exp(t))", 0]}]
"""
WHEEL = """
dimension: 2
bodies: [{name: wheel, mass: 1, inertia: 0.1, angular_velocity: 100}]
"""


def _model(name: str) -> mbody.Model:
    return mbody.load(MODELS / f"{name}.yaml")


# -- budgets ---------------------------------------------------------------------------------

def test_step_budget_stops_the_cli_with_one_paragraph_and_exit_2(tmp_path, capsys):
    run = tmp_path / "run.npz"
    assert main(["simulate", str(MODELS / "slider_crank.yaml"), "--max-steps", "50",
                 "-o", str(run)]) == 2
    captured = capsys.readouterr()
    err = captured.err
    assert captured.out == "" and "Traceback" not in err
    assert err.startswith("mbody: error: the simulation stopped at the step budget: 50 steps "
                          "(--max-steps 50), at t = ") and err.count("\n") == 1
    for piece in (" s of 10 s: ", "steps per simulated second so far",
                  "at that rate the whole run needs about", "No trajectory is kept",
                  "a shorter --t-end", "a looser --rtol (e.g. 1e-8)",
                  "a stiff integrator such as --method Radau", "raise --max-steps."):
        assert piece in err, piece
    assert not run.exists()  # nothing written: the message says so
    t = float(re.search(r"at t = (\S+) s of", err).group(1))
    rate = float(re.search(r": (\S+) steps per simulated second so far", err).group(1))
    assert 0 < t < 10 and rate == pytest.approx(50 / t, rel=1e-3)


def test_step_budget_from_python_and_a_run_that_fits():
    model = _model("torque_free_asymmetric")
    with pytest.raises(mbody.MbodyError, match=r"step budget: 10 steps \(max_steps=10\)"):
        mbody.simulate(model, t_end=5.0, max_steps=10)
    traj = mbody.simulate(model, t_end=5.0, max_steps=69)  # exactly its 69 steps
    assert traj.info["steps"] == 69 and traj.t[-1] == 5.0
    assert mbody.simulate(model, t_end=1.0, max_steps=None).info["steps"] > 0
    assert DEFAULT_MAX_STEPS == 1_000_000


def test_wall_time_budget(capsys):
    # Any step takes longer than a nanosecond: the budget is hit after the first step.
    # each surface names the budget as it was given: max_wall=1e-9 in Python, --max-wall
    with pytest.raises(mbody.MbodyError, match=r"wall-time budget: .* \(max_wall=1e-9\), "
                       r"at t = .* s of 10 s: .*raise max_wall\.$"):
        mbody.simulate(_model("pendulum"), max_wall=1e-9)
    assert main(["simulate", str(MODELS / "pendulum.yaml"), "--max-wall", "1e-9"]) == 2
    err = capsys.readouterr().err
    assert "mbody: error: the simulation stopped at the wall-time budget" in err
    assert "(--max-wall 1e-9)" in err and err.endswith("raise --max-wall.\n")
    assert "Traceback" not in err and err.count("\n") == 1


@pytest.mark.parametrize("kwargs", [{"max_steps": 0}, {"max_steps": -5}, {"max_steps": 2.5},
                                    {"max_steps": True}, {"max_wall": 0},
                                    {"max_wall": -1.0}, {"max_wall": float("nan")},
                                    {"max_wall": float("inf")}])
def test_bad_budgets(kwargs):
    with pytest.raises(mbody.MbodyError, match=next(iter(kwargs))):
        mbody.simulate(_model("seed_example_2"), t_end=0.1, **kwargs)


def test_cli_budget_options(capsys):
    args = ["simulate", str(MODELS / "seed_example_2.yaml"), "--t-end", "0.5"]
    assert main(args + ["--max-steps", "0"]) == 0  # 0: no limit
    # refused by the parser (argparse exits 2), with the documented range
    for value, message in (
            (["--max-steps", "-1"], "argument --max-steps: expected a whole number of steps "
             "from 1 to 1 000 000 000 (0: no limit), got '-1'"),
            (["--max-wall", "0"], "argument --max-wall: expected a number of seconds above 0 "
             "up to 1e7, got '0'"),
            (["--max-steps", "many"], "argument --max-steps: expected a whole number of steps "
             "from 1 to 1 000 000 000 (0: no limit), got 'many'")):
        with pytest.raises(SystemExit) as exc:
            main(args + value)
        assert exc.value.code == 2
        assert capsys.readouterr().err.endswith(f"mbody: error: {message}\n")


# -- warnings --------------------------------------------------------------------------------

def test_a_collapsing_step_size_is_warned_about():
    traj = mbody.simulate(mbody.loads(CHIRP), t_end=8.0, fps=30)
    rate = traj.info["step_rate"]
    assert rate["peak"] > 20 * rate["start"]
    (w,) = traj.info["warnings"]
    m = re.match(r"the integration slowed down from t = (\S+) s: (\S+) steps per simulated "
                 r"second at t = (\S+) \.\. (\S+) s, (\d+) times the (\S+) per second over "
                 r"the first (\S+) s\.", w)
    assert m, w
    assert 4 < float(m.group(1)) < float(m.group(3)) < float(m.group(4)) <= 8
    assert float(m.group(2)) == pytest.approx(rate["peak"], rel=1e-3)
    assert int(m.group(5)) > 20
    assert "--method Radau" in w and "--rtol" in w
    assert f"warning: {w}" in summary(traj)


def test_steady_runs_have_no_warnings():
    for name in ("torque_free_asymmetric", "pendulum", "spring_mass_damper"):
        traj = mbody.simulate(_model(name), t_end=10.0)
        assert traj.info["warnings"] == [], name
        assert "warning" not in summary(traj)


def test_a_spin_that_aliases_the_frame_rate_is_warned_about(tmp_path, capsys):
    model = mbody.loads(WHEEL)
    traj = mbody.simulate(model, t_end=1.0, fps=10)  # 15.9 rev/s > 10 fps / 2
    (w,) = traj.info["warnings"]
    assert w.startswith("spin faster than 10 fps can show: wheel at up to 100 rad/s "
                        "(15.9 rev/s, at t = 0 s)")
    assert "fps / 2 = 5 rev/s" in w and w.endswith("use --fps 32 or more")
    assert mbody.simulate(model, t_end=1.0, fps=32).info["warnings"] == []
    assert mbody.simulate(model, t_end=1.0, fps=31).info["warnings"] != []
    path = tmp_path / "wheel.yaml"
    path.write_text(WHEEL)
    assert main(["simulate", str(path), "--t-end", "1", "--fps", "10"]) == 0
    assert "warning: spin faster than 10 fps can show: wheel" in capsys.readouterr().out
    # spatial bodies: |omega|, the fastest body first
    traj = mbody.simulate(_model("spinning_disc_bearings"), t_end=0.2, fps=60)
    (w,) = traj.info["warnings"]
    assert w.startswith("spin faster than 60 fps can show: disc at up to 300 rad/s")


def test_warnings_survive_save_and_load(tmp_path):
    traj = mbody.simulate(mbody.loads(WHEEL), t_end=1.0, fps=10)
    traj.save(tmp_path / "w.npz")
    again = mbody.Trajectory.load(tmp_path / "w.npz")
    assert again.info["warnings"] == traj.info["warnings"]
    assert summary(again) == summary(traj)


# -- sampling --------------------------------------------------------------------------------

def test_sampling_evaluations_are_counted():
    """DOP853: 12 evaluations per attempted step, 2 to start (f(0) and the initial step
    size), and 3 more for the interpolant on each step that holds output samples."""
    model = _model("torque_free_asymmetric")
    calls = []

    def f(model, state):
        calls.append(state.t)
        return mbody.solve.dynamics.accelerations(model, state)

    traj = mbody.simulate(model, t_end=5.0, fps=60, dynamics=f)
    i = traj.info
    assert i["evaluations"] == len(calls)
    assert i["sampling_evaluations"] > 0 and i["sampling_evaluations"] % 3 == 0
    assert i["sampling_evaluations"] <= 3 * i["steps"]
    assert (i["evaluations"] - i["sampling_evaluations"] - 2) % 12 == 0
    # fewer samples, fewer interpolants; the steps do not change
    sparse = mbody.simulate(model, t_end=5.0, fps=1, dynamics=f).info
    assert sparse["steps"] == i["steps"]
    assert sparse["sampling_evaluations"] == 3 * 5  # one step holds each of t = 1 .. 5
    assert i["evaluations"] - i["sampling_evaluations"] == \
        sparse["evaluations"] - sparse["sampling_evaluations"]
    # RK45's interpolant is free
    assert mbody.simulate(model, t_end=1.0, method="RK45").info["sampling_evaluations"] == 0
    assert "of them for the samples" in summary(traj)


# -- shipped models --------------------------------------------------------------------------

SPIN_UP = {"screw_jack"}
"""Shipped models that speed up without bound by design: the screw jack's 2 N m motor
beats the 1.593 N m that holds its load, theta'' = 438.518 rad/s^2 (its file's comment)."""


@pytest.mark.parametrize("path", [p for p in SHIPPED if p.stem not in SPIN_UP],
                         ids=[p.stem for p in SHIPPED if p.stem not in SPIN_UP])
def test_every_shipped_model_simulates_10_s_within_a_step_budget(path):
    """The heaviest needs about 10 000 steps: 30 000 is generous, and a model that runs
    away (the slider-crank of old needed 24 500 and reached 700 rad/s) is caught."""
    traj = mbody.simulate(mbody.load(path), t_end=10.0, fps=10, max_steps=30_000)
    assert traj.t[-1] == 10.0
    assert not any("slowed down" in w for w in traj.info["warnings"])
    w = traj.angular_velocity
    assert np.all(np.isfinite(w)) and np.abs(w).max() < 500  # rad/s


def test_the_screw_jack_spins_up_as_its_closed_form_says():
    """The screw jack at constant acceleration: omega(t) = 50 + alpha t, the platform's
    height z(t) = 0.425 + h (50 t + alpha t^2 / 2), h = p / 2 pi, alpha = (tau - m g h) /
    (m h^2 + J); after 5 s the screw turns at 2243 rad/s, within the step budget, and the
    run says that an animation at 10 fps cannot show such a spin."""
    traj = mbody.simulate(mbody.load(MODELS / "screw_jack.yaml"), t_end=5.0,
                          fps=10, max_steps=30_000)
    h = 0.005 / (2 * np.pi)
    m, J = 204.0, 4.0 * 0.02**2 / 2
    alpha = (2.0 - m * 9.81 * h) / (m * h * h + J)
    t = np.asarray(traj.t)
    assert t[-1] == 5.0
    # DOP853 at rtol 1e-10 over a few thousand steps: the error stays far below 1e-8
    np.testing.assert_allclose(traj.angular_velocity[:, 0, 2], 50 + alpha * t, rtol=1e-8)
    np.testing.assert_allclose(traj.position[:, 1, 2],
                               0.425 + h * (50 * t + alpha * t**2 / 2), rtol=1e-8)
    assert any("spin faster than 10 fps" in w for w in traj.info["warnings"])


def test_slider_crank_last_power_stroke_then_a_free_coast():
    """The model comment: 4 kN and 60 N m at t = 0 (the initial-state numbers are those
    of constant loads), both fading; after 0.1 s the mechanism coasts with T + V = 9.83 J,
    conserved, the crank turning forward at 76 .. 151 rad/s."""
    model = _model("slider_crank")
    asm = mbody.assemble(model)
    Q = dict(zip(asm.coordinates, asm.Q, strict=True))
    assert Q["piston.x"] == -4000.0 and Q["crank.theta"] == -60.0
    traj = mbody.simulate(model, t_end=10.0, fps=60)
    assert traj.info["steps"] < 15_000 and traj.info["warnings"] == []
    E = traj.series["energy"][traj.t >= 0.5]
    assert E.mean() == pytest.approx(9.83, abs=0.01)
    assert np.ptp(E) < 1e-7 * E.mean()
    crank = traj.angular_velocity[traj.t >= 0.5, 0]
    assert crank.min() == pytest.approx(76.3, abs=0.5)
    assert crank.max() == pytest.approx(151, abs=1)
    assert traj.angular_velocity[:, 0].max() <= 157.08 + 1e-6  # at the samples
    assert traj.info["joint_position_drift"] < 1e-9

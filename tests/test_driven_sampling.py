"""Runs of driven mechanisms as a new user makes them: a run whose samples are too far
apart for its drivers' motion says so (its peaks read low), the energy check of a
mechanism at rest, and `mbody.kinematics` at a time that is not a number."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import main
from mbody.simulate.kinematic import kinematic_run
from mbody.simulate.kinematic import summary as kinematic_summary
from mbody.simulate.peaks import PEAK_SAMPLES, sampling_warning
from mbody.simulate.simulation import summary

ROOT = Path(__file__).resolve().parents[1]
SPARSE = "peaks sampled too sparsely"
"""How the warning of samples too sparse for the drivers' motion begins."""

M, ARM = 2.0, 0.1  # the crank's mass (kg) and its mass centre's distance from the pin (m)
OMEGA = 600 * 2 * math.pi / 60  # 600 rpm
PERIOD = 2 * math.pi / OMEGA

CRANK = f"""model: crank
description: "an unbalanced crank driven at 600 rpm, no gravity"
dimension: 2
gravity: [0, 0]
bodies:
  - {{name: crank, mass: {M}, inertia: 0.01, position: [{ARM}, 0]}}
joints:
  - {{name: O, type: revolute, parent: ground, child: crank, at: [0, 0]}}
drivers:
  - {{name: motor, joint: O, speed: "600 rpm"}}
"""


def _sparse(traj) -> list[str]:
    return [w for w in traj.info["warnings"] if w.startswith(SPARSE)]


def test_the_threshold_is_a_sampled_sines_peak_within_half_a_percent():
    """N samples a revolution read a sine's peak at worst cos(pi / N) of it (the peak
    half-way between two samples): 36 keep that within 0.4 %."""
    assert 1 - math.cos(math.pi / PEAK_SAMPLES) < 0.004
    assert 1 - math.cos(math.pi / (PEAK_SAMPLES - 1)) > 0.004


@pytest.mark.parametrize("per_rev", [6, 12, 24])
def test_a_sampled_peak_reads_as_low_as_the_warning_says(per_rev):
    """The crank's pin carries m a_G = -m r w^2 (cos theta, sin theta) (world axes), a
    sine of the driver's angle: sampled N times a revolution with the peak half-way
    between two samples, the largest sample is cos(pi / N) of the peak, the figure the
    warning gives."""
    model = mbody.loads(CRANK)
    fps = per_rev / PERIOD
    t0 = PERIOD / (2 * per_rev)  # the samples straddle theta = 0 and pi
    run = kinematic_run(model, t0 + PERIOD, fps, t_start=t0, axes="world")
    fx = run.reactions[:, run.reaction_labels.index("O.Fx")]
    peak = M * ARM * OMEGA**2
    fine = kinematic_run(model, PERIOD, 3600 / PERIOD, axes="world")
    assert np.abs(fine.reactions[:, fine.reaction_labels.index("O.Fx")]).max() == \
        pytest.approx(peak, rel=1e-12)
    low = 1 - np.abs(fx).max() / peak
    assert low == pytest.approx(1 - math.cos(math.pi / per_rev), rel=1e-9)
    (w,) = _sparse(run)
    assert f"{per_rev:g} samples a revolution" in w
    assert f"up to {100 * low:.2g} % low" in w


def test_simulate_of_the_shipped_driven_slider_crank_warns_at_its_default_sampling():
    """`mbody simulate`'s defaults (10 s at 60 fps) are 6 samples a revolution at 600 rpm:
    the run keeps them, and says its peaks read low and what to do."""
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    run = mbody.simulate(model)
    assert run.info["kinematic"] and run.info["samples"] == 601
    (w,) = _sparse(run)
    assert "motor turns at 600 rpm" in w and "60 fps is 6 samples a revolution" in w
    assert "up to 13 % low" in w  # 1 - cos(30 deg)
    assert "--fps 360 or more" in w and "mbody kinematics" in w
    assert f"warning: {w}" in summary(run)
    # the run's own peak of the motor torque against one a degree: lower, as said
    fine = kinematic_run(model, 0.1, 3600)
    label = "motor.M"
    coarse_peak = next(p["value"] for p in run.info["peaks"] if p["label"] == label)
    fine_peak = next(p["value"] for p in fine.info["peaks"] if p["label"] == label)
    assert 0.05 < 1 - coarse_peak / fine_peak < 0.5
    assert _sparse(fine) == []


def test_the_warning_starts_below_peak_samples_a_revolution():
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    at = kinematic_run(model, 0.1, PEAK_SAMPLES / 0.1)  # exactly 36 a revolution
    assert _sparse(at) == []
    (w,) = _sparse(kinematic_run(model, 0.1, (PEAK_SAMPLES - 0.5) / 0.1))
    assert "35.5 samples a revolution" in w and "--fps 360 or more" in w


def test_a_partly_driven_run_warns_too_but_cannot_be_a_kinematic_run():
    model = mbody.load(ROOT / "models" / "flyball_governor.yaml")
    assert _sparse(mbody.simulate(model, 1.0, 60)) == []  # 60 a revolution at 60 rpm
    run = mbody.simulate(model, 1.0, 20)
    assert not run.info.get("kinematic")
    (w,) = _sparse(run)
    assert "motor turns at 60 rpm" in w and "20 fps is 20 samples a revolution" in w
    assert "--fps 36 or more" in w and "mbody kinematics" not in w
    assert f"warning: {w}" in summary(run)


def test_the_fastest_of_several_steady_drivers_is_named():
    """Two cranks driven at 600 and 1800 rpm: the faster has the fewer samples a
    revolution."""
    text = CRANK.replace("- {name: crank,", "- {name: crank2, mass: 1, inertia: 0.01, "
                         "position: [0.5, 0]}\n  - {name: crank,")
    text += ("  - {name: fast, joint: O2, speed: \"-1800 rpm\"}\n")
    text = text.replace("joints:\n", "joints:\n  - {name: O2, type: revolute, parent: ground, "
                        "child: crank2, at: [0.4, 0]}\n")
    run = kinematic_run(mbody.loads(text), 0.1, 600)
    (w,) = _sparse(run)
    assert w.startswith(f"{SPARSE}: fast turns at 1800 rpm") and "20 samples" in w


def test_no_check_without_a_steady_driver():
    """A driver at rest, a law whose rate varies, and runs without drivers: nothing to
    count samples against."""
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    still = model.with_values({"drivers.motor.speed": "0 rpm"})
    assert _sparse(kinematic_run(still, 1.0, 10)) == []
    assert sampling_warning(mbody.load(ROOT / "models" / "pendulum.yaml"),
                            mbody.simulate(mbody.load(ROOT / "models" / "pendulum.yaml"),
                                           1.0, 10)) is None


def test_the_warning_is_saved_with_the_run_and_printed_by_both_commands(tmp_path, capsys):
    out = tmp_path / "run.npz"
    model = str(ROOT / "models" / "slider_crank_driven.yaml")
    assert main(["simulate", model, "--t-end", "0.5", "-o", str(out), "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert f"warning: {SPARSE}: motor turns at 600 rpm" in printed
    again = mbody.Trajectory.load(out)
    assert _sparse(again) and kinematic_summary(again) in printed
    assert main(["kinematics", model, "--fps", "120"]) == 0
    assert "warning: " + SPARSE in capsys.readouterr().out
    assert main(["kinematics", model, "--fps", "120", "--json"]) == 0  # with the peaks
    shown = json.loads(capsys.readouterr().out)
    assert shown["peaks"] and [w[:len(SPARSE)] for w in shown["warnings"]] == [SPARSE]
    assert main(["kinematics", model]) == 0  # one revolution, one sample a degree
    assert "warning" not in capsys.readouterr().out


def test_a_long_kinematic_run_closes_where_the_drivers_angle_is_large():
    """The shipped Scotch yoke at simulate's defaults: after 6 s at 600 rpm the motor's
    angle is 380 rad, known to 5.7e-14 rad, and Newton's steps cannot go below that (the
    run stopped there as if at a dead centre). Its torque is the closed form's,
    m_y r^2 w^2 sin(theta) cos(theta) (a balanced crank, a yoke sliding level), to the
    rounding of the angle."""
    model = mbody.load(ROOT / "models" / "scotch_yoke.yaml")
    run = mbody.simulate(model)  # 10 s at 60 fps
    assert run.info["kinematic"] and run.info["samples"] == 601
    assert run.info["newton_steps_most"] <= 4
    theta = math.radians(30) + OMEGA * run.t
    torque = 0.8 * 0.05**2 * OMEGA**2 * np.sin(theta) * np.cos(theta)
    got = run.reactions[:, run.reaction_labels.index("motor.M")]
    assert np.abs(got - torque).max() < 1e-9 * np.abs(torque).max()
    assert _sparse(run)  # 6 samples a revolution


# -- the energy check of a mechanism at rest -----------------------------------------------

def test_the_energy_check_at_rest_says_the_powers_are_zero():
    """Driven at 0 rpm nothing moves: every power is zero (rounding of velocities of
    1e-29 m/s), and the check holds trivially: stored as 0, said so."""
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    run = kinematic_run(model.with_values({"drivers.motor.speed": "0 rpm"}), 1.0, 100)
    assert run.info["power_balance_residual"] == 0.0
    assert run.info["energy_balance_residual"] == 0.0
    text = kinematic_summary(run)
    assert "every power is zero" in text and "1.0e+00" not in text
    # a slow motion is still checked: a revolution a day
    day = model.with_values({"drivers.motor.speed": f"{2 * math.pi / 86400!r} rad/s"})
    slow = kinematic_run(day, 1.0, 100)
    assert 0 < slow.info["power_balance_residual"] < 1e-9
    assert "every power is zero" not in kinematic_summary(slow)


def test_the_cli_prints_the_energy_check_at_rest(capsys):
    model = str(ROOT / "models" / "slider_crank_driven.yaml")
    assert main(["kinematics", model, "--set", "drivers.motor.speed=0 rpm"]) == 0
    out = capsys.readouterr().out
    assert "energy check: every power is zero" in out and "1.0e+00" not in out


# -- mbody.kinematics at a time that is not a number ----------------------------------------

@pytest.mark.parametrize("t", [math.nan, math.inf, -math.inf])
def test_kinematics_refuses_a_time_that_is_not_finite(t):
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    with pytest.raises(mbody.MbodyError, match=r"t must be a finite number of seconds"):
        mbody.kinematics(model, t)

"""Runs of driven mechanisms as a new user makes them: a run whose samples are too far
apart for its drivers' motion says so (its peaks read low), the energy check of a
mechanism at rest, and `mbody.kinematics` at a time that is not a number."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import main
from mbody.simulate.kinematic import kinematic_run
from mbody.simulate.kinematic import summary as kinematic_summary

ROOT = Path(__file__).resolve().parents[1]
OMEGA = 600 * 2 * math.pi / 60  # 600 rpm


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

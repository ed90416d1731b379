"""Runs of driven mechanisms as a new user makes them: a run whose samples are too far
apart for its drivers' motion says so (its peaks read low), the energy check of a
mechanism at rest, and `mbody.kinematics` at a time that is not a number."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mbody

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


# -- mbody.kinematics at a time that is not a number ----------------------------------------

@pytest.mark.parametrize("t", [math.nan, math.inf, -math.inf])
def test_kinematics_refuses_a_time_that_is_not_finite(t):
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    with pytest.raises(mbody.MbodyError, match=r"t must be a finite number of seconds"):
        mbody.kinematics(model, t)

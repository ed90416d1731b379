"""Runs of driven mechanisms as a new user makes them: a run whose samples are too far
apart for its drivers' motion says so (its peaks read low), the energy check of a
mechanism at rest, and `mbody.kinematics` at a time that is not a number."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import mbody

ROOT = Path(__file__).resolve().parents[1]


# -- mbody.kinematics at a time that is not a number ----------------------------------------

@pytest.mark.parametrize("t", [math.nan, math.inf, -math.inf])
def test_kinematics_refuses_a_time_that_is_not_finite(t):
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    with pytest.raises(mbody.MbodyError, match=r"t must be a finite number of seconds"):
        mbody.kinematics(model, t)

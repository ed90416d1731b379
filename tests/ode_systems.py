"""Plain ODEs for the integrator's tests and benchmark (tests/test_dop853.py,
tools/bench_integrator.py): Python versions of the compiled core's built-in test systems
(mbody/kernel/src/dop853_module.c), written with the same operations in the same order,
so that both give the same numbers."""

from __future__ import annotations

import math

import numpy as np


def oscillator(t, y, w=2.0):
    return np.array([y[1], -(w * w) * y[0]])


def van_der_pol(t, y, mu=5.0):
    return np.array([y[1], mu * (1.0 - y[0] * y[0]) * y[1] - y[0]])


ARENSTORF_MU = 0.012277471
ARENSTORF_Y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]
ARENSTORF_PERIOD = 17.0652165601579625588917206249  # HNW I, II.0: the orbit closes


def arenstorf(t, y, mu=ARENSTORF_MU):
    nu = 1.0 - mu
    a, b, y2 = y[0] + mu, y[0] - nu, y[1] * y[1]
    ra, rb = a * a + y2, b * b + y2
    d1, d2 = ra * math.sqrt(ra), rb * math.sqrt(rb)
    return np.array([y[2], y[3], y[0] + 2.0 * y[3] - nu * a / d1 - mu * b / d2,
                     y[1] - 2.0 * y[2] - nu * y[1] / d1 - mu * y[1] / d2])


def pendulum(t, y, k=9.81):
    return np.array([y[1], -k * math.sin(y[0])])


SYSTEMS = {  # name: (Python function, params, y0, t0, t_bound)
    "oscillator": (oscillator, [2.0], [1.0, 0.0], 0.0, 10.0),
    "van_der_pol": (van_der_pol, [5.0], [2.0, 0.0], 0.0, 12.0),
    "arenstorf": (arenstorf, [ARENSTORF_MU], ARENSTORF_Y0, 0.0, ARENSTORF_PERIOD),
    "pendulum": (pendulum, [9.81], [2.5, 0.0], 0.0, 5.0),
}

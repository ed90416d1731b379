"""Exact time derivatives of expressions of t (mbody.model.calculus), against closed forms
written by hand: what a driver's law needs at velocity (f′) and acceleration (f″) level."""

from __future__ import annotations

import numpy as np
import pytest

from mbody.model.calculus import derivative
from mbody.model.expressions import compile_expression

T = np.linspace(0.05, 3.0, 11)

CASES = [  # f, f′, f″ (numpy, by hand)
    ("0.4 + 0.2*sin(t)", lambda t: 0.2 * np.cos(t), lambda t: -0.2 * np.sin(t)),
    ("12.566*t", lambda t: 12.566 + 0 * t, lambda t: 0 * t),
    ("0.05*sin(2*pi*t)", lambda t: 0.1 * np.pi * np.cos(2 * np.pi * t),
     lambda t: -0.2 * np.pi**2 * np.sin(2 * np.pi * t)),
    ("3*t^2 - exp(-t/2)*cos(4*t)",
     lambda t: 6 * t + np.exp(-t / 2) * (0.5 * np.cos(4 * t) + 4 * np.sin(4 * t)),
     lambda t: 6 + np.exp(-t / 2) * (-0.25 * np.cos(4 * t) - 2 * np.sin(4 * t)
                                     - 2 * np.sin(4 * t) + 16 * np.cos(4 * t))),
    ("sqrt(1+t^2)", lambda t: t / np.sqrt(1 + t**2), lambda t: (1 + t**2) ** -1.5),
    ("log(2+t)/(1+t)", lambda t: (1 / (2 + t)) / (1 + t) - np.log(2 + t) / (1 + t) ** 2,
     lambda t: (-1 / (2 + t) ** 2 / (1 + t) - 2 / ((2 + t) * (1 + t) ** 2)
                + 2 * np.log(2 + t) / (1 + t) ** 3)),
    ("tan(t/3)", lambda t: (1 + np.tan(t / 3) ** 2) / 3,
     lambda t: 2 * np.tan(t / 3) * (1 + np.tan(t / 3) ** 2) / 9),
    ("t^t", lambda t: t**t * (np.log(t) + 1),
     lambda t: t**t * ((np.log(t) + 1) ** 2 + 1 / t)),
    ("2^t", lambda t: 2**t * np.log(2), lambda t: 2**t * np.log(2) ** 2),
]


@pytest.mark.parametrize(("text", "d1", "d2"), CASES)
def test_first_and_second_derivatives_equal_the_closed_forms(text, d1, d2):
    f = compile_expression(text)
    f1 = derivative(f)
    f2 = derivative(f1)
    # each is a sum of a few products of exactly rounded terms: a few ulps of its scale
    for got, want in ((f1(T), d1(T)), (f2(T), d2(T))):
        scale = np.maximum(1.0, np.abs(want))
        assert np.all(np.abs(got - want) <= 1e-13 * scale * 50)


def test_constant_parts_fold_away():
    assert derivative(compile_expression("20 + 0*t")).tree == ("num", 0.0)
    f1 = derivative(compile_expression("1.5*t"))
    assert f1.constant and f1.value == 1.5
    assert derivative(f1).tree == ("num", 0.0)

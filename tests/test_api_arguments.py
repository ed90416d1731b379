"""What the public functions take, checked where it comes in (`mbody.model.arguments`, and
`State` itself): a state of another model, a dict where a state goes, values that are not
finite, known reaction values of the wrong kind, numbers given as text or bools, a path
where a model goes. Each refusal names the argument and what it takes, in mbody's words
(an `MbodyError`; an `MbodyTypeError`, also a `TypeError`, for a wrong type), before
any work; and what is right still gives the numbers it did."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.errors import MbodyTypeError

MODELS = Path(__file__).resolve().parent.parent / "models"


# -- State and State.planar themselves ----------------------------------------------------

def test_state_refuses_shapes_and_times_it_cannot_use():
    one = ([[0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0, 0.0]], [[0.0] * 3], [[0.0] * 3])
    with pytest.raises(MbodyTypeError, match=r"^State: t must be a number of seconds, got "
                                             r"str '0'$"):
        mbody.State(*one, "0")  # it used to be kept, and repr() then failed
    with pytest.raises(MbodyTypeError, match="got bool True"):
        mbody.State(*one, True)
    with pytest.raises(mbody.MbodyError, match="^State: t must be a finite number"):
        mbody.State(*one, math.nan)
    s = mbody.State(*one, np.float32(0.5))
    assert type(s.t) is float and s.t == 0.5 and "t = 0.5 s" in repr(s)
    with pytest.raises(mbody.MbodyError, match=r"^State: position must be an \(n, 3\) array, "
                                               r"one row per body, got shape \(3,\) \(one "
                                               r"body: \[\[\.\.\., \.\.\., \.\.\.\]\]\)$"):
        mbody.State(np.zeros(3), *one[1:])
    with pytest.raises(mbody.MbodyError, match=r"^State: position has 2 rows \(bodies\), "
                                               r"quaternion 1: one row per body in each$"):
        mbody.State(np.zeros((2, 3)), one[1], np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(MbodyTypeError, match=r"^State: velocity must be an \(n, 3\) array of "
                                             r"numbers, got list"):
        mbody.State(one[0], one[1], [[0.0, "fast", 0.0]], one[3])
    kept = np.zeros((1, 3))
    assert mbody.State(kept, *one[1:]).position is kept  # a float array is not copied


def test_state_planar_takes_one_body_as_scalars_and_names_a_mismatch():
    row = mbody.State.planar([[0.0, -0.5]], [0.3], [[1.0, 0.0]], [2.0], t=1.5)
    for scalars in (mbody.State.planar([0.0, -0.5], 0.3, [1.0, 0.0], 2.0, t=1.5),
                    mbody.State.planar([0.0, -0.5], [0.3], [1.0, 0.0], [2.0], t=1.5)):
        for name in ("position", "quaternion", "velocity", "omega"):
            np.testing.assert_array_equal(getattr(scalars, name), getattr(row, name))
    assert row.quaternion[0, 3] == pytest.approx(math.sin(0.15), abs=1e-15)
    rest = mbody.State.planar(np.zeros((2, 2)), [0.0, 1.0], 0, 0)  # 0: every body at rest
    assert rest.velocity.shape == (2, 3) and not rest.omega.any()
    with pytest.raises(mbody.MbodyError, match=r"^State.planar: position has 3 rows, angle 2: "
                                               "one per body in each$"):
        mbody.State.planar(np.zeros((3, 2)), np.zeros(2), np.zeros((2, 2)), np.zeros(2))
    with pytest.raises(mbody.MbodyError, match=r"^State.planar: velocity must be a \(2, 2\) "
                                               r"array \(one row per body; angle gives 2\), "
                                               r"got shape \(2,\)$"):
        mbody.State.planar(np.zeros((2, 2)), np.zeros(2), np.zeros(2), np.zeros(2))
    with pytest.raises(MbodyTypeError, match="^State.planar: angle must be an"):
        mbody.State.planar([0.0, 0.0], "30 deg", [0.0, 0.0], 0.0)

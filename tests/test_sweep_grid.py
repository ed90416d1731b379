"""A sweep's grid is known from its counts: a case's values are made from its index alone,
equal to numpy's linspace to 15 digits, and a grid beyond `MAX_CASES` is refused before
any value is made (a count of 10^20 was an internal error, 10^7·15 took 26 s and 4 GB)."""

from __future__ import annotations

import numpy as np
import pytest

from mbody.errors import MbodyError
from mbody.sweep import grid as grid_module
from mbody.sweep.grid import MAX_CASES, Axis, parse_grid


@pytest.mark.parametrize("lo, hi, count", [(0.3, 1.2, 10), (0.4, 0.8, 3), (-7.25, 1e3, 97),
                                           (1.0, 1.0, 5), (2.0, -3.5, 1000), (1e-9, 3e-9, 7)])
def test_each_value_is_linspaces_to_15_digits(lo, hi, count):
    axis = Axis("p", (lo, hi), count)
    want = [float(f"{x:.15g}") for x in np.linspace(lo, hi, count).tolist()]
    got = [axis.value(k) for k in range(axis.size)]
    assert got == want  # bit for bit: the same operations as linspace's
    assert got[-1] == float(f"{hi:.15g}")


def test_a_case_is_made_from_its_index():
    grid = parse_grid(["a=0:1:3", "b=10,20", "c=5 rpm:6 rpm:2"])
    assert len(grid) == 12
    assert grid.numbers(0) == [0.0, 10, 5.0] and grid.numbers(11) == [1.0, 20, 6.0]
    assert grid.numbers(7) == [0.5, 20, 6.0]  # the last axis varies fastest
    assert grid.values(7)["c"] == "6.0 rpm"


@pytest.mark.parametrize("specs, cases", [(["a=1:2:100000000000000000000"], "100 000 000 000 "
                                           "000 000 000"),
                                          (["a=1:2:50000000", "b=0:1:3"], "150 000 000")])
def test_a_grid_too_large_is_refused_from_its_counts(monkeypatch, specs, cases):
    def made(*_: object) -> None:
        raise AssertionError("a value was made before the bound was checked")

    monkeypatch.setattr(grid_module.Axis, "value", made)
    with pytest.raises(MbodyError) as info:
        parse_grid(specs)
    assert MAX_CASES == 100_000_000
    assert str(info.value) == (f"the sweep has {cases} cases; at most 100 000 000 are run "
                               "(fewer values per axis, or samples=N)")  # Python's spelling


def test_a_unit_goes_in_the_column_name_and_the_values_are_numbers():
    """A range in a unit, or values listed each in one unit: numbers in the cells, the
    unit in the column's name, written back with it for the file. Values that are not
    numbers in one unit (two units, an expression, a plain number) stay as given."""
    grid = parse_grid(["drivers.motor.speed=300 rpm:900 rpm:3", "joints.O.angle=5 deg,10 deg",
                       "bodies.rod.mass=0.4,0.8", "drivers.m2.speed=1 rpm,2 Hz",
                       "loads.f.force.0=2*t,3*t"])
    assert grid.columns == ("drivers.motor.speed [rpm]", "joints.O.angle [deg]",
                            "bodies.rod.mass", "drivers.m2.speed", "loads.f.force.0")
    assert grid.numbers(31) == [600.0, 10.0, 0.8, "2 Hz", "3*t"]  # each axis's second value
    assert grid.values(31) == {"drivers.motor.speed": "600.0 rpm", "joints.O.angle": "10.0 deg",
                               "bodies.rod.mass": 0.8, "drivers.m2.speed": "2 Hz",
                               "loads.f.force.0": "3*t"}
    assert grid.shown(31) == ("drivers.motor.speed=600.0 rpm, joints.O.angle=10.0 deg, "
                              "bodies.rod.mass=0.8, drivers.m2.speed=2 Hz, loads.f.force.0=3*t")


def test_an_expression_is_not_a_number_in_a_unit():
    """'2*t' was read as 2 in the unit '*t' by a range (and written back as '2.0 *t')."""
    with pytest.raises(MbodyError, match="'2\\*t' is not a number"):
        parse_grid(["loads.f.force.0=2*t:3*t:2"])

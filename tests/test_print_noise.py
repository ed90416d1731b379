"""Rounding noise is not printed as data (review R4, F11), and `check`'s words for a file
pose that needs no assembly (F13).

The text outputs print a value below the tolerance of the computation that gave it as 0
(`mbody.util.formatting`): a point's coordinate below `LENGTH_RTOL` of its body's size,
an equilibrium's angle below the solver's tolerance. The data (the Python objects,
``--json``) keep the values as computed.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import mbody
from mbody.cli.app import main
from mbody.util.formatting import LENGTH_RTOL, NOISE, num, quiet, vec

DATA = Path(__file__).resolve().parent / "data"

PENDULUM = (DATA / "review_pendulum.yaml").read_text(encoding="utf-8")
"""The reviewer's pendulum: a 1 m rod at 30 deg, its mass centre written to 10 digits,
so that the pin at (0, 0) is 3.9e-12 m off the rod's axis in its body axes."""


@pytest.fixture
def pendulum(tmp_path):
    path = tmp_path / "pend.yaml"
    path.write_text(PENDULUM)
    return path


def test_the_rule():
    assert num(3.89e-12) == "3.89e-12"  # no scale given: only rounding (1e-12) is noise
    assert num(3.89e-12, 1e-9 * 0.5) == "0"
    assert num(-2.4e-17) == "0" and num(-1e-13, 1e-12) == "0"
    assert num(1e-6, 1e-9) == "1e-06"  # a real dimension stays
    assert vec([3.89e-12, 0.5, 7.0], 2, 5e-10) == "(0, 0.5)"
    assert quiet(2e-12) == 2e-12 and quiet(5e-13) == 0.0 and NOISE == 1e-12


def test_assemble_prints_the_pin_on_the_axis(pendulum, capsys):
    assert main(["assemble", str(pendulum)]) == 0
    out = capsys.readouterr().out
    assert "O.Fx     reaction  (0, 0.5)" in out and "e-12" not in out
    # the data keep the value: the mass centre's y, 0.4330127019, is 7.8e-12 beyond
    # sqrt(3)/4; along the rod's axis (30 deg) that is sin 30 of it
    model = mbody.load(pendulum)
    fbd = mbody.assemble(model).bodies["rod"].fbd
    point = next(fo.B_r for fo in fbd.forces if fo.name == "O.Fx")
    assert point[1] == pytest.approx(0.5, abs=1e-10)
    expected = (0.4330127019 - math.sqrt(3) / 4) * math.sin(math.radians(30))
    assert point[0] == pytest.approx(expected, rel=0.01)
    assert abs(point[0]) > 1e-12 and abs(point[0]) < LENGTH_RTOL * fbd.size


def test_a_point_that_is_a_dimension_is_printed(tmp_path, capsys):
    """A pin 1 mm off the axis of a 1 m rod is a dimension, far above the tolerance."""
    path = tmp_path / "off.yaml"
    path.write_text(PENDULUM.replace("at: [0, 0]", "at: [0.001, 0]"))
    assert main(["assemble", str(path)]) == 0
    out = capsys.readouterr().out
    assert "(0.000866025, 0.4995)" in out


def test_equilibrium_prints_the_rest_angle_as_zero(pendulum, capsys):
    assert main(["equilibrium", str(pendulum)]) == 0
    out = capsys.readouterr().out
    assert "  rod   (0, -0.5)  0 deg" in out and "e-10 deg" not in out
    assert main(["equilibrium", str(pendulum), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    q = data["quaternion"][0]
    angle = 2 * math.atan2(q[3], q[0])
    assert angle != 0.0 and abs(angle) < 1e-8  # kept as solved: the solver's tolerance


def test_check_says_the_file_pose_needs_no_assembly(tmp_path, capsys):
    path = tmp_path / "holds.yaml"
    path.write_text("dimension: 2\ngravity: [0, -9.81]\n"
                    "bodies: [{name: rod, mass: 1, inertia: 0.1, position: [0.5, 0]}]\n"
                    "joints: [{name: O, type: revolute, parent: ground, child: rod, "
                    "at: [[0, 0], [-0.5, 0]]}]\n")
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert ("assembled pose: the file's pose already satisfies every joint and driver at "
            "t = 0\n") in out

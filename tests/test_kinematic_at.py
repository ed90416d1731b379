"""A driven mechanism's reactions and efforts at chosen instants (`mbody kinematics --at`,
`--every`, `--csv`; `mbody.kinematic_at`): against closed forms for a driven crank, the
`solve --set angle` route, the one-instant Python route, and the run's own samples."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.errors import MbodyError
from mbody.simulate.instants import first_reach

G0 = 9.81
M, R, RPM, START = 2.0, 0.1, 120.0, 30.0
W = RPM * 2 * math.pi / 60
CRANK = f"""model: crank
dimension: 2
gravity: [0, -{G0}]
bodies:
  - {{name: crank, mass: {M}, inertia: 0.01, position: [0.0866, 0.05], angle: {START} deg}}
joints:
  - {{name: O, type: revolute, parent: ground, child: crank, at: [[0, 0], [-{R}, 0]]}}
drivers:
  - {{name: motor, joint: O, speed: "{RPM} rpm"}}
"""
"""A crank of mass M whose mass centre is R from its pivot, turned at a steady rate."""

DATA = Path(__file__).resolve().parent / "data"

SLIDER_CRANK = (DATA / "review_slider_crank.yaml").read_text(encoding="utf-8")
"""The course review's slider-crank (R4, F7): loads that do not vary in time, so the
`solve --set` route (the file's pose turned to the angle, at t = 0) is the same instant."""

# Newton closes the loops to 1e-12 of the mechanism's size; the forces follow to about
# that relative error, far inside this
RTOL = 1e-9


@pytest.fixture
def crank(tmp_path: Path) -> Path:
    path = tmp_path / "crank.yaml"
    path.write_text(CRANK)
    return path


@pytest.fixture
def slider_crank(tmp_path: Path) -> Path:
    path = tmp_path / "sc.yaml"
    path.write_text(SLIDER_CRANK)
    return path


def crank_closed_form(theta: float) -> tuple[float, float, float]:
    """The pin's force on the crank (world x, y) and the motor's torque at crank angle
    theta: m a_G = F + m g with a_G = -ω² r (cos θ, sin θ); about G, 0 = M + (r_O - r_G) x F,
    so M = m g r cos θ (the torque lifts the weight; the centripetal pull has no arm)."""
    c, s = math.cos(theta), math.sin(theta)
    return -M * W * W * R * c, -M * W * W * R * s + M * G0, M * G0 * R * c


@pytest.mark.parametrize("axes", ["joint", "world"])
def test_crank_at_angles_matches_the_closed_form(crank, axes):
    """A pin without `axis` on ground has the world axes as its frame: both axes agree."""
    angles = [0.0, 45.0, 90.0, 180.0, 270.0, 300.0]
    table = mbody.kinematic_at(mbody.load(crank), [f"{a:g} deg" for a in angles], axes=axes)
    scale = M * W * W * R + M * G0
    for k, a in enumerate(angles):
        Fx, Fy, torque = crank_closed_form(math.radians(a))
        assert table["O.Fx"][k] == pytest.approx(Fx, abs=RTOL * scale)
        assert table["O.Fy"][k] == pytest.approx(Fy, abs=RTOL * scale)
        assert table["motor.M"][k] == pytest.approx(torque, abs=RTOL * scale * R)
        # the instant is where the driver's law is at the angle asked, modulo a turn
        turned = (math.radians(a) - math.radians(START)) % (2 * math.pi)
        assert table.t[k] == pytest.approx(turned / W, abs=1e-14)
        assert math.degrees(table.coordinates[k, 0]) == pytest.approx(a)


def test_slider_crank_at_90_deg_equals_the_solve_set_angle_route(slider_crank, capsys):
    """The course review's check: `solve --set bodies.crank.angle=90 deg --axes world`
    (the pose turned to 90 deg, its velocities from the driver's rate) and `kinematics
    --at '90 deg'` are the same instant, from the command line and from Python."""
    model = mbody.load(slider_crank)
    turned = model.with_values({"bodies.crank.angle": "90 deg"})
    expected = mbody.assemble(turned).solve(axes="world").reactions
    scale = max(abs(v) for v in expected.values())

    table = mbody.kinematic_at(model, "90 deg", axes="world")
    assert set(table.labels) == set(expected)
    for label, value in expected.items():
        assert table[label][0] == pytest.approx(value, abs=RTOL * scale), label

    assert main(["solve", str(slider_crank), "--set", "bodies.crank.angle=90 deg",
                 "--axes", "world", "--json"]) == 0
    solved = json.loads(capsys.readouterr().out)["reactions"]
    assert main(["kinematics", str(slider_crank), "--at", "90 deg", "--axes", "world",
                 "--json"]) == 0
    row = json.loads(capsys.readouterr().out)["at"][0]
    assert row["drivers"] == {"motor": pytest.approx(90.0)} and row["asked"] == "90 deg"
    for label, value in solved.items():
        assert row["values"][label] == pytest.approx(value, abs=RTOL * scale), label


def test_an_instant_between_samples_is_solved_there_not_interpolated(slider_crank):
    """A coarse run (13 samples a revolution: 90 deg falls between two) gives the same
    values at 90 deg as a run of a sample a degree, while interpolating its samples would
    be far off: the instant is solved, not read off the samples."""
    model = mbody.load(slider_crank)
    turn = 60.0 / 300.0
    coarse = mbody.kinematic_run(model, turn, 13 / turn, axes="world")
    angles = np.degrees(coarse.series["driver:motor"])
    assert not np.any(np.isclose(angles % 360.0, 90.0, atol=1.0))
    fine = mbody.kinematic_at(model, "90 deg", axes="world")
    exact = mbody.kinematic_at(model, "90 deg", axes="world", run=coarse)
    scale = float(np.abs(fine.values).max())
    np.testing.assert_allclose(exact.values, fine.values, rtol=0, atol=RTOL * scale)
    assert exact.t[0] == pytest.approx(fine.t[0], abs=1e-15)
    c = coarse.reaction_labels.index("motor.M")
    guess = np.interp(exact.t[0], coarse.t, coarse.reactions[:, c])
    assert abs(guess - exact["motor.M"][0]) > 1e3 * RTOL * scale  # interpolating is not it


def test_at_a_time_equals_the_one_instant_python_route(slider_crank):
    """`--at '0.01 s'`: mbody.kinematics(model, t) then assemble and solve, as driven.md
    shows for one instant."""
    model = mbody.load(slider_crank)
    table = mbody.kinematic_at(model, ["0.01 s", "25 ms"], axes="world")
    assert table.asked == ("t = 0.01 s", "t = 25 ms")
    for k, t in enumerate((0.01, 0.025)):
        sol = mbody.assemble(model, mbody.kinematics(model, t)).solve(axes="world")
        scale = max(abs(v) for v in sol.reactions.values())
        for label, value in sol.reactions.items():
            assert table[label][k] == pytest.approx(value, abs=RTOL * scale)
    np.testing.assert_allclose(np.degrees(table.coordinates[:, 0]),
                               30.0 + 360.0 * 5.0 * np.array([0.01, 0.025]), rtol=1e-14)


def test_angles_are_matched_modulo_a_turn(crank):
    """90 deg, 450 deg, -270 deg and a quarter turn are the same crank position: the first
    time the run reaches it."""
    table = mbody.kinematic_at(mbody.load(crank), ["90 deg", "450 deg", "-270 deg",
                                                   "0.25 rev", math.pi / 2])
    assert np.ptp(table.t) == pytest.approx(0.0, abs=1e-15)
    assert np.ptp(table.values, axis=0) == pytest.approx(0.0, abs=1e-9)


def test_every_30_deg_is_a_table_over_one_revolution_and_its_csv(slider_crank, tmp_path,
                                                                  capsys):
    model = mbody.load(slider_crank)
    out = tmp_path / "table.csv"
    assert main(["kinematics", str(slider_crank), "--every", "30 deg", "--axes", "world",
                 "--csv", str(out)]) == 0
    text = capsys.readouterr().out
    assert "at the instants asked (world axes" in text and f"wrote {out} (12 rows)" in text
    with out.open() as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["motor (deg)", "t (s)", "O.Fx (N)", "O.Fy (N)", "A.Fx (N)",
                       "A.Fy (N)", "B.Fx (N)", "B.Fy (N)", "P.Fx (N)", "P.Fy (N)",
                       "P.Mz (N m)", "motor.M (N m)"]
    data = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(data[:, 0], np.arange(0, 360, 30), atol=1e-9)
    table = mbody.kinematic_at(model, every="30 deg", axes="world")
    np.testing.assert_array_equal(data, table.rows())  # 17 digits read back: the doubles
    one = mbody.kinematic_at(model, [f"{a} deg" for a in range(0, 360, 30)], axes="world")
    np.testing.assert_allclose(data[:, 1], one.t, rtol=1e-14)
    np.testing.assert_allclose(data[:, 2:], one.values, rtol=0,
                               atol=RTOL * float(np.abs(one.values).max()))


def test_csv_without_instants_is_every_sample_of_the_run(slider_crank, tmp_path, capsys):
    out = tmp_path / "run.csv"
    npz = tmp_path / "run.npz"
    assert main(["kinematics", str(slider_crank), "--csv", str(out), "-o", str(npz)]) == 0
    assert f"wrote {out} (361 rows)" in capsys.readouterr().out
    run = mbody.Trajectory.load(npz)
    with out.open() as f:
        rows = list(csv.reader(f))
    assert rows[0][:3] == ["motor (deg)", "t (s)", "O.Fx (N)"] and len(rows) == 362
    data = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(data[:, 1], run.t)
    np.testing.assert_array_equal(data[:, 2:], run.reactions)
    np.testing.assert_allclose(data[:, 0], np.degrees(run.series["driver:motor"]), rtol=1e-15)


def test_csv_never_replaces_an_input(slider_crank, capsys):
    before = slider_crank.read_bytes()
    assert main(["kinematics", str(slider_crank), "--at", "90 deg", "--csv",
                 str(slider_crank)]) == 2
    assert "is the model itself" in capsys.readouterr().err
    link = slider_crank.with_name("link.csv")
    link.symlink_to(slider_crank)  # the same file under a CSV's name
    assert main(["kinematics", str(slider_crank), "--at", "90 deg", "--csv", str(link)]) == 2
    assert "is the model itself" in capsys.readouterr().err
    assert slider_crank.read_bytes() == before


@pytest.mark.parametrize(("args", "words"), [
    (["--at", "90"], "--at 90: give its unit: an angle of driver 'motor'"),
    (["--at", "90 degrees"], "write '90 deg'"),
    (["--at", "20 mm"], "driver 'motor' drives an angle (deg, rad or rev), and '20 mm' is "
                        "a displacement"),
    (["--at", "mtor=90 deg"], "--at mtor=90 deg: no driver named 'mtor'; did you mean "
                              "'motor'?"),
    (["--at", "1 s"], "--at 1 s: t = 1 s is outside the run, t = 0 .. 0.2 s; lengthen "
                      "the run (--t-end)"),
    (["--at", "90 deg", "--t-end", "0.01"], "--at 90 deg: motor = 90 deg is not reached "
                                            "in the run: motor goes from 30 to 48 deg"),
    (["--every", "0 deg"], "--every 0 deg: expected a step above 0"),
    (["--at", "90 deg", "--every", "30 deg"], "give the instants one way"),
])
def test_bad_instants_exit_2_with_what_was_expected(slider_crank, capsys, args, words):
    assert main(["kinematics", str(slider_crank), *args]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_a_displacement_driver_is_asked_in_lengths(tmp_path):
    """A block pushed along a slide by `displacement: 0.1 t + 0.2 t²`: '20 mm' (or 0.05,
    in m) is the first root of 0.2 t² + 0.1 t = x; the push is m x'' = 0.4 m throughout,
    and the slide carries the weight."""
    path = tmp_path / "slide.yaml"
    path.write_text("model: slide\ndimension: 2\ngravity: [0, -9.81]\nbodies:\n"
                    "  - {name: block, mass: 3, inertia: 0.01}\n"
                    "joints:\n  - {name: P, type: prismatic, parent: ground, child: block, "
                    "at: [0, 0], axis: [1, 0]}\n"
                    "drivers:\n  - {name: push, joint: P, displacement: '0.1*t + 0.2*t^2'}\n")
    model = mbody.load(path)
    table = mbody.kinematic_at(model, ["20 mm", 0.05, "0.5 s"], axes="world")
    t = (-0.1 + np.sqrt(0.01 + 4 * 0.2 * np.array([0.02, 0.05]))) / 0.4
    np.testing.assert_allclose(table.t[:2], t, rtol=1e-13)
    assert table.t[2] == 0.5
    np.testing.assert_allclose(table["push.F"], 3 * 0.4, rtol=1e-9)  # m x'' = F
    np.testing.assert_allclose(table["P.Fy"], 3 * 9.81, rtol=1e-9)
    with pytest.raises(MbodyError, match="drives a displacement"):
        mbody.kinematic_at(model, "90 deg")


def test_first_reach_brackets_then_bisects():
    def law(t):
        return 0.5 * np.sin(t)

    t = np.linspace(0.0, 10.0, 11)
    assert first_reach(law, t, 0.25, None) == pytest.approx(math.asin(0.5), abs=1e-15)
    # modulo a turn: -0.25 + 2 pi k is first reached on the way down, after pi
    assert first_reach(law, t, -0.25 + 2 * math.pi, 2 * math.pi) == pytest.approx(
        math.pi + math.asin(0.5), abs=1e-15)
    assert first_reach(law, t, 0.75, None) is None


# == review R5-4, R5-5, R5-11: tiny steps, huge angles, one labelling ======================

@pytest.mark.parametrize("step", ["1e-310 s", "1e-310 deg", "5e-324 rad", "1e-300 s"])
def test_a_tiny_step_is_refused_with_a_short_count(slider_crank, capsys, step):
    """A step whose quotient overflows (or is astronomically large) is exit 2, its count
    written as a number is (1e299, not 300 digits), from the command and from Python."""
    assert main(["kinematics", str(slider_crank), "--every", step]) == 2
    err = capsys.readouterr().err
    assert f"--every {step}: " in err and "a table has at most 100 000; take a larger step" \
        in err and "Traceback" not in err and len(err) < 200
    with pytest.raises(MbodyError, match="a table has at most 100 000") as refused:
        mbody.kinematic_at(mbody.load(slider_crank), every=step)
    assert len(str(refused.value)) < 200


def test_a_time_beyond_any_run_made_here_is_refused_in_a_few_words(slider_crank):
    with pytest.raises(MbodyError) as refused:
        mbody.kinematic_at(mbody.load(slider_crank), times=[1e300])
    text = str(refused.value)
    assert text.startswith("times=1e300: t = 1e+300 s is later than the run made here "
                           "reaches (at most 10 000 000 samples") and len(text) < 300
    assert "run=mbody.kinematic_run(model, t_end, fps)" in text


@pytest.mark.parametrize("huge", ["1e20 deg", "1e16 deg", "-1e20 deg", "1e17 rev"])
def test_a_huge_angle_is_that_angle_less_whole_turns_in_its_unit(crank, huge):
    """1e20 deg is 280 deg plus whole turns (the double 1e20 is a whole number, reduced
    here exactly in Python's integers); the row is that of the angle, labelled with it, as
    if it had been asked so, and the closed form's."""
    value, unit = huge.split()
    turn = 360 if unit == "deg" else 1
    exact = int(float(value)) % turn  # the float's exact value, reduced in integers
    angle = exact if unit == "deg" else exact * 360.0
    model = mbody.load(crank)
    table = mbody.kinematic_at(model, [huge, f"{angle} deg"])
    assert table.t[0] == table.t[1]
    np.testing.assert_array_equal(table.values[0], table.values[1])
    assert math.degrees(table.coordinates[0, 0]) == pytest.approx(angle, abs=1e-12)
    Fx, Fy, torque = crank_closed_form(math.radians(angle))
    assert table["motor.M"][0] == pytest.approx(torque, abs=RTOL * (M * W * W * R + M * G0) * R)


def test_an_angle_in_rad_beyond_a_model_files_bound_is_refused(crank, capsys):
    with pytest.raises(MbodyError, match=r"at='1e20 rad': expected an angle of at most 1e9 "
                                         r"rad .* write it in deg or rev"):
        mbody.kinematic_at(mbody.load(crank), "1e20 rad")
    with pytest.raises(MbodyError, match="at most 1e9 rad"):
        mbody.kinematic_at(mbody.load(crank), 1e10)  # a number is in rad
    assert main(["kinematics", str(crank), "--at", "2e9 rad"]) == 2
    assert "--at 2e9 rad: expected an angle of at most 1e9 rad" in capsys.readouterr().err


def test_one_instant_has_one_label_however_it_is_asked(slider_crank, capsys):
    """The slider-crank starts at 30 deg and turns at 300 rpm: at t = 330/1800 s it is at
    360 deg. Asked as that time, as 0, 360 or 720 deg, or as a row of --every, the row is
    labelled 0 deg (a run over a whole turn: less whole turns, 0 .. 360)."""
    model = mbody.load(slider_crank)
    t = 330 / 1800
    table = mbody.kinematic_at(model, ["0 deg", "360 deg", "720 deg", "-360 deg", "1 rev"],
                               times=[t])
    every = mbody.kinematic_at(model, every="90 deg")
    assert every.asked[0] == "0 deg" and every.t[0] == pytest.approx(t, abs=1e-12)
    labels = [*np.degrees(table.coordinates[:, 0]), math.degrees(every.coordinates[0, 0])]
    assert labels[:5] == [0.0] * 5 and labels[-1] == 0.0  # the value asked, exactly
    assert labels[5] == pytest.approx(0.0, abs=1e-9)  # the law's, to its rounding
    # 450 deg and 0.2 s (30 + 360 deg) are 90 and 30 deg, as --every labels them
    again = mbody.kinematic_at(model, ["450 deg"], times=[0.2])
    np.testing.assert_allclose(np.degrees(again.coordinates[:, 0]), [90.0, 30.0], atol=1e-9)
    assert main(["kinematics", str(slider_crank), "--at", "0.2 s", "--at", "390 deg",
                 "--at", "30 deg"]) == 0
    rows = capsys.readouterr().out.splitlines()[-3:]
    assert [r.split()[0] for r in rows] == ["30", "30", "30"]


def test_a_run_short_of_a_turn_labels_the_laws_angle(slider_crank):
    """Over 0 .. 0.01 s the crank turns from 30 to 48 deg, less than a turn: a row is
    labelled with the law's angle there (40 deg), asked as 40, 400 or -320 deg or as the
    time it is at 40 deg."""
    model = mbody.load(slider_crank)
    run = mbody.kinematic_run(model, 0.01, 3600)
    table = mbody.kinematic_at(model, ["40 deg", "400 deg", "-320 deg"], times=[10 / 1800],
                               run=run)
    np.testing.assert_allclose(np.degrees(table.coordinates[:, 0]), 40.0, rtol=1e-14)


def test_a_run_of_too_many_samples_says_how_many_in_a_few_words(slider_crank):
    with pytest.raises(MbodyError) as refused:
        mbody.kinematic_run(mbody.load(slider_crank), 1e300, 3600)
    assert str(refused.value).startswith("3.6e303 samples (1e300 s at 3600 fps) is more than "
                                         "10 000 000; lower fps or t_end")


@pytest.mark.parametrize("step", ["360 deg", "1 rev", "400 deg"])
def test_a_step_of_a_turn_or_more_gives_the_row_at_zero(slider_crank, step):
    """A step of a whole turn or more on a run that turns fully: the one row at 0 (the
    count was a turn over the step, below 1 for a whole turn, and refused: review
    R6-4), equal to that angle asked directly."""
    model = mbody.load(slider_crank)
    table = mbody.kinematic_at(model, every=step)
    assert len(table.t) == 1
    np.testing.assert_allclose(table.values, mbody.kinematic_at(model, "0 deg").values,
                               rtol=0, atol=RTOL * float(np.abs(table.values).max()))

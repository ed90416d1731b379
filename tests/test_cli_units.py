"""Values written with a unit on the command line (review R7, findings 1, 3 and 12): a
time option reads a time with its unit as `kinematics --at` does; the hint for a value
the shell split at its space says to quote it only when the quoted value is accepted,
else what to write instead; a --known value with a unit and a driver's rate with an SI
prefix are told to convert, never pointed to a value 1000 times off."""

from __future__ import annotations

import json
import math

import pytest
from test_cli_near_miss import DRIVEN, PENDULUM, usage_and_message
from test_cli_options import run

import mbody


def _summary_first_line(capsys, *args) -> str:
    code, out, err = run(capsys, *args)
    assert code == 0, err
    return out.splitlines()[0]


# == a time with its unit where seconds are expected ===========================================

@pytest.mark.parametrize(("written", "seconds"), [("500 ms", "0.5"), ("0.5 s", "0.5"),
                                                  ("0.01 min", "0.6")])
def test_simulate_reads_its_end_with_a_unit_of_time(capsys, written, seconds):
    with_unit = _summary_first_line(capsys, "simulate", PENDULUM, "--t-end", written)
    assert with_unit == _summary_first_line(capsys, "simulate", PENDULUM, "--t-end", seconds)
    assert f"t = 0 .. {seconds} s" in with_unit


def test_kinematics_reads_its_times_with_a_unit_as_its_at_does(capsys):
    def summary(*args) -> dict:
        code, out, err = run(capsys, "kinematics", DRIVEN, "--json", *args)
        assert code == 0, err
        return json.loads(out)

    assert (summary("--t-end", "100 ms", "--t-start", "10 ms")
            == summary("--t-end", "0.1", "--t-start", "0.01"))
    assert summary("--t-end", "0.1 s")["t_end"] == pytest.approx(0.1, rel=1e-15)


def test_a_time_of_another_kind_says_what_is_read(capsys):
    code, _, err = run(capsys, "simulate", PENDULUM, "--t-end", "1 kg")
    assert code == 2
    assert usage_and_message(err)[1] == (
        "argument --t-end: expected a time in seconds from 1e-9 to 1e9 (or with its unit, "
        "such as '100 ms'), or turns such as '1 rev', got '1 kg'")
    code, _, err = run(capsys, "simulate", PENDULUM, "--t-end", "2e9 s")
    assert code == 2 and "from 1e-9 to 1e9" in err and "got '2e9 s'" in err


# == simulate --t-end in turns =================================================================

def test_simulate_of_a_driven_model_ends_after_turns_of_its_driver(capsys):
    # the motor turns at 600 rpm: a turn is 0.1 s
    turns = _summary_first_line(capsys, "simulate", DRIVEN, "--t-end", "2 rev", "--fps", "600")
    assert turns == _summary_first_line(capsys, "simulate", DRIVEN, "--t-end", "0.2",
                                        "--fps", "600")
    assert "t = 0 .. 0.2 s" in turns


def test_simulate_in_turns_of_a_model_without_drivers_says_to_give_seconds(capsys):
    code, out, err = run(capsys, "simulate", PENDULUM, "--t-end", "1 rev")
    assert (code, out) == (2, "")
    assert err == ("mbody: error: --t-end 1 rev: this model has no driver, so a turn has no "
                   "fixed time; give the end in seconds\n")


# == a value split at its space: quote it only where the quoted value is read ===================

@pytest.mark.parametrize("args", [
    ("simulate", PENDULUM, "--t-end", "1", "s"),
    ("simulate", DRIVEN, "--t-end", "1", "rev"),
    ("kinematics", DRIVEN, "--t-end", "0.1", "s"),
    ("kinematics", DRIVEN, "--t-end", "100", "ms"),
    ("check", PENDULUM, "--set", "bodies.rod.angle=30", "deg"),
    # a body's rate reads a driver's units (review R7-13): quoting it works
    ("check", PENDULUM, "--set", "bodies.rod.angular_velocity=100", "rpm"),
])
def test_the_quotes_suggested_are_accepted(capsys, args):
    code, _, err = run(capsys, *args)
    message = usage_and_message(err)[1]
    quoted = f"{args[2]} '{args[3]} {args[4]}'"
    assert code == 2
    assert message.endswith(f"a value with a space is one argument: quote it, {quoted}")
    code, _, err = run(capsys, *args[:3], f"{args[3]} {args[4]}")
    assert code == 0, err


@pytest.mark.parametrize(("args", "hint", "meant"), [
    (("check", PENDULUM, "--set", "bodies.rod.mass=2", "kg"),
     "bodies.rod.mass takes no unit (numbers are in SI units, written without the unit: 2): "
     "write --set bodies.rod.mass=2", ("--set", "bodies.rod.mass=2")),
    (("check", PENDULUM, "--set", "bodies.rod.mass=500", "g"),
     "bodies.rod.mass takes no unit (numbers are in SI units, written without the unit: "
     "500 g is 0.5 kg): write --set bodies.rod.mass=0.5", ("--set", "bodies.rod.mass=0.5")),
    (("solve", PENDULUM, "--known", "O.Fx=3", "N"),
     "O.Fx takes no unit (numbers are in SI units, written without the unit: 3; values are "
     "in N): write --known O.Fx=3", ("--known", "O.Fx=3")),
    (("solve", PENDULUM, "--known", "O.Fx=3", "kN"),
     "O.Fx takes no unit (numbers are in SI units, written without the unit: 3 kN is 3000 N; "
     "values are in N): write --known O.Fx=3000", ("--known", "O.Fx=3000")),
])
def test_a_unit_that_is_refused_quoted_gets_the_number_to_write(capsys, args, hint, meant):
    code, _, err = run(capsys, *args)
    assert code == 2
    assert usage_and_message(err)[1] == f"unrecognized arguments: {args[-1]}; {hint}"
    code, _, err = run(capsys, *args[:2], *meant)  # what the hint says to write runs
    assert code == 0, err


def test_a_typed_option_refusing_the_quoted_value_says_why(capsys):
    code, _, err = run(capsys, "simulate", PENDULUM, "--fps", "60", "Hz")
    assert code == 2
    assert usage_and_message(err)[1] == (
        "unrecognized arguments: Hz; quoted, --fps '60 Hz' is refused too: expected a number "
        "of samples per second above 0 up to 1e6, got '60 Hz'")


def test_a_path_whose_key_reads_other_units_says_which(capsys):
    code, _, err = run(capsys, "check", PENDULUM, "--set", "bodies.rod.angle=30", "grad")
    assert code == 2
    assert usage_and_message(err)[1] == (
        "unrecognized arguments: grad; bodies.rod.angle takes a number in SI units or with a "
        "unit (deg, rad; got 'grad')")


# == --known with a unit (R7-3) ================================================================

@pytest.mark.parametrize(("value", "hint"), [
    ("3N", "numbers are in SI units, written without the unit: 3"),
    ("2 kN", "numbers are in SI units, written without the unit: 2 kN is 2000 N"),
    ("2 N*m", "this number is a force in N, written without the unit; N m measures a moment"),
])
def test_a_known_value_with_a_unit_is_told_to_drop_it(capsys, value, hint):
    code, out, err = run(capsys, "solve", PENDULUM, "--known", f"O.Fx={value}")
    assert (code, out) == (2, "")
    assert err == (f"mbody: error: --known O.Fx: expected a number in N or an expression of "
                   f"t, got {value!r} ({hint})\n")
    asm = mbody.assemble(mbody.load(PENDULUM))
    with pytest.raises(mbody.MbodyError) as exc:
        asm.solve(known={"O.Fx": value})
    assert str(exc.value) == (f"known['O.Fx']: expected a number in N or an expression of "
                              f"t, got {value!r} ({hint})")


def test_a_misspelt_expression_keeps_its_own_message(capsys):
    code, _, err = run(capsys, "solve", PENDULUM, "--known", "O.Fx=3x")
    assert code == 2 and "write '*' for multiplication" in err


# == a rate with an SI prefix (R7-12) ==========================================================

@pytest.mark.parametrize(("typed", "converted"), [("0.6 krpm", "0.6 krpm is 600 rpm"),
                                                  ("10 kHz", "10 kHz is 10000 Hz")])
def test_a_prefixed_rate_is_converted_not_respelt(capsys, typed, converted):
    code, _, err = run(capsys, "check", DRIVEN, "--set", f"drivers.motor.speed={typed}")
    assert code == 2
    assert "did you mean" not in err
    assert f"units take no prefix: {converted}; units: rad/s, deg/s, rpm" in err


# == fbd -o is a folder (R7-10) ================================================================

@pytest.mark.parametrize("suffix", [".svg", ".PNG", ".pdf"])
def test_fbd_refuses_a_picture_name_for_its_folder(capsys, tmp_path, suffix):
    target = tmp_path / f"fbd{suffix}"
    code, out, err = run(capsys, "fbd", PENDULUM, "-o", target)
    assert (code, out) == (2, "")
    assert err == (f"mbody: error: -o {target}: fbd -o is a folder; the pictures are named "
                   f"fbd_<body>.<format> inside it; did you mean -o {tmp_path} "
                   f"--image-format {suffix[1:].lower()}?\n")
    assert list(tmp_path.iterdir()) == []  # no folder made under that name


def test_fbd_writes_into_an_existing_folder_named_like_a_picture(capsys, tmp_path):
    (tmp_path / "old.svg").mkdir()
    code, _, err = run(capsys, "fbd", PENDULUM, "-o", tmp_path / "old.svg")
    assert code == 0, err
    assert (tmp_path / "old.svg" / "fbd_rod.svg").is_file()


# == wording: plurals by count, check's driver law (R7-14) =====================================

def test_graph_counts_one_body_and_one_joint_in_the_singular(capsys, tmp_path):
    target = tmp_path / "g.svg"
    code, out, err = run(capsys, "graph", PENDULUM, "-o", target)
    assert code == 0, err
    assert out == f"wrote {target}  (1 body, 1 joint, mobility 1)\n"


def test_one_answers_file_is_counted_in_the_singular(capsys, tmp_path):
    answers = tmp_path / "ana.yaml"
    answers.write_text('equations:\n  - {body: rod, eq: "m*a_x = O.Fx"}\n')
    code, out, err = run(capsys, "verify", PENDULUM, answers, "--summary",
                         tmp_path / "c.csv")
    assert code in (0, 1), err
    assert out.startswith("1 answers file for model 'physical-pendulum': ")
    assert "file(s)" not in out


@pytest.mark.parametrize(("speed", "law"), [("600 rpm", "0.523599 + 62.8319*t"),
                                            ("-600 rpm", "0.523599 - 62.8319*t")])
def test_check_prints_a_speed_law_to_six_digits_with_its_sign(capsys, speed, law):
    code, out, err = run(capsys, "check", DRIVEN, "--set", f"drivers.motor.speed={speed}")
    assert code == 0, err
    assert f"  motor          O: {law} (rad, t in s); effort motor.M\n" in out
    # the law itself keeps every digit: 600 rpm is 20 pi rad/s from 30 deg
    model = mbody.load(DRIVEN).with_values({"drivers.motor.speed": speed})
    f = model.drivers.laws[0][0]
    sign = 1 if speed[0] != "-" else -1
    assert float(f(1.0)) == pytest.approx(math.pi / 6 + sign * 20 * math.pi, rel=1e-15)


# == kinematics --csv labels its rows with the law's value (R7-8) ===============================

def test_the_csv_of_a_run_labels_its_samples_without_rounding_noise(capsys, tmp_path):
    target = tmp_path / "k.csv"
    code, _, err = run(capsys, "kinematics", DRIVEN, "--csv", target)
    assert code == 0, err
    lines = target.read_text().splitlines()
    assert lines[0].startswith("motor (deg),t (s),")
    # 600 rpm from 30 deg, a sample a degree (3600 a second) over one turn: 30 .. 390 deg
    labels = [float(line.split(",")[0]) for line in lines[1:]]
    assert labels == [30.0 + k for k in range(361)]
    times = [float(line.split(",")[1]) for line in lines[1:]]
    assert times[0] == 0.0 and times[-1] == pytest.approx(0.1, rel=1e-15)

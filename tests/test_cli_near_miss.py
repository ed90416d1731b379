"""A near miss on the command line (issue 22's new-user review) is answered the way a
misspelt command or choice is: the command's own usage line, what is wrong, what was
probably meant, exit 2, never a traceback.

- A misspelt option of a command (``simulate --t_end``, ``solve --know``, ``verify
  --sumary``) names the command's option it was closest to; an option of another command
  says which commands have it; one with nothing close says where the options are listed.
- An extra positional argument says how many the command takes.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_cli_options import run  # main() run as a user runs it, argparse exits caught

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"
DRIVEN = MODELS / "slider_crank_driven.yaml"


def usage_and_message(err: str) -> tuple[str, str]:
    """(the usage's first line, the one-line message after 'mbody: error: ')."""
    lines = err.rstrip("\n").split("\n")
    assert lines[-1].startswith("mbody: error: "), err
    return lines[0], lines[-1].removeprefix("mbody: error: ")


# == misspelt options =============================================================

@pytest.mark.parametrize(("args", "given", "meant"), [
    (("simulate", PENDULUM, "--t_end", "3"), "--t_end 3", "--t-end"),  # _ for -
    (("simulate", PENDULUM, "--tend", "3"), "--tend 3", "--t-end"),
    (("simulate", PENDULUM, "--fsp", "30"), "--fsp 30", "--fps"),  # swapped letters
    (("simulate", PENDULUM, "--T-END=3"), "--T-END=3", "--t-end"),  # case; with =
    (("solve", PENDULUM, "--know", "O.Fx=3"), "--know O.Fx=3", "--known"),  # no abbreviation
    (("convert", PENDULUM, "-o", "x.xml", "--too", "mjcf"), "--too mjcf", "--to"),
    (("kinematics", DRIVEN, "--t_end", "1"), "--t_end 1", "--t-end"),
])
def test_a_misspelt_option_gets_its_commands_usage_and_a_did_you_mean(capsys, args, given,
                                                                      meant):
    code, out, err = run(capsys, *args)
    usage, message = usage_and_message(err)
    assert code == 2 and out == ""
    assert usage.startswith(f"usage: mbody {args[0]} [-h]")  # not `mbody [-h] COMMAND`
    assert message == f"unrecognized arguments: {given}; did you mean '{meant}'?"


def test_a_misspelt_option_whose_value_was_taken_as_a_positional(capsys):
    """`verify M --sumary x.csv`: x.csv is read as a second answers file, --sumary is
    the only leftover; it still gets its did-you-mean."""
    code, _, err = run(capsys, "verify", PENDULUM, "--sumary", "x.csv")
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody verify ")
    assert message == "unrecognized arguments: --sumary; did you mean '--summary'?"


def test_several_misspelt_options_each_get_their_hint(capsys):
    code, _, err = run(capsys, "simulate", PENDULUM, "--t_end", "3", "--fsp", "30")
    assert code == 2
    assert usage_and_message(err)[1] == (
        "unrecognized arguments: --t_end 3 --fsp 30; --t_end: did you mean '--t-end'?; "
        "--fsp: did you mean '--fps'?")


def test_an_option_with_nothing_close_gets_no_did_you_mean(capsys):
    code, _, err = run(capsys, "simulate", PENDULUM, "--zqxw", "3")
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody simulate ")
    assert "did you mean" not in message
    assert message == ("unrecognized arguments: --zqxw 3; mbody simulate --help lists the "
                       "options")


def test_an_option_of_another_command_says_which_commands_have_it(capsys):
    code, _, err = run(capsys, "check", PENDULUM, "--t-end", "3")
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody check ")
    assert message.startswith("unrecognized arguments: --t-end 3; --t-end is an option of ")
    owners = message.split("is an option of ")[1].removesuffix(", not of check").split(", ")
    assert {"simulate", "kinematics", "sweep"} <= set(owners) and "check" not in owners


def test_a_misspelt_option_is_named_even_when_a_required_one_is_missing(capsys):
    """argparse stops at the missing -o before it reports --ouput, which is its cause."""
    code, _, err = run(capsys, "convert", PENDULUM, "--ouput", "x.xml")
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody convert ")
    assert message == ("the following arguments are required: -o/--output; also "
                       "unrecognized arguments: --ouput; did you mean '--output'?")


def test_a_misspelt_top_level_option(capsys):
    code, _, err = run(capsys, "--verison")
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody [-h]")
    assert message == "unrecognized arguments: --verison; did you mean '--version'?"


def test_an_option_before_the_command_is_told_to_go_after_it(capsys):
    """`mbody --t-end 3 simulate M`: argparse takes '3' for the command."""
    code, _, err = run(capsys, "--t-end", "3", "simulate", PENDULUM)
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody [-h]")
    # argparse's own words (the invalid choice '3', the choices) are its to change: what
    # mbody adds is what is checked
    assert "'3'" in message and message.endswith(
        "; --t-end is an option of simulate, kinematics, animate, sweep; it goes after the "
        "command")
    code, _, err = run(capsys, "--t-end=3", "simulate", PENDULUM)
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody simulate ")
    assert message == ("unrecognized arguments: --t-end=3; --t-end goes after the command: "
                       "mbody simulate ... --t-end=3")


def test_an_option_without_a_command(capsys):
    code, _, err = run(capsys, "--t-end")
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody [-h]")
    assert message == ("unrecognized arguments: --t-end; --t-end is an option of simulate, "
                       "kinematics, animate, sweep; it goes after the command")


def test_a_misspelt_commands_own_options_are_not_called_misplaced(capsys):
    code, _, err = run(capsys, "chek", "--set", "bodies.rod.mass=2", PENDULUM)
    assert code == 2
    message = usage_and_message(err)[1]
    assert "'chek'" in message and message.endswith("; did you mean 'check'?")
    assert "is an option of" not in message and "goes after the command" not in message


def test_negative_numbers_and_words_after_a_double_dash_are_not_options(capsys):
    code, _, err = run(capsys, "check", PENDULUM, "-3", "--", "-x")
    assert code == 2
    assert usage_and_message(err)[1] == ("unrecognized arguments: -3 -- -x; check takes "
                                         "MODEL (and options), so 2 arguments too many")


# == positional leftovers =========================================================

def test_an_extra_model_path_says_it_is_one_too_many(capsys):
    code, _, err = run(capsys, "check", PENDULUM, PENDULUM)
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody check ")
    assert message == (f"unrecognized arguments: {PENDULUM}; check takes MODEL (and "
                       "options), so one argument too many")


@pytest.mark.parametrize(("args", "left", "quoted"), [
    (("kinematics", DRIVEN, "--t-end", "1", "rev"), "rev", "--t-end '1 rev'"),
    (("kinematics", DRIVEN, "--set", "drivers.motor.speed=600", "rpm"), "rpm",
     "--set 'drivers.motor.speed=600 rpm'"),
    (("sweep", DRIVEN, "--set", "drivers.motor.speed=300", "rpm:1200", "rpm:4", "-o", "x.csv"),
     "rpm:1200 rpm:4", "--set 'drivers.motor.speed=300 rpm:1200 rpm:4'"),
])
def test_a_value_split_at_its_space_is_told_to_be_quoted(capsys, args, left, quoted):
    code, _, err = run(capsys, *args)
    assert code == 2
    assert usage_and_message(err)[1] == (f"unrecognized arguments: {left}; a value with a "
                                         f"space is one argument: quote it, {quoted}")


def test_an_extra_model_after_an_options_value_is_not_taken_for_a_unit(capsys):
    code, _, err = run(capsys, "check", PENDULUM, "--set", "bodies.rod.mass=2", PENDULUM)
    assert code == 2
    assert usage_and_message(err)[1].endswith("check takes MODEL (and options), so one "
                                              "argument too many")


def test_the_installed_command_end_to_end():
    """As a user runs it: a subprocess, exit 2, no traceback, the command's usage."""
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    p = subprocess.run([sys.executable, "-m", "mbody", "simulate", str(PENDULUM), "--t_end",
                        "3"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stdout == "" and "Traceback" not in p.stderr
    assert p.stderr.startswith("usage: mbody simulate ")
    assert p.stderr.endswith("mbody: error: unrecognized arguments: --t_end 3; did you mean "
                             "'--t-end'?\n")


# == units of a driver's speed (in the file, or set by --set) ======================

@pytest.mark.parametrize(("typed", "meant"), [
    ("600 RPM", "600 rpm"),     # the case only: the closest
    ("10 HZ", "10 Hz"),
    ("600 rps", "600 rev/s"),   # by spelling 'rpm', 60 times slower: an abbreviation
    ("600 RPS", "600 rev/s"),
    ("10 rad/sec", "10 rad/s"),
])
def test_a_misspelt_rate_unit_gets_a_did_you_mean(typed, meant):
    import mbody

    model = mbody.load(DRIVEN)
    with pytest.raises(mbody.ModelError) as err:
        model.with_values({"drivers.motor.speed": typed})
    issue = err.value.issues[0]
    assert issue.key == "drivers.motor.speed" and f"got '{typed}'" in issue.message
    assert issue.hint.startswith(f"did you mean '{meant}'? units: rad/s, deg/s, rpm, "
                                 "rev/min, rev/s, Hz; set by drivers.motor.speed=")
    assert model.with_values({"drivers.motor.speed": meant}).drivers is not None


def test_a_unit_with_nothing_close_lists_the_units_only():
    import mbody

    with pytest.raises(mbody.ModelError) as err:
        mbody.load(DRIVEN).with_values({"drivers.motor.speed": "600 furlongs"})
    assert err.value.issues[0].hint.startswith("units: rad/s, deg/s, rpm, rev/min, rev/s, "
                                               "Hz; set by")


def test_a_misspelt_rate_unit_on_the_command_line(capsys):
    code, out, err = run(capsys, "kinematics", DRIVEN, "--set", "drivers.motor.speed=600 RPM")
    assert (code, out) == (2, "")
    assert err.startswith("mbody: error: ") and err.count("\n") == 1
    assert "got '600 RPM' (did you mean '600 rpm'? units: " in err
    assert "set by drivers.motor.speed=600 RPM;" in err


def test_a_rate_out_of_range_names_the_value_as_typed_and_the_range(capsys):
    """1e300 rpm is 1.05e299 rad/s: it was refused quoting the law mbody built from it
    ('0.5235987755982988 + 1.0471975511965978e+299*t')."""
    code, out, err = run(capsys, "kinematics", DRIVEN, "--set",
                         "drivers.motor.speed=1e300 rpm")
    assert (code, out) == (2, "")
    rpm_max = 1e100 * 60 / (2 * math.pi)  # 9.55e100 rpm is 1e100 rad/s
    assert err == ("mbody: error: models/slider_crank_driven.yaml:42:36: drivers.motor.speed:"
                   " the rate '1e300 rpm' is out of range: expected a magnitude of at most "
                   f"1e+100 rad/s ({rpm_max:.3g} rpm) (set by drivers.motor.speed=1e300 rpm; "
                   "the file's own value is on line 42)\n").replace(
                       "models/", f"{MODELS}/")


@pytest.mark.parametrize(("typed", "ok"), [
    ("9.5e100 rpm", True), ("9.6e100 rpm", False),  # the bound is on rad/s: 9.55e100 rpm
    ("1e100 rad/s", True), ("-1.1e100 rad/s", False), ("1e400 rpm", False),
    ("5.7e101 deg/s", True), ("5.8e101 deg/s", False),
])
def test_the_rate_bound_is_the_models_number_bound_in_rad_per_s(typed, ok):
    import mbody

    model = mbody.load(DRIVEN)
    if ok:
        rate = model.with_values({"drivers.motor.speed": typed}).drivers.speed[0]
        assert 1e99 < abs(rate) <= 1e100
    else:
        with pytest.raises(mbody.ModelError, match="out of range: expected a magnitude of at "
                           r"most 1e\+100 rad/s"):
            model.with_values({"drivers.motor.speed": typed})


# == kinematics --t-end in turns, as sweep's ======================================

def kinematic_json(capsys, *args) -> dict:
    code, out, err = run(capsys, "kinematics", DRIVEN, "--json", *args)
    assert code == 0, err
    return json.loads(out)


@pytest.mark.parametrize(("t_end", "t_start", "end", "samples"), [
    ("1 rev", "0", 0.1, 361),          # 600 rpm: a turn is 60/600 = 0.1 s
    ("2 revs", "0", 0.2, 721),
    ("2.5 revolutions", "1", 1.25, 901),  # turns after --t-start
    ("0.05", "0", 0.05, 181),          # seconds, as before
])
def test_kinematics_t_end_in_turns_of_the_driver(capsys, t_end, t_start, end, samples):
    run_ = kinematic_json(capsys, "--t-end", t_end, "--t-start", t_start)
    assert run_["t_end"] == pytest.approx(end, rel=1e-12)
    assert run_["samples"] == samples  # 3600 per second: one a degree


def test_one_turn_is_the_default_run(capsys):
    assert kinematic_json(capsys, "--t-end", "1 rev") == kinematic_json(capsys)


def test_turns_need_a_driver_at_a_constant_rate(capsys, tmp_path):
    varying = tmp_path / "varying.yaml"
    varying.write_text(DRIVEN.read_text().replace('speed: "600 rpm"',
                                                  'angle: "30 deg + 60*t + sin(t)"'))
    for model, extra in ((varying, []), (DRIVEN, ["--set", "drivers.motor.speed=0"])):
        code, out, err = run(capsys, "kinematics", model, "--t-end", "1 rev", *extra)
        assert (code, out) == (2, "")
        assert err == ("mbody: error: --t-end 1 rev: this model's first driver does not "
                       "turn at a constant rate, so a turn has no fixed time; give the end "
                       "in seconds\n")


@pytest.mark.parametrize(("typed", "expected"), [
    ("1 turn", "expected a time in seconds from -1e9 to 1e9 (or with its unit, such as "
               "'100 ms'), or turns such as '1 rev', got '1 turn'"),
    ("0 rev", "expected a number of turns above 0 up to 1e6, got '0 rev'"),
])
def test_a_bad_end_time_says_which_forms_are_accepted(capsys, typed, expected):
    code, _, err = run(capsys, "kinematics", DRIVEN, "--t-end", typed)
    usage, message = usage_and_message(err)
    assert code == 2 and usage.startswith("usage: mbody kinematics ")
    assert message == f"argument --t-end: {expected}"


def test_sweep_reads_its_end_time_with_the_same_parser():
    from mbody.cli import build_parser

    parse = build_parser().parse_args
    base = ["sweep", str(DRIVEN), "--set", "bodies.rod.mass=1:2:2", "-o", "x.csv"]
    assert parse([*base, "--t-end", "1 rev"]).t_end == ("rev", 1.0)
    assert parse([*base, "--t-end", "0.5"]).t_end == ("s", 0.5)
    assert parse(["kinematics", str(DRIVEN), "--t-end", "1 rev"]).t_end == ("rev", 1.0)


@pytest.mark.parametrize(("args", "said", "t_end"), [
    ([], "the default end (a turn)", 2 * math.pi / 1e-90),
    (["--t-end", "2 rev"], "--t-end 2 rev", 2 * 2 * math.pi / 1e-90),
])
def test_an_end_in_turns_keeps_the_bound_of_seconds(capsys, args, said, t_end):
    """A driver barely turning (1e-90 rad/s) turns once in 6.3e90 s; the run was started
    and its position analysis diverged at t = 1.7e88 s."""
    code, out, err = run(capsys, "kinematics", DRIVEN, "--set", "drivers.motor.speed=1e-90",
                         *args)
    assert (code, out) == (2, "")
    assert err.startswith(f"mbody: error: {said} is t = {t_end:.3g} s (")
    assert err.endswith("at most 1e+09 s: give --t-end in seconds\n")

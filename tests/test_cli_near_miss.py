"""A near miss on the command line (issue 22's new-user review) is answered the way a
misspelt command or choice is: the command's own usage line, what is wrong, what was
probably meant, exit 2, never a traceback.

- A misspelt option of a command (``simulate --t_end``, ``solve --know``, ``verify
  --sumary``) names the command's option it was closest to; an option of another command
  says which commands have it; one with nothing close says where the options are listed.
- An extra positional argument says how many the command takes.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mbody.cli import main

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"
DRIVEN = MODELS / "slider_crank_driven.yaml"


def run(capsys, *args) -> tuple[int, str, str]:
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


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


def test_the_installed_command_end_to_end():
    """As a user runs it: a subprocess, exit 2, no traceback, the command's usage."""
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    p = subprocess.run([sys.executable, "-m", "mbody", "simulate", str(PENDULUM), "--t_end",
                        "3"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stdout == "" and "Traceback" not in p.stderr
    assert p.stderr.startswith("usage: mbody simulate ")
    assert p.stderr.endswith("mbody: error: unrecognized arguments: --t_end 3; did you mean "
                             "'--t-end'?\n")


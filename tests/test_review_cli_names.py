"""Three papercuts of the command line's last review:

- ``--known LABEL=VALUE`` takes an expression of t, as the Python functions' ``known=``
  do (one parser: `mbody.model.expressions`), taken at the state's time (a run's time in
  `simulate`); a bad one is refused with where and what, exit 2;
- a message names an argument in the spelling of the surface it is read on: the flag on
  the command line (``--coordinates``, ``--known O.Fx``, ``--steps``), the keyword in
  Python (``coordinates=[...]``, ``known['O.Fx']``, ``steps``);
- one byte budget (`mbody.util.budget`) for model text and data files, each kind keeping
  its default.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import build_parser, option_flags
from mbody.errors import (
    MbodyError,
    ModelError,
    option_entry,
    option_name,
    option_setting,
    options_named,
)
from mbody.util import budget
from tests.test_cli_options import commands, run

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"
FLYWHEEL = MODELS / "practice_2_flywheel.yaml"


# == 1. --known LABEL=EXPR ====================================================================

def _solve_json(capsys, *known: str) -> dict:
    code, out, err = run(capsys, "solve", FLYWHEEL, "--json",
                         *[w for k in known for w in ("--known", k)])
    assert (code, err) == (0, "")
    return json.loads(out)


def test_solve_takes_an_expression_at_the_states_time(capsys):
    """The flywheel's bearing carries its weight, 122.625 N; 10 cos(t) N more at the
    initial state (t = 0 s) is 10 N: a_y = 10 / 12.5 = 0.8 m/s^2, alpha = 10 / 0.25 =
    40 rad/s^2 as before. The same as the number 132.625, and as Python's solve."""
    by_text = _solve_json(capsys, "bearing.Fy=122.625 + 10*cos(t)")
    by_number = _solve_json(capsys, "bearing.Fy=132.625")
    assert by_text["reactions"]["bearing.Fy"] == 132.625
    assert by_text["accelerations"] == by_number["accelerations"]
    assert by_text["by_body"]["flywheel"]["flywheel.y"] == pytest.approx(0.8, rel=1e-12)
    assert by_text["by_body"]["flywheel"]["flywheel.theta"] == pytest.approx(40.0, rel=1e-12)
    python = mbody.assemble(mbody.load(FLYWHEEL)).solve(
        known={"bearing.Fy": "122.625 + 10*cos(t)"})
    assert python.accelerations.tolist() == by_text["accelerations"]


def test_export_takes_the_expression_at_the_runs_sample(tmp_path, capsys):
    """`export --state RUN --time 0.5`: the state is the run's sample at t = 0.5 s, and
    O.Fx = 2 t is recorded as 1 N, as `Assembly.reaction_values` takes it there."""
    runfile, out = tmp_path / "run.npz", tmp_path / "x.json"
    assert run(capsys, "simulate", PENDULUM, "--t-end", "1", "--fps", "10", "-o", runfile,
               "--no-progress")[0] == 0
    code, _, err = run(capsys, "export", PENDULUM, "--state", runfile, "--time", "0.5",
                       "--known", "O.Fx=2*t", "-o", out)
    assert (code, err) == (0, "")
    exp = mbody.load_export(out)
    assert exp.t == 0.5 and exp.known == {"O.Fx": 1.0}


def test_simulate_applies_the_expression_as_time_goes(tmp_path, capsys):
    """The pendulum's pin force given as O.Fx = 3 t N, O.Fy = m g: the rod is a free body
    whose mass centre obeys m a = F + m g, so x_G = x_0 + (3 / (6 m)) t^3 = x_0 + t^3 / 4
    and y_G stays (2 kg). The integrator's tolerance (rtol 1e-10) bounds the error."""
    runfile = tmp_path / "run.npz"
    code, _, err = run(capsys, "simulate", PENDULUM, "--t-end", "1", "--fps", "10",
                       "--known", "O.Fx=3*t", "--known", "O.Fy=19.62", "-o", runfile,
                       "--no-progress")
    assert (code, err) == (0, "")
    traj = mbody.Trajectory.load(runfile)
    x, y = traj.position[:, 0, 0], traj.position[:, 0, 1]
    np.testing.assert_allclose(x - x[0], traj.t**3 / 4, rtol=0, atol=1e-9)
    np.testing.assert_allclose(y, y[0], rtol=0, atol=1e-9)
    python = mbody.simulate(mbody.load(PENDULUM), 1.0, 10,
                            known={"O.Fx": "3*t", "O.Fy": 19.62})
    np.testing.assert_array_equal(python.position, traj.position)


KNOWN_ERRORS = [
    ("O.Fx=2t", "--known O.Fx: unexpected name 't' at character 2 of '2t' (write '*' for "
     "multiplication, e.g. 2*t)"),
    ("O.Fx=3*sinn(t)", "--known O.Fx: unknown name 'sinn' at character 3 of '3*sinn(t)' "
     "(did you mean 'sin'? known names: t, pi, sin, cos, tan, exp, log, sqrt, abs)"),
    ("O.Fx=3*cosine(t)", "--known O.Fx: unknown name 'cosine' at character 3 of "
     "'3*cosine(t)' (did you mean 'cos'?"),
    ("O.Fx=sin(t", "--known O.Fx: missing ')' at character 6 of 'sin(t' (to close sin( at "
     "character 1)"),
    ("O.Fx=t == 1", "--known O.Fx: unexpected character '=' at character 3 of 't == 1' "
     "(comparisons are not supported)"),
    ("O.fx=2*t", "no reaction component 'O.fx' in this model; did you mean 'O.Fx'?"),
]


@pytest.mark.parametrize("command", ["solve", "simulate", "export", "lagrange"])
@pytest.mark.parametrize(("known", "message"), KNOWN_ERRORS,
                         ids=["product", "function", "function start", "parenthesis",
                              "comparison", "label"])
def test_a_bad_expression_is_refused_with_where_and_what(tmp_path, capsys, command, known,
                                                         message):
    out = tmp_path / "x.json"
    extra = {"export": ["-o", out], "simulate": ["--no-progress", "-o", tmp_path / "r.npz"]}
    code, stdout, err = run(capsys, command, PENDULUM, "--known", known,
                            *extra.get(command, []))
    assert (code, stdout) == (2, "")
    assert err.startswith(f"mbody: error: {message}")
    assert err.count("\n") == 1
    assert not out.exists() and not (tmp_path / "r.npz").exists()


@pytest.mark.parametrize("command", ["solve", "export", "lagrange"])
def test_an_expression_not_finite_at_the_states_time_is_refused(tmp_path, capsys, command):
    extra = ["-o", tmp_path / "x.json"] if command == "export" else []
    code, _, err = run(capsys, command, PENDULUM, "--known", "O.Fx=1/t", *extra)
    assert code == 2
    assert err == ("mbody: error: --known O.Fx = '1/t' is not finite at the state's t = 0 s "
                   "(inf)\n")


def test_simulate_refuses_an_expression_not_finite_within_its_span(capsys):
    code, _, err = run(capsys, "simulate", PENDULUM, "--known", "O.Fx=1/(t - 0.5)",
                       "--t-end", "1", "--no-progress")
    assert code == 2
    assert err.startswith('mbody: error: the known reaction O.Fx = "1/(t - 0.5)" is not '
                          "finite at t = 0.5 s (inf), within the simulated span 0 .. 1 s")
    assert err.endswith("(--t-end below 0.5).\n")
    assert run(capsys, "simulate", PENDULUM, "--known", "O.Fx=1/(t - 0.5)", "--t-end",
               "0.4", "--no-progress")[0] == 0


def test_an_expression_is_parsed_never_run(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "solve", PENDULUM, "--known",
                       "O.Fx=__import__('os').system('touch pwned')")
    assert code == 2 and "unknown name '__import__'" in err
    assert not (tmp_path / "pwned").exists()


def test_numbers_are_read_as_before(capsys):
    """A number is a number (its bounds and messages as before), also in the form an
    expression would read differently: 1e-400 is below the smallest double in an
    expression, and 0 here, as float() reads it."""
    assert _solve_json(capsys, "bearing.Fy=1e-400")["reactions"]["bearing.Fy"] == 0.0
    code, _, err = run(capsys, "solve", FLYWHEEL, "--known", "bearing.Fy=1e101")
    assert code == 2 and "expected a number of magnitude at most 1e100" in err
    code, _, err = run(capsys, "solve", FLYWHEEL, "--known", "bearing.Fy=2*t",
                       "--known", "bearing.Fy=3")
    assert (code, err) == (2, "mbody: error: --known bearing.Fy is given twice\n")


def test_the_python_functions_keep_their_spelling():
    asm = mbody.assemble(mbody.load(PENDULUM))
    with pytest.raises(MbodyError, match=r"^known\['O.Fx'\]: unexpected name 't' at "
                                         r"character 2 of '2t'"):
        asm.solve(known={"O.Fx": "2t"})
    with pytest.raises(MbodyError, match=r"^known\['O.Fx'\] = '1/t' is not finite at the "
                                         r"state's t = 0 s \(inf\)$"):
        asm.generalized(known={"O.Fx": "1/t"})


def test_a_model_files_expression_gets_the_did_you_mean_too(tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text("dimension: 2\nbodies: [{name: p, mass: 2, inertia: 0.5}]\n"
                    "loads: [{type: force, body: p, force: [\"50*sinus(2*t)\", 0]}]\n")
    code, _, err = run(capsys, "check", path)
    assert code == 2
    assert (f"{path}:3:40: loads[0].force[0]: invalid expression: unknown name 'sinus' at "
            "character 4 (marked |): \"50*|sinus(2*t)\" (did you mean 'sin'? known names: "
            "t, pi, sin, cos, tan, exp, log, sqrt, abs)") in err
    for text, hint in (("nan", "a value must be a finite number"), ("ln(t)", "'log'"),
                       ("Time", "'t'"), ("x", "the only variable is t")):
        with pytest.raises(MbodyError, match=hint):
            mbody.model.expressions.compile_expression(text)


# == 2. each surface's spelling ==============================================================

def test_each_option_is_named_by_its_long_flag_in_every_command():
    """What `main` sets around a command: every option by its destination, its long
    name (sweep's --out, not -o), and the keywords a command declares (sweep's values is
    --set) and an imported model's (joint_positions is --q)."""
    parser = build_parser()
    for name, command in commands().items():
        args = argparse_defaults(command)
        flags = option_flags(command, args)
        for action in command._actions:
            if action.option_strings and action.dest != "help":
                assert flags[action.dest] in action.option_strings, (name, action.dest)
                assert flags[action.dest].startswith("--"), (name, action.dest)
        assert flags["joint_positions"] == "--q"
    sweep = parser.parse_args(["sweep", "m.yaml", "--set", "x=1", "--out", "o.csv"])
    flags = option_flags(commands()["sweep"], sweep)
    assert {k: flags[k] for k in ("values", "run", "revolutions", "out", "steps", "t_end")} \
        == {"values": "--set", "run": "--run", "revolutions": "--t-end", "out": "--out",
            "steps": "--steps", "t_end": "--t-end"}


def argparse_defaults(command: argparse.ArgumentParser) -> argparse.Namespace:
    """The namespace of `command`'s defaults (what its set_defaults put there)."""
    return argparse.Namespace(**command._defaults)


def test_the_helpers_give_each_spelling():
    assert (option_name("coordinates", "[...]"), option_setting("max_steps", 10),
            option_setting("method", "Radau"), option_setting("rtol", 1e-6),
            option_entry("known", "A.Fx"), option_name("samples", "N", "N")) == \
        ("coordinates=[...]", "max_steps=10", "method='Radau'", "rtol=1e-6",
         "known['A.Fx']", "samples=N")
    flags = {"coordinates": "--coordinates", "max_steps": "--max-steps", "method": "--method",
             "rtol": "--rtol", "known": "--known", "samples": "--samples",
             "equilibrium": "--equilibrium"}
    with options_named(flags):
        assert (option_name("coordinates", "[...]"), option_setting("max_steps", 10),
                option_setting("method", "Radau"), option_setting("rtol", 1e-6),
                option_entry("known", "A.Fx"), option_name("samples", "N", "N"),
                option_setting("equilibrium", True)) == \
            ("--coordinates", "--max-steps 10", "--method Radau", "--rtol 1e-6",
             "--known A.Fx", "--samples N", "--equilibrium")
    assert option_name("coordinates") == "coordinates"  # set around the block only


def _python_error(call) -> str:
    with pytest.raises(MbodyError) as info:
        call()
    return str(info.value)


def test_singular_coordinates_name_the_argument_as_given(capsys):
    """The pendulum's equilibrium hangs straight down, where its mass centre's height
    does not move to first order: rod.y cannot be its coordinate there."""
    code, _, err = run(capsys, "modes", PENDULUM, "--equilibrium", "--coordinates", "rod.y")
    assert code == 2
    assert err.startswith("mbody: error: the coordinates rod.y do not determine the motion "
                          "of 'physical-pendulum' at t = 0 s (a singular position for them")
    assert err.endswith("; choose others with --coordinates\n") and "coordinates=" not in err
    model = mbody.load(PENDULUM)
    said = _python_error(lambda: mbody.linearize(model, mbody.equilibrium(model),
                                                 coordinates=["rod.y"]))
    assert said.endswith("; choose others with coordinates=[...]") and "--" not in said


def test_a_budget_is_named_as_it_was_given(capsys):
    model = MODELS / "torque_free_asymmetric.yaml"
    code, _, err = run(capsys, "simulate", model, "--t-end", "5", "--max-steps", "10",
                       "--no-progress")
    assert code == 2
    assert "at the step budget: 10 steps (--max-steps 10)" in err
    assert "a shorter --t-end, a looser --rtol (e.g. 1e-8), a stiff integrator such as " \
           "--method Radau if the model is stiff (very stiff springs), or raise --max-steps." \
           in err
    said = _python_error(lambda: mbody.simulate(mbody.load(model), 5.0, max_steps=10))
    assert "at the step budget: 10 steps (max_steps=10)" in said
    assert "a shorter t_end, a looser rtol (e.g. 1e-8), a stiff integrator such as " \
           "method='Radau' if the model is stiff (very stiff springs), or raise max_steps." \
           in said
    assert "--" not in said


def test_a_sweeps_value_is_named_as_it_was_given(tmp_path, capsys):
    out = tmp_path / "s.csv"
    code, _, err = run(capsys, "sweep", PENDULUM, "--set", "bodies.rod.mass=0.3:x:3",
                       "--workers", "0", "--quiet", "--out", out)
    assert (code, err) == (2, "mbody: error: --set bodies.rod.mass: 'x' is not a number (a "
                              "range is START:STOP:COUNT, such as "
                              "bodies.rod.mass=0.3:1.2:10)\n")
    said = _python_error(lambda: mbody.run_sweep(PENDULUM, {"bodies.rod.mass": "0.3:x:3"},
                                                 out, workers=0))
    assert said == ("values['bodies.rod.mass']: 'x' is not a number (a range is "
                    "START:STOP:COUNT, such as bodies.rod.mass=0.3:1.2:10)")
    assert not out.exists()


def test_a_sweeps_case_errors_read_alike_wherever_they_ran(monkeypatch):
    """A case's error is a row of the results: evaluated under the caller's names
    (`Job.names`), the same in this process as on a worker, where no command line is."""
    from mbody.sweep import runs

    with options_named({"revolutions": "--t-end", "t_end": "--t-end"}):
        assert runs.turns_end("2") == "--t-end '2 rev'"
    assert runs.turns_end("2") == "revolutions=2"
    seen = []
    monkeypatch.setattr(runs, "_run_chunk",
                        lambda job, indices: seen.append(runs.turns_end("1")))
    for names in ({"revolutions": "--t-end"}, {}):
        runs.run_chunk(runs.Job(None, None, None, "k", names), [0])
    assert seen == ["--t-end '1 rev'", "revolutions=1"]


def test_a_driver_to_plot_against_is_named_as_it_was_given(tmp_path, capsys):
    runfile = tmp_path / "run.npz"
    assert run(capsys, "kinematics", MODELS / "slider_crank_driven.yaml", "--t-end", "0.1",
               "-o", runfile)[0] == 0
    code, _, err = run(capsys, "plot", runfile, "-o", tmp_path / "p.png", "--against", "motr")
    assert (code, err) == (2, "mbody: error: --against motr: expected 'time' or a driver of "
                              "this run (motor); did you mean 'motor'?\n")
    from mbody.present.plot import save_plot

    said = _python_error(lambda: save_plot(mbody.Trajectory.load(runfile),
                                           tmp_path / "q.png", against="motr"))
    assert said == ("against='motr': expected 'time' or a driver of this run (motor); did "
                    "you mean 'motor'?")


# == 3. one byte budget ======================================================================

def test_one_budget_for_model_text_and_data_each_kind_keeping_its_default(tmp_path):
    """`byte_budget` sets one value for every read within the block (a model's text, a
    run's data); outside it each kind has its own default; a call's own max_bytes wins."""
    assert (budget.MAX_BYTES, budget.DATA_BYTES, budget.TEXT_BYTES) == (32 << 20, 1 << 30,
                                                                       32 << 20)
    assert budget.byte_limit(None, budget.DATA_BYTES) == budget.DATA_BYTES
    assert budget.byte_limit(None, budget.MAX_BYTES) == budget.MAX_BYTES
    traj = mbody.simulate(mbody.load(PENDULUM), 0.5, 10)
    runfile = traj.save(tmp_path / "run.npz")
    size = PENDULUM.stat().st_size
    with budget.byte_budget(size - 1):
        assert budget.byte_limit(None, budget.DATA_BYTES) == size - 1
        with pytest.raises(ModelError, match="mbody reads at most"):
            mbody.load(PENDULUM)
        with pytest.raises(MbodyError, match="at most .* is read"):
            mbody.Trajectory.load(runfile)
        assert mbody.load(PENDULUM, max_bytes=size).n == 1  # the call's own wins
        with budget.byte_budget(None):  # None keeps the block's
            assert budget.byte_limit(None, budget.MAX_BYTES) == size - 1
    assert mbody.load(PENDULUM).n == 1 and mbody.Trajectory.load(runfile).n == 1


def test_the_command_lines_max_bytes_is_that_one_budget(tmp_path, capsys):
    runfile = tmp_path / "run.npz"
    assert run(capsys, "simulate", PENDULUM, "--t-end", "0.5", "-o", runfile,
               "--no-progress")[0] == 0
    code, _, err = run(capsys, "plot", runfile, "-o", tmp_path / "p.png", "--max-bytes", "1k")
    assert code == 2 and "at most 1 KiB (1,024 bytes) is read" in err
    code, _, err = run(capsys, "check", PENDULUM, "--max-bytes", "100")
    assert code == 2 and "mbody reads at most 100 bytes" in err
    assert budget.byte_limit(None, budget.MAX_BYTES) == budget.MAX_BYTES  # around it only
    assert budget.byte_limit(None, budget.DATA_BYTES) == budget.DATA_BYTES

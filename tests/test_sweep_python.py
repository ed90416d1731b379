"""`mbody.run_sweep`, a whole sweep from Python, is what `mbody sweep` runs: the same rows
as the command for the same sweep (solve, kinematics, modes; in this process and on a
local cluster), a resumed output from Python, bad arguments refused with the command's
messages before any case runs (each naming the arguments in its own spelling: ``--steps``
on the command line, ``steps`` in Python), and the warnings returned, not printed."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pytest

import mbody
import mbody.cli
from mbody.cli.app import build_parser, option_flags
from mbody.errors import MbodyError, options_named
from mbody.simulate.peaks import SPARSE
from mbody.sweep import cluster, runs
from mbody.sweep.limits import LIMITS
from mbody.sweep.study import SweepInterrupted, SweepResult
from tests.test_sweep import SLIDER, driven_text, floats, mbody_cli, read

ROOT = Path(__file__).resolve().parent.parent
PENDULUM = ROOT / "models" / "pendulum.yaml"
GRID = ["drivers.motor.speed=60:240:3", "bodies.rod.mass=0.3:1.2:2"]


@pytest.fixture
def driven_file(tmp_path) -> Path:
    path = tmp_path / "driven.yaml"
    path.write_text(driven_text())
    return path


def cli_rows(tmp_path: Path, model: Path, specs: list[str], *options: str
             ) -> tuple[list[str], list[list[str]], str]:
    """The command's output of the sweep, run in its own process (--workers 0): header,
    rows and what it wrote on standard error."""
    out = tmp_path / "cli.csv"
    argv = [a for s in specs for a in ("--set", s)]
    p = mbody_cli("sweep", str(model), *argv, *options, "--workers", "0", "--quiet",
                  "--out", str(out))
    assert p.returncode == 0, p.stderr
    return (*read(out), p.stderr)


def as_the_command_names_them():
    """Within the block, messages name run_sweep's arguments as `mbody sweep` does (what
    `mbody.cli.app.main` sets around the command): ``--set``, ``--steps``, ``--t-end``."""
    parser = build_parser()
    args = parser.parse_args(["sweep", "m.yaml", "--set", "x=1", "--out", "o.csv"])
    return options_named(option_flags(parser._subparsers._group_actions[0].choices["sweep"],
                                      args))


def printed(warnings: list[str]) -> str:
    """What the command writes on standard error for these warnings."""
    return "".join(f"mbody: warning: {w}\n" for w in warnings)


@pytest.mark.parametrize(("specs", "options", "kw"), [
    ([*GRID, "gravity=[0, -1.62]"], [], {}),
    (GRID, ["--run", "kinematics", "--t-end", "1 rev", "--steps", "37"],
     {"run": "kinematics", "revolutions": 1.0, "steps": 37}),
    (GRID, ["--run", "kinematics", "--t-end", "0.05", "--steps", "11"],
     {"run": "kinematics", "t_end": 0.05, "steps": 11}),
], ids=["solve", "kinematics in turns", "kinematics in seconds"])
def test_the_rows_are_the_commands(driven_file, tmp_path, specs, options, kw):
    """The same sweep from the command and from Python (both in one process): the same
    header and rows, cell for cell, in the result and in the file it wrote."""
    header, rows, stderr = cli_rows(tmp_path, driven_file, specs, *options)
    result = mbody.run_sweep(driven_file, specs, tmp_path / "py.csv", workers=0, **kw)
    assert isinstance(result, SweepResult)
    assert (result.header, result.rows) == (header, rows)
    assert read(result.path) == (header, rows) and result.path == tmp_path / "py.csv"
    assert len(result) == result.ran == 6 and result.kept == 0 and result.failed == 0
    assert result.errors == [None] * 6
    # 10 instants over 0.05 s: the 240 rad/s cases turn 1.9 times, 5 samples a turn; the
    # command names the option it advises as typed (--steps 12), Python the keyword
    assert len(result.warnings) == ("t_end" in kw)
    assert stderr == printed(result.warnings).replace("Use steps=", "Use --steps ")
    assert "--" not in "".join(result.warnings)
    assert result.report.cases == 6 and result.report.where == "this process"


def test_a_modes_sweep_from_a_mapping_is_the_commands(tmp_path):
    """The pendulum about its rest position, gravity listed as a Python list: the rows of
    ``--set gravity.1=-9.81,-3.72,-1.62 --run modes --equilibrium``; frequency:1 is the
    physical pendulum's sqrt(g d / (k_O^2)) within the linearisation's error bound."""
    header, rows, stderr = cli_rows(tmp_path, PENDULUM, ["gravity.1=-9.81,-3.72,-1.62"],
                                    "--run", "modes", "--equilibrium")
    model = mbody.load(PENDULUM)
    result = mbody.run_sweep(model, {"gravity.1": [-9.81, -3.72, -1.62]},
                             tmp_path / "py.csv", run="modes", equilibrium=True, workers=0)
    assert (result.header, result.rows) == (header, rows)
    assert result.warnings == [] and stderr == ""  # every case at an equilibrium
    k_o2 = (0.05**2 + 1.0**2) / 12 + 0.5**2
    g = -result.column("gravity.1")
    for case, w in enumerate(result.column("frequency:1")):
        at = model.with_values({"gravity.1": -g[case]})
        lin = mbody.linearize(at, mbody.equilibrium(at))
        bound = float(lin.eigenvalue_errors.max())
        assert abs(w - math.sqrt(g[case] * 0.5 / k_o2)) <= bound + 1e-12 * w
    assert result.column("steady").tolist() == [1.0] * 3
    assert result.column("stable").tolist() == [1.0] * 3


def test_the_python_forms_of_values_give_the_same_grid(tmp_path):
    """A mapping (ranges as --set texts, values listed as a tuple or an array, a fixed
    number) and the --set texts: one sweep, the same rows."""
    texts = ["drivers.motor.speed=60:240:3", "bodies.rod.mass=0.3,1.2",
             "loads.gas.force.0=0"]
    mapping = {"drivers.motor.speed": "60:240:3", "bodies.rod.mass": np.array([0.3, 1.2]),
               "loads.gas.force.0": 0}
    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    a = mbody.run_sweep(model, texts, tmp_path / "a.csv", workers=0)
    b = mbody.run_sweep(model, mapping, tmp_path / "b.csv", workers=0)
    assert a.header == b.header and a.rows == b.rows and len(a) == 6
    # the fixed value took: with no gas load, O.Fx at rest is all inertia of the start
    unloaded = mbody.assemble(model.with_values({"loads.gas.force.0": 0,
                                                 "drivers.motor.speed": 60.0,
                                                 "bodies.rod.mass": 0.3})).solve()
    assert b.column("reaction:O.Fx")[0] == unloaded.reactions["O.Fx"]


def test_an_interrupted_sweep_resumes_from_python(driven_file, tmp_path, monkeypatch):
    """Interrupted after its first chunk: SweepInterrupted (a KeyboardInterrupt) says how
    many cases were kept and where; the same call again runs only the others, and the
    output equals an uninterrupted run's; another sweep into that output is refused."""
    real = cluster.run_chunk
    calls = []

    def once_then_stop(job, part):
        calls.append(list(part))
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(job, part)

    monkeypatch.setattr(cluster, "run_chunk", once_then_stop)
    out = tmp_path / "resume.csv"
    with pytest.raises(SweepInterrupted) as stopped:
        mbody.run_sweep(driven_file, GRID, out, workers=0, chunk=2)
    assert isinstance(stopped.value, KeyboardInterrupt)
    assert (stopped.value.kept, stopped.value.cases) == (2, 6)
    assert stopped.value.journal == Path(f"{out}.partial") and stopped.value.journal.exists()
    assert not out.exists()
    monkeypatch.setattr(cluster, "run_chunk", real)
    again = mbody.run_sweep(driven_file, GRID, out, workers=0, chunk=2)
    assert (again.ran, again.kept, len(again)) == (4, 2, 6)
    assert again.report.cases == 4 and not stopped.value.journal.exists()
    whole = mbody.run_sweep(driven_file, GRID, tmp_path / "whole.csv", workers=0)
    assert again.rows == whole.rows == read(out)[1]
    done = mbody.run_sweep(driven_file, GRID, out, workers=0)  # nothing left to run
    assert (done.ran, done.kept, done.rows) == (0, 6, whole.rows)
    assert done.report.cases == 0
    with pytest.raises(MbodyError, match="another sweep"):
        mbody.run_sweep(driven_file, ["drivers.motor.speed=70:240:3", GRID[1]], out,
                        workers=0)


def test_the_command_says_how_far_an_interrupted_sweep_got(driven_file, tmp_path,
                                                          monkeypatch, capsys):
    real = cluster.run_chunk
    calls = []

    def stop_second(job, part):
        calls.append(part)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(job, part)

    monkeypatch.setattr(cluster, "run_chunk", stop_second)
    out = tmp_path / "i.csv"
    code = mbody.cli.main(["sweep", str(driven_file), "--set", GRID[0], "--set", GRID[1],
                           "--workers", "0", "--chunk", "2", "--quiet", "--out", str(out)])
    assert code == 130
    assert capsys.readouterr().err == (f"mbody: interrupted: 2 of 6 cases kept in {out}.partial;"
                                       " the same command resumes\nmbody: interrupted\n")


def refused_by_the_command(tmp_path: Path, model: Path, *args: str) -> str:
    out = tmp_path / "refused.csv"
    p = mbody_cli("sweep", str(model), *args, "--workers", "0", "--quiet",
                  *(() if "--out" in args else ("--out", str(out))))
    assert p.returncode == 2 and not out.exists(), p.stderr
    assert p.stderr.startswith("mbody: error: ")
    return p.stderr.removeprefix("mbody: error: ").rstrip("\n")


@pytest.mark.parametrize(("args", "kw"), [
    (["--set", "bodies.rdo.mass=0.3:1.2:3"], {"values": ["bodies.rdo.mass=0.3:1.2:3"]}),
    (["--set", "bodies.rdo.mass=0.3:1.2:3"], {"values": {"bodies.rdo.mass": "0.3:1.2:3"}}),
    (["--set", "bodies.rod.mass=0.3:1.2:3", "--out", "x.txt"],
     {"out": "x.txt"}),
    (["--set", "bodies.rod.mass=0.3:x:3"], {"values": ["bodies.rod.mass=0.3:x:3"]}),
    (["--set", "bodies.rod.mass=0.3:x:3"], {"values": {"bodies.rod.mass": "0.3:x:3"}}),
    (["--set", "bodies.rod.mass=0.4:0.8:1"], {"values": ["bodies.rod.mass=0.4:0.8:1"]}),
    (["--set", "bodies.rod.mass=1,.nan"], {"values": {"bodies.rod.mass": [1, math.nan]}}),
    (["--set", "bodies.rod.mass=1:2:2", "--set", "bodies.rod.mass=3"],
     {"values": ["bodies.rod.mass=1:2:2", "bodies.rod.mass=3"]}),
    (["--set", "bodies.rod.mass=2"], {"values": {"bodies.rod.mass": 2}}),
    (["--set", "bodies.rod.mass=1:2:2", "--seed", "3"], {"seed": 3}),
    (["--set", "bodies.rod.mass=1:2:2", "--run", "kinematics"], {"run": "kinematics"}),
    (["--set", "bodies.rod.mass=1:2:2", "--equilibrium"], {"equilibrium": True}),
    (["--set", "bodies.rod.mass=1:2:2", "--run", "kinematics", "--t-end", "1 rev"],
     {"run": "kinematics", "revolutions": 1.0, "model": SLIDER}),
    (["--set", "bodies.rod.mass=1:2:2", "--run", "kinematics", "--t-end", "0.1"],
     {"run": "kinematics", "t_end": 0.1, "model": SLIDER}),
], ids=["path", "path in a mapping", "extension", "range", "range in a mapping", "count of 1",
        "not finite", "given twice", "nothing varies",
        "seed without samples", "no end", "equilibrium without modes", "no turning driver",
        "not fully driven"])
def test_bad_arguments_are_refused_with_the_commands_message(driven_file, tmp_path, args, kw):
    """Before any case runs, and before anything is written."""
    model = kw.pop("model", driven_file)
    given = {"values": [a for a in args[1:2]], "out": tmp_path / "refused.csv", **kw}
    said = refused_by_the_command(tmp_path, model, *args)
    with as_the_command_names_them(), pytest.raises(MbodyError) as refused:
        mbody.run_sweep(model, workers=0, **given)
    assert str(refused.value) == said
    with pytest.raises(MbodyError) as refused:  # Python names the keywords it was given
        mbody.run_sweep(model, workers=0, **given)
    assert not any(f in str(refused.value) for f in ("--set", "--seed", "--samples",
                                                     "--equilibrium", "--run", "--t-end"))
    assert not (tmp_path / "refused.csv").exists()
    assert not (tmp_path / "refused.csv.partial").exists()


@pytest.mark.parametrize(("kw", "pattern"), [
    ({"steps": 1}, "^steps: expected a number of instants from 2 to 1 000 000 "
                   r"\(a whole number\), got 1"),
    ({"steps": 10.5}, "^steps: expected"),
    ({"t_end": 0.0}, "^t_end: expected a time in seconds above 0 up to 1e9, got 0.0"),
    ({"t_end": math.nan}, "^t_end: expected"),
    ({"revolutions": -1}, "^revolutions: expected a number of turns above 0"),
    ({"t_end": 1.0, "revolutions": 1.0}, "in seconds .* or in turns .*not both"),
    ({"fps": "60"}, "^fps: expected samples per second"),
    ({"workers": -1}, "^workers: expected"),
    ({"workers": True}, "^workers: expected"),
    ({"chunk": 0}, "^chunk: expected a number of cases from 1"),
    ({"samples": 0}, "^samples: expected a number of cases from 1"),
    ({"seed": -1, "samples": 3}, "^seed: expected a seed from 0"),
    ({"run": "simulation"}, "unknown run 'simulation'; expected one of solve, kinematics"),
    ({"values": [3]}, "expected a mapping path -> values .* got 3 \\(int\\)"),
    ({"values": {"bodies.rod.mass": []}}, r"^values\['bodies.rod.mass'\]: no values"),
    ({"values": {"bodies.rod.mass": [1.0, math.nan]}},
     r"^values\['bodies.rod.mass'\]: expected a finite number, got nan \(value 2 of 2\)$"),
    ({"values": {"gravity": [[0, -9.81], [0, -math.inf]]}},
     r"^values\['gravity'\]: expected a finite number, got -inf "
     r"\(value 2 of 2: \[0, -inf\]\)$"),
    ({"values": {"bodies.rod.mass": [1, 2], " bodies.rod.mass ": [3]}},
     r"^values\['bodies.rod.mass'\] is given twice \(as 'bodies.rod.mass' and "
     r"' bodies.rod.mass '\)$"),
    ({"equilibrium": "no", "run": "modes"}, r"^equilibrium: expected True or False, got 'no'$"),
    ({"force": 1}, r"^force: expected True or False, got 1$"),
    ({"progress": "yes"}, r"^progress: expected True or False, got 'yes'$"),
    ({"model": 3}, "expected a Model or a model file's path, got int"),
    ({"out": None}, "the output: expected a file name"),
    ({"scheduler": 8786}, "^scheduler: expected an address"),
])
def test_python_arguments_are_checked(driven_file, tmp_path, kw, pattern):
    given = {"model": driven_file, "values": {"bodies.rod.mass": [1, 2]},
             "out": tmp_path / "x.csv", **kw}
    with pytest.raises(MbodyError, match=pattern):
        mbody.run_sweep(given.pop("model"), given.pop("values"), given.pop("out"), **given)
    assert not (tmp_path / "x.csv").exists()


def test_the_ranges_are_the_commands():
    """Each numeric argument takes what the command's option takes: probed at its ends."""
    actions = {a.option_strings[0]: a for a in
               build_parser()._subparsers._group_actions[0].choices["sweep"]._actions
               if a.option_strings}

    def cli_takes(option: str, text: str) -> bool:
        try:
            actions[option].type(text)
        except argparse.ArgumentTypeError:  # what a type raises for a value it refuses
            return False
        return True

    def python_takes(name: str, x: float) -> bool:
        try:
            LIMITS[name].check(x)
        except MbodyError:
            return False
        return True

    for name, limit in LIMITS.items():
        eps = 1 if limit.integer else 1e-9 * max(abs(limit.hi), 1.0)
        probes = [limit.lo - eps, limit.lo, limit.lo + eps, limit.hi - eps, limit.hi,
                  limit.hi + eps]
        for x in probes:
            x = int(x) if limit.integer else float(x)
            text = f"{x!r} rev" if name == "revolutions" else repr(x)
            assert cli_takes(limit.option, text) == python_takes(name, x), (name, x)


@pytest.mark.parametrize("name", sorted(LIMITS))
def test_the_command_and_python_say_one_range(name):
    """The option's type is built from `LIMITS` (Y3 of review R3: the ranges were written
    twice, kept equal by a test): beyond its upper end, the command and `run_sweep` refuse
    a value in the same words."""
    limit = LIMITS[name]
    option = next(a for a in build_parser()._subparsers._group_actions[0]
                  .choices["sweep"]._actions if limit.option in a.option_strings)
    over = int(limit.hi) + 1 if limit.integer else 2 * limit.hi
    expected = f"expected {limit.what} {limit.span}"
    with pytest.raises(argparse.ArgumentTypeError) as cli:
        option.type(f"{over!r} rev" if name == "revolutions" else repr(over))
    with pytest.raises(MbodyError) as python:
        limit.check(over)
    with as_the_command_names_them(), pytest.raises(MbodyError) as named:
        limit.check(over)
    assert str(cli.value).startswith(expected), str(cli.value)
    assert str(python.value).startswith(f"{limit.keyword}: {expected}")
    assert str(named.value).startswith(f"{limit.option}: {expected}")


def test_warnings_are_returned_and_the_command_prints_them(tmp_path):
    """A modes sweep about the release (not an equilibrium) and a kinematics sweep whose
    fast cases are sampled too sparsely: the result carries each warning; the command
    prints the same text, once, as mbody: warning: ..., naming the option it advises as
    typed (--equilibrium, --steps 181) where Python names the keyword (equilibrium=True,
    steps=181)."""
    modes = mbody.run_sweep(PENDULUM, {"gravity.1": [-9.81, -1.62]}, tmp_path / "m.csv",
                            run="modes", workers=0)
    assert len(modes.warnings) == 1
    assert modes.warnings[0].startswith("the initial state of 2 of 2 cases is not an "
                                        "equilibrium")
    assert np.isnan(modes.column("stable")).all()
    p = mbody_cli("sweep", str(PENDULUM), "--set", "gravity.1=-9.81,-1.62", "--run", "modes",
                  "--workers", "0", "--quiet", "--out", str(tmp_path / "mc.csv"))
    assert "equilibrium=True linearises each" in modes.warnings[0]
    assert p.returncode == 0 and p.stderr == "mbody: warning: " + modes.warnings[0].replace(
        "equilibrium=True", "--equilibrium") + "\n"

    model = tmp_path / "driven.yaml"
    model.write_text(driven_text("600 rpm"))
    speeds = {"drivers.motor.speed": "300 rpm:3000 rpm:4"}
    sparse = mbody.run_sweep(model, speeds, tmp_path / "k.csv", run="kinematics", t_end=0.1,
                             steps=101, workers=0)
    (text,) = sparse.warnings
    assert text.startswith(f"{SPARSE}: motor turns at 3000 rpm") and "steps=181" in text
    assert text == runs.sampling_warning(runs.Settings("kinematics", 0.1, steps=101),
                                         _grid(speeds), sparse.report.sparse,
                                         sparse.report.cases, sparse.report.sparsest)
    assert sparse.report.sparse == 2
    p = mbody_cli("sweep", str(model), "--set", "drivers.motor.speed=300 rpm:3000 rpm:4",
                  "--run", "kinematics", "--t-end", "0.1", "--steps", "101", "--workers",
                  "0", "--quiet", "--out", str(tmp_path / "kc.csv"))
    assert p.returncode == 0 and p.stderr == "mbody: warning: " + text.replace(
        "steps=181", "--steps 181") + "\n"
    enough = mbody.run_sweep(model, speeds, tmp_path / "k181.csv", run="kinematics",
                             t_end=0.1, steps=181, workers=0)
    assert enough.warnings == []
    # by default (no steps: 101 were the default) each case is sampled 360 times a turn
    default = mbody.run_sweep(model, speeds, tmp_path / "kd.csv", run="kinematics",
                              t_end=0.1, workers=0)
    assert default.warnings == []


def _grid(values):
    from mbody.sweep.grid import grid_of

    return grid_of(values)


QN = ("dimension: 3\nbodies:\n  - {name: a, mass: 1, inertia: [1, 1, 1], "
      "orientation: {quaternion: [2, 0, 0, 0]}}\ngravity: [0, 0, -9.81]\n")
"""A free body in a model with a warning (its quaternion normalised)."""


def test_a_model_files_warnings_are_returned_when_the_sweep_reads_it(tmp_path):
    path = tmp_path / "q.yaml"
    path.write_text(QN)
    result = mbody.run_sweep(path, {"bodies.a.mass": [1, 2]}, tmp_path / "q.csv", workers=0)
    said = f"{path}:3:70: bodies[0].orientation.quaternion: the quaternion has norm 2; it " \
           "was normalised"
    assert result.warnings == [said]
    # a Model given: its warnings are its own (model.warnings), not repeated
    model = mbody.load(path)
    again = mbody.run_sweep(model, {"bodies.a.mass": [1, 2]}, tmp_path / "q2.csv", workers=0)
    assert again.warnings == [] and [str(w) for w in model.warnings] == [said]
    # the free body falls at g whatever its mass
    assert again.column("acceleration:a.z").tolist() == [-9.81, -9.81]
    p = mbody_cli("sweep", str(path), "--set", "bodies.a.mass=1,2", "--workers", "0",
                  "--quiet", "--out", str(tmp_path / "q3.csv"))
    assert p.returncode == 0 and p.stderr == f"mbody: warning: {said}\n"  # once


def test_failed_cases_and_the_columns(driven_file, tmp_path):
    """A failed case is a row with its message and NaN numbers; column() reads numbers,
    names the column it has not (did you mean), and refuses one that holds text."""
    result = mbody.run_sweep(driven_file, {"bodies.rod.mass": [-0.5, 0.5],
                                           "drivers.motor.speed": ["60 rpm", "120 rpm"]},
                             tmp_path / "f.csv", workers=0)
    assert result.failed == 2 and len(result) == 4
    assert "expected a number > 0" in (result.errors[0] or "")
    assert result.errors[2:] == [None, None]
    assert np.isnan(result.column("reaction:O.Fx")[:2]).all()
    assert np.isfinite(result.column("reaction:O.Fx")[2:]).all()
    assert result.column("case").tolist() == [0.0, 1.0, 2.0, 3.0]
    with pytest.raises(KeyError, match="did you mean 'reaction:O.Fx'"):
        result.column("reaction:O.fx")
    with pytest.raises(MbodyError, match="holds text"):
        result.column("settings")
    # values listed in one unit: numbers, the unit in the column's name (F15 of review
    # R4: they were text, '60 rpm'); found by the path alone too
    assert result.header[1:3] == ["bodies.rod.mass", "drivers.motor.speed [rpm]"]
    speeds = result.column("drivers.motor.speed")
    assert speeds.tolist() == [60.0, 120.0, 60.0, 120.0]
    assert result.column("drivers.motor.speed [rpm]").tolist() == speeds.tolist()
    assert "2 failed" in repr(result) and "4 cases, 4 run now" in repr(result)


def test_a_varied_value_is_a_number_in_the_unit_it_was_written_in(driven_file, tmp_path):
    """F15 of review R4: the column of a speed swept as '30 rpm:60 rpm:2' held 30.0 with
    no unit. The unit is the one typed, in the column's name (not the file's: this file
    gives the speed in rad/s); the rows are the cases at those speeds in rpm. Values
    listed in one unit are numbers the same way: the command's range and Python's list
    give one file."""
    result = mbody.run_sweep(driven_file, {"drivers.motor.speed": ["30 rpm", "60 rpm"],
                                           "bodies.rod.mass": "0.4:0.8:2"},
                             tmp_path / "u.csv", workers=0)
    assert result.header[1:3] == ["drivers.motor.speed [rpm]", "bodies.rod.mass"]
    assert [r[1:3] for r in result.rows] == [["30.0", "0.4"], ["30.0", "0.8"],
                                             ["60.0", "0.4"], ["60.0", "0.8"]]
    model = mbody.load(driven_file)
    for row, fx in zip(result.rows, result.column("reaction:O.Fx"), strict=True):
        case = model.with_values({"drivers.motor.speed": f"{row[1]} rpm",
                                  "bodies.rod.mass": float(row[2])})
        assert fx == pytest.approx(mbody.assemble(case).solve().reactions["O.Fx"], rel=1e-12)
    # O.Fx is all inertia at constant speed (gravity acts along y): it scales as the
    # speed squared, four times 30 rpm's at 60 rpm
    fx = result.column("reaction:O.Fx")
    assert fx[2] / fx[0] == pytest.approx(4.0, rel=1e-9)
    header, rows, _ = cli_rows(tmp_path, driven_file, ["drivers.motor.speed=30 rpm:60 rpm:2",
                                                       "bodies.rod.mass=0.4:0.8:2"])
    assert (header, rows) == (result.header, result.rows)


def test_a_parquet_output_from_python(driven_file, tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")  # the sweep extra
    result = mbody.run_sweep(driven_file, GRID, tmp_path / "r.parquet", workers=0)
    csv = mbody.run_sweep(driven_file, GRID, tmp_path / "r.csv", workers=0)
    table = pq.read_table(result.path)
    assert table.column_names == result.header == csv.header
    for i, name in enumerate(result.header[:-2]):
        assert table.column(name).to_pylist() == floats([r[i] for r in csv.rows]).tolist()
    assert table.column("settings").to_pylist() == [csv.settings] * 6
    again = mbody.run_sweep(driven_file, GRID, tmp_path / "r.parquet", workers=0)
    assert again.ran == 0 and again.kept == 6
    for name in result.header[1:-2]:
        assert again.column(name).tolist() == csv.column(name).tolist()


def test_a_local_cluster_from_python(driven_file, tmp_path):
    """Dask from a Python session: the rows of the same sweep in this process."""
    pytest.importorskip("distributed")
    here = mbody.run_sweep(driven_file, GRID, tmp_path / "here.csv", workers=0,
                           run="kinematics", revolutions=1.0, steps=37)
    there = mbody.run_sweep(driven_file, GRID, tmp_path / "there.csv", workers=1, chunk=2,
                            run="kinematics", revolutions=1.0, steps=37)
    assert there.report.where == "a local cluster of 1 worker process"
    assert there.header == here.header
    for a, b in zip(there.rows, here.rows, strict=True):
        x, y = floats(a[3:-2]), floats(b[3:-2])
        assert a[:3] == b[:3] and np.abs(x - y).max() <= 1e-12 * np.abs(y).max()
        assert a[-2:] == b[-2:] == ["", here.settings]

"""A sweep whose peak: columns come from too few samples a revolution says so, as a
single run does (tests/test_driven_sampling.py): how many cases, the sparsest of them,
and the --steps (kinematics) or --fps (simulate) that gives every case `PEAK_SAMPLES`."""

from __future__ import annotations

import math
import uuid
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import build_parser
from mbody.simulate.kinematic import DEFAULT_FPS, SAMPLES_A_TURN, default_fps, revolution
from mbody.simulate.peaks import PEAK_SAMPLES, SPARSE
from mbody.sweep import cluster
from mbody.sweep.grid import parse_grid
from mbody.sweep.record import parse, record
from mbody.sweep.runs import Settings, columns, sampling_warning
from mbody.sweep.table import Results
from tests.test_sweep import SLIDER, driven_text, floats, job_of, mbody_cli, read

SPEEDS = ["drivers.motor.speed=300 rpm:3000 rpm:4"]
"""5, 20, 35 and 50 revolutions a second."""


def sweep(tmp_path: Path, settings: Settings, text: str | None = None,
          specs: list[str] = SPEEDS) -> tuple[cluster.Report, list[str], list[list[str]]]:
    model = mbody.loads(text or driven_text("600 rpm"), "driven.yaml")
    job = job_of(model, specs, settings)
    out = tmp_path / f"{uuid.uuid4().hex}.csv"
    results = Results(out, columns(model, settings), job.grid, record(settings, model))
    report = cluster.run(job, range(len(job.grid)), results, progress=False, workers=0)
    results.finish()
    return (report, *read(out))


def warning(report: cluster.Report, settings: Settings) -> str | None:
    return sampling_warning(settings, parse_grid(SPEEDS), report.sparse, report.cases,
                            report.sparsest)


def test_kinematics_cases_sampled_too_sparsely_are_counted(tmp_path):
    # 0.1 s at 101 instants, 1000 a second: 200, 50, 28.6 and 20 a revolution
    settings = Settings("kinematics", 0.1, steps=101)
    report, _, _ = sweep(tmp_path, settings)
    assert report.sparse == 2
    s = report.sparsest
    assert s is not None and (s.case, s.driver) == (3, "motor")
    assert s.per_turn == pytest.approx(20.0, rel=1e-12)
    assert s.rate == pytest.approx(100.0 * math.pi, rel=1e-12)
    text = warning(report, settings)
    assert text is not None and text.startswith(f"{SPARSE}: motor turns at 3000 rpm")
    assert "case 3 (drivers.motor.speed=3000.0 rpm) has 20 samples a revolution" in text
    assert "2 of the 4 cases run" in text
    # 36 a revolution at 5 revolutions in 0.1 s: 5 * 36 intervals
    assert "Use steps=181 or more" in text  # from Python (the command: --steps 181, below)


@pytest.mark.parametrize("steps, sparse", [(181, 0), (180, 1)])
def test_the_steps_asked_for_are_just_enough(tmp_path, steps, sparse):
    report, _, _ = sweep(tmp_path, Settings("kinematics", 0.1, steps=steps))
    assert report.sparse == sparse


def test_turns_give_every_case_the_same_samples_a_revolution(tmp_path):
    settings = Settings("kinematics", revolutions=10.0, steps=101)
    report, _, _ = sweep(tmp_path, settings)
    assert report.sparse == 4
    assert report.sparsest is not None
    assert report.sparsest.per_turn == pytest.approx(10.0, rel=1e-12)
    assert "Use steps=361 or more" in (warning(report, settings) or "")
    report, _, _ = sweep(tmp_path, Settings("kinematics", revolutions=10.0, steps=361))
    assert report.sparse == 0


def test_sparse_peaks_read_low_and_the_steps_asked_for_mend_them(tmp_path):
    """At 20 samples a revolution the fastest case's peaks read low, its motor torque by
    more than a sine's 1 - cos(pi / 20) (the harmonics the warning names); at the --steps
    the warning asks for (36 a revolution) every peak is within 1 % of a sweep at 360 a
    revolution (PEAK_SAMPLES: the slider-crank's within 0.8 %)."""
    runs = [sweep(tmp_path, Settings("kinematics", 0.1, steps=k)) for k in (101, 181, 1801)]
    header = runs[0][1]
    peaks = [i for i, h in enumerate(header) if h.startswith("peak:")]
    sparse, enough, dense = (np.array([floats([r[i] for i in peaks]) for r in rows])
                             for _, _, rows in runs)
    motor = [header[i] for i in peaks].index("peak:motor.M")
    assert np.all(sparse <= dense * (1 + 1e-9)) and np.all(enough <= dense * (1 + 1e-9))
    low = 1 - sparse[3, motor] / dense[3, motor]
    assert low > 1 - math.cos(math.pi / 20)
    assert 0.065 < low < 0.075  # docs/sweeps.md: "7 % low at 20 a revolution"
    assert np.all(enough >= 0.99 * dense)


def test_simulate_cases_are_checked_at_their_fps(tmp_path):
    settings = Settings("simulate", 0.05, fps=60.0)
    report, _, _ = sweep(tmp_path, settings)
    assert report.sparse == 4  # 60 fps is 12 samples a revolution at 300 rpm
    assert report.sparsest is not None and report.sparsest.case == 3
    assert report.sparsest.per_turn == pytest.approx(1.2, rel=1e-12)
    text = warning(report, settings) or ""
    assert "can miss it entirely" in text and "Use fps=1800 or more" in text
    report, _, _ = sweep(tmp_path, Settings("simulate", 0.05, fps=PEAK_SAMPLES * 50.0))
    assert report.sparse == 0


def test_a_sweep_without_a_turning_driver_has_no_such_warning(tmp_path):
    report, _, _ = sweep(tmp_path, Settings("simulate", 0.05), SLIDER.read_text(),
                         ["bodies.rod.mass=0.3:1.2:2"])
    assert report.cases == 2 and report.sparse == 0 and report.sparsest is None


def test_the_command_line_says_it(tmp_path):
    model = tmp_path / "driven.yaml"
    model.write_text(driven_text("600 rpm"))
    argv = ["sweep", str(model), "--run", "kinematics", "--set", SPEEDS[0], "--t-end", "0.1",
            "--workers", "0"]
    # 101 instants were the default; now the default samples each case as mbody
    # kinematics does, 360 a revolution, which needs no warning
    p = mbody_cli(*argv, "--steps", "101", "-o", str(tmp_path / "a.csv"))
    assert p.returncode == 0, p.stderr
    assert f"mbody: warning: {SPARSE}: motor turns at 3000 rpm" in p.stderr
    assert "Use --steps 181 or more" in p.stderr
    p = mbody_cli(*argv, "--steps", "181", "-o", str(tmp_path / "b.csv"))
    assert p.returncode == 0 and SPARSE not in p.stderr, p.stderr
    p = mbody_cli(*argv, "-o", str(tmp_path / "c.csv"))
    assert p.returncode == 0 and SPARSE not in p.stderr, p.stderr


# == the default sampling: mbody kinematics' ==================================================

def _sine_driven() -> str:
    """The driven slider-crank whose crank rocks, 0.5 sin(3 t) rad: no constant rate."""
    return driven_text().replace("speed: 100}", 'angle: "0.5*sin(3*t)"}')


@pytest.mark.parametrize(("text", "varied", "values", "t_end"), [
    (driven_text("600 rpm"), "drivers.motor.speed", ["300 rpm", "1234 rpm"], 0.1),
    (_sine_driven(), "bodies.rod.mass", [0.4, 0.8], 0.5),
], ids=["a turning crank", "a rocking crank"])
def test_by_default_each_case_is_sampled_as_mbody_kinematics_samples_it(tmp_path, text, varied,
                                                                        values, t_end):
    """F15 of review R4: a kinematics sweep sampled every case at 101 instants, mbody
    kinematics 360 times a revolution of the first driver (else 100 a second), so their
    peaks differed. Now each case's instants are the single run's (`default_fps` of the
    case, at its own speed) and its peaks are the single run's: the same compiled
    evaluation of the same states, to rounding (1e-12 of the peak: the states themselves
    agree to Newton's tolerance, a few ulps). At 1234 rpm, 0.1 s is 740.4 samples of
    1/7404 s: the sweep adds the end itself, so that final: is at t = 0.1 s, where the
    crank has turned 2 pi 1234/60 x 0.1 rad from the file's 45 degrees."""
    path = tmp_path / "m.yaml"
    path.write_text(text)
    model = mbody.load(path)
    result = mbody.run_sweep(path, {varied: values}, tmp_path / "k.csv", run="kinematics",
                             t_end=t_end, workers=0)
    assert result.failed == 0 and result.warnings == [], result.errors
    turning = revolution(model) is not None
    assert parse(result.settings)["steps"] == ("360 a turn" if turning else "100 a second")
    for k, value in enumerate(values):
        case = model.with_values({varied: value})
        fps = default_fps(revolution(case))
        if turning:  # one sample a degree of the crank at the case's speed
            assert fps == pytest.approx(SAMPLES_A_TURN * float(value.split()[0]) / 60.0,
                                        rel=1e-12)
        else:
            assert fps == DEFAULT_FPS
        run = mbody.kinematic_run(case, t_end, fps)
        for label, peak in zip(run.reaction_labels, np.abs(run.reactions).max(axis=0),
                               strict=True):
            assert result.column(f"peak:{label}")[k] == pytest.approx(peak, rel=1e-12), label
        q = mbody.kinematics(case, t_end).quaternion[0]  # the crank's, about z
        theta = result.column("final:crank.theta")[k]
        assert theta == pytest.approx(math.remainder(2 * math.atan2(q[3], q[0]), 2 * math.pi),
                                      abs=1e-9)
        if turning:  # from the file's pose, at the case's speed
            q0 = case.initial.quaternion[0]
            turned = (2 * math.atan2(q0[3], q0[0])
                      + 2 * math.pi * float(value.split()[0]) / 60.0 * t_end)
            assert theta == pytest.approx(math.remainder(turned, 2 * math.pi), abs=1e-9)


def test_a_default_sampling_too_long_is_a_failed_case(tmp_path):
    """360 a revolution at 600 rpm over 300 s is 1 080 001 instants, beyond what --steps
    takes: the case fails and says what to give, before any memory is spent."""
    path = tmp_path / "m.yaml"
    path.write_text(driven_text("600 rpm"))
    result = mbody.run_sweep(path, {"bodies.rod.mass": [0.4, 0.8]}, tmp_path / "k.csv",
                             run="kinematics", t_end=300.0, workers=0)
    assert result.errors == ["an end of 300 s at 3600 samples a second (mbody kinematics' "
                             "sampling) is 1 080 001 instants; at most 1 000 000 a case: "
                             "give steps, or an earlier end"] * 2  # Python's spelling


def test_the_help_says_the_default_sampling():
    """The commands' help texts are written at start-up, without importing the runs: they
    say the numbers `default_fps` uses."""
    options = {}
    for command, flag in (("kinematics", "--fps"), ("sweep", "--steps")):
        parser = build_parser()._subparsers._group_actions[0].choices[command]
        options[command] = next(a.help for a in parser._actions if flag in a.option_strings)
    assert f"{SAMPLES_A_TURN} per revolution" in options["kinematics"]
    assert f"else {DEFAULT_FPS:g})" in options["kinematics"]
    assert f"{SAMPLES_A_TURN} a revolution" in options["sweep"]
    assert f"else {DEFAULT_FPS:g} a second" in options["sweep"]

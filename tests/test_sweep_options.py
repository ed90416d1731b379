"""`mbody sweep` and `mbody.run_sweep` (review R7, findings 2, 11 and 15): a sweep that
needs Dask where Dask is not installed is refused before any case runs, leaving nothing
behind; the summary line's counts add up (the pilot cases run here to time the others
are said, words agree with their counts); an option that does not apply to the run is
refused, naming the option, the run and the runs it goes with, and ``--fps`` of a
``kinematics`` run samples as ``mbody kinematics --fps`` does."""

from __future__ import annotations

import csv
import inspect
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import build_parser
from mbody.errors import MbodyError
from mbody.simulate.peaks import PEAK_SAMPLES
from mbody.simulate.simulation import simulate
from mbody.sweep import cluster, runs
from tests.test_cli_options import run

ROOT = Path(__file__).resolve().parent.parent
PENDULUM = ROOT / "models" / "pendulum.yaml"
DRIVEN = ROOT / "models" / "slider_crank_driven.yaml"
"""Its crank at 600 rpm: a turn is 0.1 s."""


# -- R7-15: without Dask, refused before any case ---------------------------------------

@pytest.fixture
def no_dask(monkeypatch):
    """As if the ``sweep`` extra were not installed: ``import dask.distributed`` (and
    ``distributed``) fail, as an entry None in `sys.modules` makes them; and every case
    run is counted."""
    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    monkeypatch.setitem(sys.modules, "distributed", None)
    ran: list[int] = []
    real = cluster.run_chunk

    def counted(job, indices):
        ran.extend(indices)
        return real(job, indices)

    monkeypatch.setattr(cluster, "run_chunk", counted)
    return ran


NO_DASK = ("sweeps run on Dask (dask.distributed): pip install 'mbody[sweep]' (or "
           "{workers} to run them in this process)")


@pytest.mark.parametrize("extra", [[], ["--workers", "2"], ["--chunk", "1"],
                                   ["--scheduler", "tcp://127.0.0.1:1"]],
                         ids=["default", "workers", "chunk", "scheduler"])
def test_without_dask_a_sweep_is_refused_before_any_case(capsys, tmp_path, no_dask, extra):
    """R7-15: the pilot case ran, was journalled into OUT.partial, and only then did the
    command say it needs Dask; the next run kept that row as 'from an earlier run'."""
    out = tmp_path / "bs2.csv"
    code, stdout, err = run(capsys, "sweep", PENDULUM, "--set", "bodies.rod.mass=1,2,3",
                            "--out", out, "--quiet", *extra)
    assert code == 2 and stdout == ""
    assert err == f"mbody: error: {NO_DASK.format(workers='--workers 0')}\n"
    assert no_dask == [] and list(tmp_path.iterdir()) == []
    # as the message says: the same sweep in this process runs every case, keeps none
    code, stdout, err = run(capsys, "sweep", PENDULUM, "--set", "bodies.rod.mass=1,2,3",
                            "--out", out, "--quiet", "--workers", "0")
    assert code == 0 and err == ""
    assert stdout.startswith(f"wrote {out}: 3 cases, 3 run now\n")
    assert sorted(no_dask) == [0, 1, 2]


def test_without_dask_run_sweep_is_refused_before_any_case(tmp_path, no_dask):
    out = tmp_path / "py.csv"
    with pytest.raises(MbodyError) as err:
        mbody.run_sweep(PENDULUM, {"bodies.rod.mass": [1, 2, 3]}, out, workers=2)
    assert str(err.value) == NO_DASK.format(workers="workers=0")
    assert no_dask == [] and list(tmp_path.iterdir()) == []


def test_without_dask_a_sweep_that_needs_no_cluster_runs(tmp_path, no_dask):
    """One case to run is the pilot, run here: no cluster is started, Dask is not needed
    (as before); nor with workers=0, whatever the count."""
    one = mbody.run_sweep(PENDULUM, {"bodies.rod.mass": [1]}, tmp_path / "one.csv")
    assert (one.ran, one.failed, one.report.pilot, one.report.chunks) == (1, 0, 1, 0)
    here = mbody.run_sweep(PENDULUM, {"bodies.rod.mass": [1, 2, 3]}, tmp_path / "here.csv",
                           workers=0)
    assert here.ran == 3 and here.failed == 0 and sorted(no_dask) == [0, 0, 1, 2]


# -- R7-2: the summary line adds up -------------------------------------------------------

def test_the_summary_says_the_pilot_and_counts_its_words(tmp_path):
    """Three cases: one run first to time them (the pilot), then the two left in one chunk
    here; pilot and chunks' cases add up to the cases. One case: the pilot only."""
    result = mbody.run_sweep(PENDULUM, {"bodies.rod.mass": [1, 2, 3]}, tmp_path / "p.csv",
                             workers=0)
    r = result.report
    assert (r.cases, r.pilot, r.chunks, r.chunk) == (3, 1, 1, 2)
    text = r.text()
    assert text.startswith("3 cases in ")
    assert "(1 pilot case, then 1 chunk of up to 2 cases; this process spent " in text
    assert "(s)" not in text
    one = mbody.run_sweep(PENDULUM, {"bodies.rod.mass": [1]}, tmp_path / "o.csv", workers=0)
    assert one.report.text().startswith("1 case in ")
    assert "on this process (1 pilot case, no chunks; " in one.report.text()
    # a chunk size given: no pilot
    given = mbody.run_sweep(PENDULUM, {"bodies.rod.mass": [1, 2, 3]}, tmp_path / "g.csv",
                            workers=0, chunk=1)
    assert given.report.pilot == 0
    assert "on this process (3 chunks of up to 1 case; this process spent " in \
        given.report.text()


@pytest.mark.parametrize(("fields", "said"), [
    ({"cases": 3, "pilot": 1, "chunks": 2, "chunk": 1, "workers": 2,
      "where": "a local cluster of 2 worker processes", "start": 0.5, "wall": 1.0},
     "3 cases in 1.0 s on a local cluster of 2 worker processes (1 pilot case here, then 2 "
     "chunks of up to 1 case on the workers; the workers spent "),
    ({"cases": 5, "pilot": 3, "chunks": 1, "chunk": 2, "workers": 1,
      "where": "a local cluster of 1 worker process", "start": 0.5, "wall": 1.0, "lost": 1},
     "5 cases in 1.0 s on a local cluster of 1 worker process (3 pilot cases here, then 1 "
     "chunk of up to 2 cases on the worker; the worker spent "),
])
def test_the_summary_of_a_cluster(fields, said):
    text = cluster.Report(**fields).text()
    assert text.startswith(said), text
    assert "(s)" not in text
    if fields.get("lost"):
        assert text.endswith("; 1 chunk lost with its worker, written as failed)")


def test_a_local_cluster_of_one_worker_is_said_in_the_singular(tmp_path):
    pytest.importorskip("distributed")
    result = mbody.run_sweep(PENDULUM, {"bodies.rod.mass": [1, 2, 3]}, tmp_path / "c.csv",
                             workers=1)
    r = result.report
    assert r.where == "a local cluster of 1 worker process"
    # the pilot's cases and the chunks' (each at most `chunk`) make the cases
    assert r.cases == 3 and r.pilot >= 1 and r.chunks >= 1
    assert r.pilot + r.chunks <= 3 <= r.pilot + r.chunks * r.chunk
    assert f"({r.pilot} pilot case" in r.text() and " on the worker; " in r.text()


# -- R7-11: an option that does not apply to the run is refused -------------------------

REFUSED = [
    (["--run", "solve", "--t-end", "1"], "--t-end", "solve",
     "--t-end goes with --run kinematics or --run simulate (the end of each case's run); "
     "the solve run is one solve of each case at its initial state"),
    (["--t-end", "1 rev"], "--t-end", "solve", None),
    (["--run", "solve", "--steps", "7"], "--steps", "solve",
     "--steps goes with --run kinematics (its instants, evenly spaced); the solve run is one "
     "solve of each case at its initial state"),
    (["--run", "solve", "--fps", "3"], "--fps", "solve",
     "--fps goes with --run kinematics or --run simulate (samples per second); the solve run "
     "is one solve of each case at its initial state"),
    (["--run", "simulate", "--t-end", "1", "--steps", "5"], "--steps", "simulate",
     "--steps goes with --run kinematics (its instants, evenly spaced); the simulate run is "
     "sampled at --fps (default 60)"),
    (["--run", "modes", "--t-end", "1"], "--t-end", "modes",
     "--t-end goes with --run kinematics or --run simulate (the end of each case's run); "
     "the modes run linearises each case at one state"),
    # every option the run does not use is named, not the first alone
    (["--run", "solve", "--t-end", "1", "--steps", "7", "--fps", "3"], "--t-end", "solve",
     "--t-end goes with --run kinematics or --run simulate (the end of each case's run); "
     "--steps goes with --run kinematics (its instants, evenly spaced); --fps goes with "
     "--run kinematics or --run simulate (samples per second); the solve run is one solve "
     "of each case at its initial state"),
    (["--run", "modes", "--fps", "30"], "--fps", "modes", None),
    (["--run", "modes", "--steps", "30"], "--steps", "modes", None),
]


@pytest.mark.parametrize(("options", "flag", "kind", "message"), REFUSED,
                         ids=[" ".join(r[0]) for r in REFUSED])
def test_an_option_the_run_does_not_use_is_refused(capsys, tmp_path, options, flag, kind,
                                                   message):
    """R7-11: `--run solve --t-end 1 --steps 7 --fps 3` ran the solves and said nothing;
    refused now as --equilibrium with another run always was, before the model is read."""
    out = tmp_path / "y9.csv"
    code, stdout, err = run(capsys, "sweep", PENDULUM, "--set", "bodies.rod.mass=1,2",
                            *options, "--out", out, "--workers", "0", "--quiet")
    assert code == 2 and stdout == "" and list(tmp_path.iterdir()) == []
    (line,) = err.splitlines()
    assert line.startswith(f"mbody: error: {flag} goes with --run ")
    assert f"the {kind} run " in line
    if message is not None:
        assert line == f"mbody: error: {message}"


@pytest.mark.parametrize(("kw", "message"), [
    ({"t_end": 1.0}, "t_end goes with run='kinematics' or run='simulate' (the end of each "
     "case's run); the solve run is one solve of each case at its initial state"),
    ({"revolutions": 1.0}, "revolutions goes with run='kinematics' or run='simulate' (the "
     "end of each case's run); the solve run is one solve of each case at its initial state"),
    ({"steps": 7}, "steps goes with run='kinematics' (its instants, evenly spaced); the "
     "solve run is one solve of each case at its initial state"),
    ({"fps": 60.0}, "fps goes with run='kinematics' or run='simulate' (samples per second); "
     "the solve run is one solve of each case at its initial state"),
    ({"run": "simulate", "t_end": 1.0, "steps": 5}, "steps goes with run='kinematics' (its "
     "instants, evenly spaced); the simulate run is sampled at fps (default 60)"),
    ({"steps": 7, "fps": 60.0}, "steps goes with run='kinematics' (its instants, evenly "
     "spaced); fps goes with run='kinematics' or run='simulate' (samples per second); the "
     "solve run is one solve of each case at its initial state"),
    ({"run": "kinematics", "t_end": 0.1, "steps": 11, "fps": 100.0},
     "steps and fps: give the kinematics run's instants one way, steps=K (K evenly spaced "
     "from 0 to the end) or fps=F (F a second, as mbody kinematics --fps samples)"),
])
def test_run_sweep_refuses_them_in_its_own_words(tmp_path, kw, message):
    with pytest.raises(MbodyError) as err:
        mbody.run_sweep(DRIVEN, {"bodies.rod.mass": [0.4, 0.8]}, tmp_path / "y.csv",
                        workers=0, **kw)
    assert str(err.value) == message
    assert list(tmp_path.iterdir()) == []


def test_steps_and_fps_together_are_refused(capsys, tmp_path):
    code, _, err = run(capsys, "sweep", DRIVEN, "--set", "bodies.rod.mass=0.4,0.8", "--run",
                       "kinematics", "--t-end", "0.1", "--steps", "11", "--fps", "100",
                       "--out", tmp_path / "b.csv", "--workers", "0")
    assert code == 2
    assert err == ("mbody: error: --steps and --fps: give the kinematics run's instants one "
                   "way, --steps K (K evenly spaced from 0 to the end) or --fps F (F a "
                   "second, as mbody kinematics --fps samples)\n")


def test_the_options_that_apply_are_taken(capsys, tmp_path):
    """What each run uses is not refused: --fps with simulate (recorded), --t-end with
    kinematics and simulate, --equilibrium with modes."""
    for options in (["--run", "simulate", "--t-end", "0.05", "--fps", "40"],
                    ["--run", "kinematics", "--t-end", "0.05", "--steps", "11"],
                    ["--run", "modes", "--equilibrium"], ["--run", "solve"]):
        out = tmp_path / f"{options[1]}.csv"
        code, _, err = run(capsys, "sweep", DRIVEN, "--set", "bodies.rod.mass=0.4,0.8",
                           *options, "--out", out, "--workers", "0", "--quiet")
        assert code == 0, err


def test_simulate_samples_at_mbody_simulate_s_default():
    """A simulate sweep without fps samples as `mbody.simulate` does by default."""
    assert inspect.signature(simulate).parameters["fps"].default == runs.SIMULATE_FPS
    assert runs.Settings("simulate", 1.0).frame_rate == runs.SIMULATE_FPS


def test_the_help_says_which_runs_need_an_end_and_take_which_option():
    parser = build_parser()._subparsers._group_actions[0].choices["sweep"]
    helps = {a.option_strings[0]: a.help for a in parser._actions if a.option_strings}
    assert "required for kinematics and simulate" in helps["--t-end"]
    assert "as mbody kinematics --fps" in helps["--fps"]
    assert all(parser.get_default(d) is None for d in ("t_end", "steps", "fps"))


def _peaks(result, k: int, traj) -> None:
    for label, peak in zip(traj.reaction_labels, np.abs(traj.reactions).max(axis=0),
                           strict=True):
        assert result.column(f"peak:{label}")[k] == pytest.approx(peak, rel=1e-12), label


@pytest.mark.parametrize("fps", [1000.0, 1234.0])
def test_kinematics_fps_samples_as_mbody_kinematics_fps(tmp_path, fps):
    """--fps F of a kinematics sweep is `mbody kinematics --fps F`'s sampling: instants
    k / F from 0 (the end added when they fall short of it, as by default), so each row's
    peaks are those of the single run at that fps, and final: is the end's. Recorded as
    fps=F, not as the default sampling."""
    model = mbody.load(DRIVEN)
    masses = [0.4, 0.8]
    result = mbody.run_sweep(model, {"bodies.rod.mass": masses}, tmp_path / "k.csv",
                             run="kinematics", t_end=0.1, fps=fps, workers=0)
    assert result.failed == 0 and result.warnings == []
    assert "; fps=" + f"{fps:g}" + ";" in result.settings and "steps=" not in result.settings
    for k, m in enumerate(masses):
        case = model.with_values({"bodies.rod.mass": m})
        _peaks(result, k, mbody.kinematic_run(case, 0.1, fps))
        q = mbody.kinematics(case, 0.1).quaternion[0]
        theta = result.column("final:crank.theta")[k]
        assert theta == pytest.approx(math.remainder(2 * math.atan2(q[3], q[0]), 2 * math.pi),
                                      abs=1e-9)
    # the default sampling is another sweep's: refused on a rerun, naming both
    with pytest.raises(MbodyError, match=r"fps=.* \(this sweep has none\)"):
        mbody.run_sweep(model, {"bodies.rod.mass": masses}, tmp_path / "k.csv",
                        run="kinematics", t_end=0.1, workers=0)


def test_kinematics_fps_too_low_is_warned_with_the_fps_to_give(capsys, tmp_path):
    """200 a second at 600 rpm is 20 samples a turn: the warning asks for --fps (the option
    given), 36 a turn of 10 turns a second."""
    code, _, err = run(capsys, "sweep", DRIVEN, "--set", "bodies.rod.mass=0.4,0.8", "--run",
                       "kinematics", "--t-end", "0.1", "--fps", "200", "--out",
                       tmp_path / "w.csv", "--workers", "0", "--quiet")
    assert code == 0
    assert f"Use --fps {PEAK_SAMPLES * 10} or more" in err and "--steps" not in err
    with open(tmp_path / "w.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[1][-1].startswith("run=kinematics; t-end=0.1; fps=200; model=")


def test_kinematics_fps_of_too_many_instants_is_a_failed_case(tmp_path):
    """2 s at 10^6 a second is 2 000 001 instants, beyond what a case takes: the case
    fails and says to lower the fps given (not the default sampling's wording)."""
    result = mbody.run_sweep(DRIVEN, {"bodies.rod.mass": [0.4, 0.8]}, tmp_path / "f.csv",
                             run="kinematics", t_end=2.0, fps=1e6, workers=0)
    assert result.errors == ["an end of 2 s at 1e6 samples a second (fps) is 2 000 001 "
                             "instants; at most 1 000 000 a case: give a lower fps (or "
                             "steps), or an earlier end"] * 2

"""sweep: one model run over a grid (or random samples) of values, on Dask."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from mbody.cli.common import (
    EXIT_OK,
    EXIT_UNMET,
    MODEL_HELP,
    bounded,
    load_model,
    output_stream,
    seconds_or_turns,
)
from mbody.sweep.limits import LIMITS

RUN_NAMES = ("solve", "kinematics", "simulate", "modes")
"""`mbody.sweep.runs.RUNS` (not imported at start-up; a test keeps them equal)."""


def limited(name: str) -> Callable[[str], float]:
    """The argparse type of `run_sweep`'s keyword `name`: its range (`LIMITS`), as
    `run_sweep` checks it."""
    limit = LIMITS[name]
    return bounded(limit.what, limit.lo, limit.hi, integer=limit.integer,
                   lo_open=limit.lo_open)


def _end_time() -> Callable[[str], tuple[str, float]]:
    """--t-end's type: seconds or turns, each in `run_sweep`'s range (``t_end``,
    ``revolutions``)."""
    seconds, turns = LIMITS["t_end"], LIMITS["revolutions"]
    return seconds_or_turns(seconds.lo, seconds.hi, lo_open=seconds.lo_open,
                            turns_max=turns.hi)


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser(
        "sweep", help="run a model over a grid of values (or random samples), on Dask",
        description="Vary values of the model file by path and run every case: a solve, "
        "the kinematic analysis with the reactions and driver efforts at each instant, a "
        "simulation, or the natural frequencies (with whether the state is an equilibrium "
        "and stable, as mbody modes says). One row per case in --out: the varied paths, "
        "then <quantity>:<label> columns (acceleration:, reaction:, final:, peak:, "
        "frequency:, growth:; steady, stable as true or false), error, and settings (the "
        "run, its settings that change the numbers, and the model's digest). Cases run on "
        "a local Dask cluster started for the command (--workers), or on an existing one "
        "(--scheduler). An interrupted "
        "sweep resumes: the same command runs only the cases not in --out yet; rows of "
        "other settings are refused (--force runs them again).")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--set", dest="grid", action="append", default=[], required=True,
                   metavar="PATH=START:STOP:COUNT",
                   help="a varied value: COUNT values from START to STOP (both included; "
                   "a unit as the file reads it: '100 rpm:3000 rpm:30'), or listed "
                   "(PATH=a,b,c); PATH=VALUE sets one value for every case; "
                   "repeatable: the cases are the grid of all of them")
    s.add_argument("--samples", type=limited("samples"), metavar="N",
                   help="N random cases instead of the grid, each value uniform in "
                   "START:STOP (or drawn from a list)")
    s.add_argument("--seed", type=limited("seed"), default=0, metavar="S",
                   help="the random samples' seed (default 0)")
    s.add_argument("--run", dest="run_kind", choices=RUN_NAMES, default="solve",
                   help="what each case computes (default solve)")
    s.add_argument("--t-end", type=_end_time(), metavar="T",
                   help="the end of each case's run, required for kinematics and simulate "
                   "(no default; refused with solve and modes): seconds, or turns of the "
                   "first driver that turns ('1 rev': one turn at each case's speed)")
    s.add_argument("--steps", type=limited("steps"), metavar="K",
                   help="kinematics only: K instants evenly spaced from 0 to the end, both "
                   "included (default: as mbody kinematics samples, 360 a revolution of "
                   "the first driver at each case's speed when it turns at a constant "
                   "rate, else 100 a second; and the end)")
    # those defaults are mbody.simulate.kinematic.default_fps's (a test keeps them equal)
    s.add_argument("--fps", type=limited("fps"), metavar="F",
                   help="simulate: samples per second (default 60); kinematics: F samples "
                   "a second from 0, as mbody kinematics --fps (and the end), instead of "
                   "--steps")
    s.add_argument("--equilibrium", action="store_true",
                   help="modes only: linearise each case about the static equilibrium "
                   "nearest its initial pose, as mbody modes --equilibrium (Newton's "
                   "method; stable or not); without it, about the initial state, which may "
                   "not be one")
    s.add_argument("--out", "-o", dest="output", required=True, metavar="FILE",
                   help="the results: .csv or .parquet (an unfinished one resumes)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="an existing Dask cluster's scheduler, tcp://HOST:PORT (default: a "
                   "local cluster started and stopped by the command)")
    s.add_argument("--workers", type=limited("workers"), metavar="N",
                   help="the local cluster's worker processes (default: one per core); 0 "
                   "runs the cases in this process, without Dask")
    s.add_argument("--chunk", type=limited("chunk"), metavar="N",
                   help="cases per chunk sent to a worker (default: measured, "
                   "about 2 s of work)")
    s.add_argument("--quiet", action="store_true", help="no progress bar (there is one only "
                   "on a terminal)")
    s.add_argument("--force", action="store_true",
                   help="run again, and replace, the rows of --out (and its journal) that "
                   "are not this sweep's: computed with other settings (--run, --t-end, "
                   "--steps, --fps, --equilibrium, the model's content) or other values, "
                   "or written by an mbody that did not record the settings; without it "
                   "such an output is refused. --out is never the model file, even so")
    # --out is read back to resume, with the model: --force never lets it be the model
    s.set_defaults(run=sweep, output_resumed=("--out",),
                   keywords={"values": "--set", "run": "--run", "revolutions": "--t-end",
                             "out": "--out"})


def sweep(a: argparse.Namespace) -> int:
    """`mbody.sweep.study.run_sweep` with the command's arguments, and what it says."""
    from mbody.sweep.runs import Settings, check_run
    from mbody.sweep.study import SweepInterrupted, check_request, run_sweep

    t_end, revs = None, None
    if a.t_end is not None:
        unit, x = a.t_end
        t_end, revs = (x, None) if unit == "s" else (None, x)
    check_request(a.grid, a.output, a.samples, a.seed)  # before the model file is read
    check_run(Settings(a.run_kind, t_end, revs, a.steps, a.fps, a.equilibrium))
    model = load_model(a.model)
    say = output_stream(a.output)
    try:
        result = run_sweep(model, a.grid, a.output, run=a.run_kind, t_end=t_end,
                           revolutions=revs, steps=a.steps, fps=a.fps,
                           equilibrium=a.equilibrium, samples=a.samples, seed=a.seed,
                           workers=a.workers, scheduler=a.scheduler, chunk=a.chunk,
                           progress=sys.stderr.isatty() and not a.quiet, force=a.force)
    except SweepInterrupted as exc:
        sys.stderr.write(f"mbody: interrupted: {exc.kept} of {exc.cases} cases kept in "
                         f"{exc.journal}; the same command resumes\n")
        raise
    failed = result.failed
    notes = [f"{result.kept} kept from an earlier run with the same settings"] \
        if result.kept else []
    if result.replaced:
        notes.append(f"{result.replaced} earlier rows of other settings or values "
                     "replaced, as --force asks")
    print(f"wrote {result.path}: {len(result.rows)} cases, {result.ran} run now"
          + (f", {failed} failed (see their error column)" if failed else "")
          + (f" ({'; '.join(notes)})" if notes else ""), file=say)
    if result.ran:
        print(result.report.text(), file=say)
    for warning in result.warnings:
        sys.stderr.write(f"mbody: warning: {warning}\n")
    if result.rows and failed == len(result.rows):  # nothing computed: say so, exit 1
        case, first = next((r[0], e) for r, e in zip(result.rows, result.errors,
                                                      strict=True))
        sys.stderr.write(f"mbody: cannot solve: every case failed; case {case}: {first}\n")
        return EXIT_UNMET
    return EXIT_OK

"""sweep: one model run over a grid (or random samples) of values, on Dask."""

from __future__ import annotations

import argparse
import sys
import uuid

from mbody.cli.common import (
    EXIT_OK,
    EXIT_UNMET,
    MODEL_HELP,
    bounded,
    load_model,
    output_stream,
    seconds_or_turns,
)
from mbody.errors import MbodyError

RUN_NAMES = ("solve", "kinematics", "simulate", "modes")
"""`mbody.sweep.runs.RUNS` (not imported at start-up; a test keeps them equal)."""


UNRECORDED = {"kinematics": "--steps", "simulate": "--fps"}
"""The runs whose settings (besides --t-end) change their numbers but not their columns,
so that an output does not say which were used: the setting that is not --t-end."""


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser(
        "sweep", help="run a model over a grid of values (or random samples), on Dask",
        description="Vary values of the model file by path and run every case: a solve, "
        "the kinematic analysis with the reactions and driver efforts at each instant, a "
        "simulation, or the natural frequencies (with whether the state is an equilibrium "
        "and stable, as mbody modes says). One row per case in --out: the varied paths, "
        "then <quantity>:<label> columns (acceleration:, reaction:, final:, peak:, "
        "frequency:; steady, stable) and error. Cases run on a local Dask cluster started "
        "for the command (--workers), or on an existing one (--scheduler). An interrupted "
        "sweep resumes: "
        "the same command runs only the cases not in --out yet.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--set", dest="grid", action="append", default=[], required=True,
                   metavar="PATH=START:STOP:COUNT",
                   help="a varied value: COUNT values from START to STOP (both included; "
                   "a unit as the file reads it: '100 rpm:3000 rpm:30'), or listed "
                   "(PATH=a,b,c); PATH=VALUE sets one value for every case; "
                   "repeatable: the cases are the grid of all of them")
    s.add_argument("--samples", type=bounded("a number of cases", 1, 1e8, integer=True),
                   metavar="N", help="N random cases instead of the grid, each value "
                   "uniform in START:STOP (or drawn from a list)")
    s.add_argument("--seed", type=bounded("a seed", 0, 2**63 - 1, integer=True), default=0,
                   metavar="S", help="the random samples' seed (default 0)")
    s.add_argument("--run", dest="run_kind", choices=RUN_NAMES, default="solve",
                   help="what each case computes (default solve)")
    s.add_argument("--t-end", type=seconds_or_turns(0.0, 1e9, lo_open=True), metavar="T",
                   help="kinematics, simulate: the end, in seconds or in turns of the first "
                   "driver that turns ('1 rev': one turn at each case's speed)")
    s.add_argument("--steps", type=bounded("a number of instants", 2, 1e6, integer=True),
                   default=101, metavar="K",
                   help="kinematics: instants from 0 to the end, both included (default 101)")
    s.add_argument("--fps", type=bounded("samples per second", 0.0, 1e6, lo_open=True),
                   default=60.0, metavar="F", help="simulate: samples per second (default 60)")
    s.add_argument("--equilibrium", action="store_true",
                   help="modes: linearise each case about the static equilibrium nearest its "
                   "initial pose, as mbody modes --equilibrium (Newton's method; stable or "
                   "not); without it, about the initial state, which may not be one")
    s.add_argument("--out", "-o", dest="output", required=True, metavar="FILE",
                   help="the results: .csv or .parquet (an unfinished one resumes)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="an existing Dask cluster's scheduler, tcp://HOST:PORT (default: a "
                   "local cluster started and stopped by the command)")
    s.add_argument("--workers", type=bounded("a number of worker processes", 0, 4096,
                                             integer=True), metavar="N",
                   help="the local cluster's worker processes (default: one per core); 0 "
                   "runs the cases in this process, without Dask")
    s.add_argument("--chunk", type=bounded("a number of cases", 1, 1e8, integer=True),
                   metavar="N", help="cases per chunk sent to a worker (default: measured, "
                   "about 2 s of work)")
    s.add_argument("--quiet", action="store_true", help="no progress bar (there is one only "
                   "on a terminal)")
    s.set_defaults(run=sweep)


def sweep(a: argparse.Namespace) -> int:
    from mbody.model.values import edits, entry_names
    from mbody.sweep import cluster
    from mbody.sweep.grid import parse_grid
    from mbody.sweep.modes import not_steady_warning
    from mbody.sweep.runs import Job, Settings, check_settings, columns, sampling_warning
    from mbody.sweep.table import Results, output_format

    kind = a.run_kind
    output_format(a.output)
    grid = parse_grid(a.grid, a.samples, a.seed)
    if a.samples is None and a.seed:
        raise MbodyError("--seed goes with --samples (a grid has no randomness)")
    model = load_model(a.model)
    if grid.fixed:
        model = model.with_values(grid.fixed)
    if model.source is None:  # pragma: no cover - every model a command reads has one
        raise MbodyError("this model has no document to set values in")
    # every path names something in the file, before any case runs
    edits(model.source.read(), [(p, None) for p in grid.paths], entry_names(model))
    t_end, revs = None, None
    if a.t_end is not None:
        unit, x = a.t_end
        t_end, revs = (x, None) if unit == "s" else (None, x)
    settings = Settings(kind, t_end, revs, a.steps, a.fps, a.equilibrium)
    check_settings(model, settings)
    results = Results(a.output, columns(model, settings), grid)
    todo = [k for k in range(len(grid)) if k not in results.rows]
    job = Job(model.source, grid, settings, uuid.uuid4().hex)
    say = output_stream(a.output)
    try:
        report = cluster.run(job, todo, results, scheduler=a.scheduler, workers=a.workers,
                             chunk=a.chunk,
                             progress=sys.stderr.isatty() and not a.quiet)
    except KeyboardInterrupt:
        sys.stderr.write(f"mbody: interrupted: {len(results.rows)} of {len(grid)} cases kept "
                         f"in {results.journal}; the same command resumes\n")
        raise
    path = results.finish()
    failed = sum(1 for r in results.rows.values() if r[-1])
    kept = len(results.rows) - len(todo)
    print(f"wrote {path}: {len(results.rows)} cases, {len(todo)} run now"
          + (f", {failed} failed (see their error column)" if failed else "")
          # the output records the grid's values, not the run's settings: a rerun with
          # another --t-end keeps the earlier rows as they are, so say so
          + (f" ({kept} kept as the earlier run made them: the output does not record "
             f"--t-end or {UNRECORDED[settings.run]}, so other values need another --out)"
             if kept and settings.run in UNRECORDED else ""),
          file=say)
    if todo:
        print(report.text(), file=say)
    for warning in (not_steady_warning(results.header, results.rows.values(), a.equilibrium),
                    sampling_warning(settings, grid, report.sparse, report.cases,
                                     report.sparsest)):
        if warning:
            sys.stderr.write(f"mbody: warning: {warning}\n")
    if results.rows and failed == len(results.rows):  # nothing computed: say so, exit 1
        first = results.rows[min(results.rows)][-1]
        sys.stderr.write(f"mbody: cannot solve: every case failed; case {min(results.rows)}: "
                         f"{first}\n")
        return EXIT_UNMET
    return EXIT_OK

"""kinematics: a driven mechanism's motion over time, and the reactions and drivers'
efforts it takes."""

from __future__ import annotations

import argparse

from mbody.cli.common import (
    EXIT_OK,
    MODEL_HELP,
    add_axes_option,
    bounded,
    load_model,
    output_stream,
    output_suffix,
    seconds,
    seconds_or_turns,
)
from mbody.errors import MbodyError, given_twice


def register(sub: argparse._SubParsersAction) -> None:
    from mbody.cli.sim import FPS_MAX, T_END_MAX

    s = sub.add_parser(
        "kinematics", help="a driven mechanism's motion, reactions and drivers' efforts "
        "over time (no integration)",
        description="Move MODEL by its drivers: at each sample time the positions that "
        "close every joint and driver (Newton's method from the previous sample, on the "
        "branch of the file's pose), the velocities and accelerations they impose, and the "
        "reactions and drivers' efforts that take them (kinetostatics). Prints each "
        "reaction's and effort's peak and an energy check, and with --at or --every their "
        "values at the instants asked (each solved there); saves the run with -o in the "
        "format plot, animate, export and report read, and a table with --csv. For a fully "
        "driven mechanism this is its motion; a partly driven one needs 'mbody simulate'.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--t-end", type=seconds_or_turns(-T_END_MAX, T_END_MAX),
                   default=None, metavar="T",
                   help="the run's end, s ('0.5', '500 ms'), or turns after --t-start of "
                   "the first driver "
                   "when it turns at a constant rate ('1 rev', as sweep's --t-end) "
                   "(default: one such turn, else 1 s); the samples are --t-start + k/fps, "
                   "and a warning names the last one when it falls before T")
    s.add_argument("--t-start", type=seconds("a number of seconds", -T_END_MAX, T_END_MAX),
                   default=0.0, metavar="SECONDS", help="the first sample's time, s "
                   "('0.01', '10 ms'; default 0)")
    s.add_argument("--fps", type=bounded("a number of samples per second", 0, FPS_MAX,
                                         lo_open=True),
                   default=None, metavar="N", help="samples per second (default: 360 per "
                   "revolution of a constant-rate driver, one a degree; else 100)")
    # those defaults are mbody.simulate.kinematic.default_fps's (a test keeps them equal)
    s.add_argument("--point", action="append", default=[], metavar="NAME=BODY:X,Y[,Z]",
                   help="a body point to follow (repeatable), in the body's axes from its "
                   "mass centre, e.g. --point P=coupler:0.1,0.05; saved with the run "
                   "(series 'point:NAME')")
    s.add_argument("--at", action="append", default=[], metavar="[DRIVER=]VALUE",
                   help="print every reaction and driver's effort at this instant, solved "
                   "there (not interpolated): a value of the first driver's coordinate with "
                   "its unit ('90 deg', '0.25 rev', '20 mm'; an angle modulo a turn, at the "
                   "first time the run reaches it), another driver's with DRIVER=, or a time "
                   "('0.01 s', '10 ms'); repeatable")
    s.add_argument("--every", "--table", metavar="STEP", default=None,
                   help="print the same as a table over one cycle, a row every STEP of the "
                   "first driver's coordinate ('30 deg': 0, 30, ... 330 deg) or of time "
                   "('0.005 s')")
    s.add_argument("--csv", metavar="FILE.csv",
                   help="write the table as CSV (units in the header): the rows of --at or "
                   "--every when given, else every sample of the run")
    s.add_argument("-o", "--output", metavar="RUN.npz",
                   help="save the run here (.npz; read with mbody.Trajectory.load)")
    s.add_argument("--json", action="store_true",
                   help="the summary as JSON (samples, peaks, energy check, the rows of "
                   "--at or --every)")
    add_axes_option(s)
    s.set_defaults(run=kinematics)


def parse_points(pairs: list[str]) -> dict[str, tuple[str, list[float]]]:
    """``["P=coupler:0.1,0.05"]`` -> ``{"P": ("coupler", [0.1, 0.05])}``."""
    from mbody.simulate.kinematic import body_point

    out: dict[str, tuple[str, list[float]]] = {}
    for p in pairs:
        name, sep, rest = p.partition("=")
        body, sep2, _ = rest.partition(":")
        if not (sep and sep2 and name.strip() and body.strip()):
            raise MbodyError(f"--point expects NAME=BODY:X,Y[,Z] (for example "
                             f"P=coupler:0.1,0.05), got {p!r}")
        if name.strip() in out:
            raise given_twice(f"--point {name.strip()}")
        out[name.strip()] = body_point(rest, f"--point {name}")
    return out


def kinematics(a: argparse.Namespace) -> int:
    import sys

    from mbody.cli.sim import check_samples, end_time
    from mbody.model.reprs import count
    from mbody.simulate.instants import Instants, asked_instants, kinematic_at
    from mbody.simulate.kinematic import default_sampling, kinematic_run, revolution, summary
    from mbody.util import jsontext
    from mbody.util.atomic import ensure_writable

    points = parse_points(a.point)
    output_suffix(a.output, "-o", "a run file (.npz)", (".npz",), a.force)
    output_suffix(a.csv, "--csv", "a CSV table", (".csv",), a.force)
    if a.at and a.every is not None:
        raise MbodyError("--at and --every: give the instants one way (--at for some, "
                         "--every for a table over one cycle)")
    model = load_model(a.model)
    at = a.at or None
    if at or a.every is not None:  # a bad value is reported before the run
        asked_instants(model, at, every=a.every)
    turn = revolution(model)
    t_end = end_time(a.t_end, a.t_start, turn)
    fps = a.fps if a.fps is not None else default_sampling(model)[1]
    if t_end <= a.t_start:
        raise MbodyError(f"--t-end {t_end:g} is not after --t-start {a.t_start:g}")
    check_samples(t_end - a.t_start, fps)
    for target in (a.output, a.csv):  # fail now, not after the run
        if target:
            ensure_writable(target)
    traj = kinematic_run(model, t_end, fps, t_start=a.t_start, points=points, axes=a.axes)
    rows = (kinematic_at(model, at, every=a.every, axes=a.axes, run=traj)
            if at or a.every is not None else None)
    if a.output:
        traj.save(a.output)
    if a.csv:
        (rows or Instants.of_run(model, traj)).write_csv(a.csv)
    stream = output_stream(a.output, a.csv)
    if a.json:
        i = traj.info
        jsontext.dump({"model": model.name, "samples": i["samples"], "t_end": i["t_end"],
                       "fps": i["fps"], "newton_steps": i["newton_steps"],
                       "backward_error": i["backward_error"], "reaction_axes": a.axes,
                       "peaks": i["peaks"], "driver_work": i["driver_work"],
                       "load_work": i["load_work"], "energy_change": i["energy_change"],
                       "energy_balance_residual": i["energy_balance_residual"],
                       "power_balance_residual": i["power_balance_residual"],
                       "warnings": list(i.get("warnings", ())),
                       **({"at": rows.json()} if rows is not None else {}),
                       "output": a.output, "csv": a.csv},
                      stream if a.output or a.csv else sys.stdout)
        return EXIT_OK
    print(summary(traj, a.output), file=stream)
    if rows is not None:
        axes = "world axes" if a.axes == "world" else "joint-frame components"
        print(f"at the instants asked ({axes}; each solved there, carried from the run's "
              f"sample before it):\n{rows.text()}", file=stream)
    if a.csv:
        print(f"wrote {a.csv} ({count(len(rows if rows is not None else traj.t), 'row')})",
              file=stream)
    return EXIT_OK

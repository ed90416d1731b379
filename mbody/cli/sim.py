"""simulate, plot: integrate a model's motion, and plot a saved run."""

from __future__ import annotations

import argparse
import math
import sys

from mbody.cli.common import EXIT_OK, MODEL_HELP, load_model, parse_known, regular_file
from mbody.errors import MbodyError


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("simulate", help="integrate the motion (unknown reactions solved "
                       "each step)",
                       description="Integrate the Newton-Euler equations of MODEL from its "
                       "initial state. Reaction values given in the file or with --known are "
                       "applied as loads; the unknown ones are solved with the accelerations "
                       "at every step (joints held by projecting the state onto them after each "
                       "step) and stored "
                       "with the run. Prints the run summary with the drift of energy, "
                       "angular momentum and joints; saves the trajectory with -o.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--t-end", type=float, default=10.0, metavar="SECONDS",
                   help="simulated time, s (default 10)")
    s.add_argument("--fps", type=float, default=60.0,
                   help="output samples per second (default 60)")
    s.add_argument("-o", "--output", metavar="RUN.npz",
                   help="save the trajectory here (.npz; read with mbody.Trajectory.load)")
    s.add_argument("--rtol", type=float, default=None,
                   help="relative tolerance per step (default 1e-10)")
    s.add_argument("--atol", type=float, default=None,
                   help="absolute tolerance per step (default 1e-12)")
    s.add_argument("--method", default="DOP853",
                   help="integrator: DOP853 (default), RK45, RK23, Radau, BDF, LSODA")
    s.add_argument("--known", metavar="LABEL=VALUE", action="append", default=[],
                   help="a known reaction value, e.g. --known A.Fx=3 (repeatable)")
    s.add_argument("--max-steps", type=int, default=None, metavar="N",
                   help="stop with a message after N integrator steps (default 1000000; "
                   "0: no limit)")
    s.add_argument("--max-wall", type=float, default=None, metavar="SECONDS",
                   help="stop with a message after this much wall-clock time (default: no "
                   "limit)")
    s.add_argument("--progress", action="store_true",
                   help="show the progress bar on stderr even when it is not a terminal")
    s.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    s.set_defaults(run=simulate)

    s = sub.add_parser("plot", help="plot a saved run: angular velocity, energy, momentum, "
                       "drift, joint reactions", description="Plot the angular-velocity "
                       "components, kinetic energy and angular momentum of a saved run over "
                       "time, and their relative drift, in one multi-panel figure. A run "
                       "that stores joint reactions (every run of a model with joints) gets "
                       "a third row: the reaction force components (N) and moment "
                       "components (N m) over time, each along its joint-frame axis, +R on "
                       "the child (the first 12 of each kind; a kind the joints do not have, "
                       "such as the moments of a planar revolute joint, gets no panel).")
    s.add_argument("trajectory", metavar="RUN.npz",
                   help="a trajectory saved by 'mbody simulate -o'")
    s.add_argument("-o", "--output", required=True, metavar="FILE",
                   help="the figure: .png, .pdf or .svg")
    s.add_argument("--body", action="append", default=None, metavar="NAME",
                   help="bodies for the angular-velocity panel (repeatable; default the "
                   "first 6)")
    s.set_defaults(run=plot)


def simulate(a: argparse.Namespace) -> int:
    from mbody.simulate.simulation import DEFAULT_ATOL, DEFAULT_MAX_STEPS, DEFAULT_RTOL, summary
    from mbody.simulate.simulation import simulate as _simulate

    max_steps = DEFAULT_MAX_STEPS if a.max_steps is None else a.max_steps
    if max_steps < 0:
        raise MbodyError(f"--max-steps must be a whole number of steps (0: no limit), got "
                         f"{max_steps}")
    if a.max_wall is not None and not (a.max_wall > 0 and math.isfinite(a.max_wall)):
        raise MbodyError(f"--max-wall must be a positive number of seconds, got "
                         f"{a.max_wall:g}")
    model = load_model(a.model)
    if a.output:  # fail now, not after a long integration
        from mbody.io.atomic import ensure_writable

        ensure_writable(a.output)
    known = parse_known(a.known)
    traj = _simulate(model, a.t_end, a.fps,
                     rtol=DEFAULT_RTOL if a.rtol is None else a.rtol,
                     atol=DEFAULT_ATOL if a.atol is None else a.atol, method=a.method,
                     known=known,
                     progress=(a.progress or sys.stderr.isatty()) and not a.no_progress,
                     max_steps=max_steps or None, max_wall=a.max_wall)
    if a.output:
        traj.save(a.output)
    print(summary(traj, a.output))
    return EXIT_OK


def plot(a: argparse.Namespace) -> int:
    from mbody.present.plot import save_plot
    from mbody.simulate.trajectory import Trajectory

    regular_file(a.trajectory, "a run file written by 'mbody simulate -o RUN.npz'")
    traj = Trajectory.load(a.trajectory)
    save_plot(traj, a.output, a.body)
    print(f"wrote {a.output}")
    return EXIT_OK

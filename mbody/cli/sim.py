"""simulate, plot: integrate a model's motion, and plot a saved run."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from mbody.cli.common import (
    EXIT_OK,
    MODEL_HELP,
    PICTURE_SUFFIXES,
    add_axes_option,
    add_known_option,
    add_progress_options,
    bounded,
    load_model,
    number,
    output_stream,
    output_suffix,
    parse_known,
    regular_file,
    seconds,
    seconds_or_turns,
    show_progress,
)
from mbody.errors import MbodyError

if TYPE_CHECKING:
    from mbody.model.model import Model

T_END_MIN, T_END_MAX, FPS_MAX, SAMPLES_MAX = 1e-9, 1e9, 1e6, 10_000_000
"""Bounds of --t-end (s), --fps and of the samples t_end x fps gives (as
`mbody.simulate` keeps them: a run's samples are held in memory). A span below 1e-9 s
means nothing physical, and one of a few denormal seconds overflows the simulator's
step-rate estimate."""
RTOL, ATOL = (1e-13, 0.01), (1e-300, 0.01)
"""Tolerances --rtol and --atol accept: a relative tolerance below 1e-13 asks for digits
a double does not have (SciPy's integrators raise it, with a warning, to 2.2e-14); above
1 % (relative, or 0.01 absolute) a step controls nothing, and a mechanism's integration
can run away (rtol 0.5 or atol 1 on the shipped slider-crank and four-bar)."""
MAX_STEPS, MAX_WALL = 10**9, 1e7
"""Largest --max-steps (0: no limit) and --max-wall (s, 115 days)."""


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
    s.add_argument("--t-end", type=seconds_or_turns(T_END_MIN, T_END_MAX),
                   default=("s", 10.0), metavar="T",
                   help="simulated time: seconds ('2.5', '500 ms'), or turns of the first "
                   "driver when it turns at a constant rate ('2 rev', as kinematics' "
                   f"--t-end) (default 10; from {number(T_END_MIN)} to {number(T_END_MAX)}, "
                   f"and t_end x fps at most {number(SAMPLES_MAX)} samples)")
    s.add_argument("--fps", default=60.0, metavar="N",
                   type=bounded("a number of samples per second", 0, FPS_MAX, lo_open=True),
                   help=f"output samples per second (default 60; at most {number(FPS_MAX)})")
    s.add_argument("-o", "--output", metavar="RUN.npz",
                   help="save the trajectory here (.npz; read with mbody.Trajectory.load)")
    s.add_argument("--rtol", type=bounded("a relative tolerance", *RTOL), default=None,
                   metavar="REL", help=f"relative tolerance per step (default 1e-10; "
                   f"{number(RTOL[0])} to {number(RTOL[1])})")
    s.add_argument("--atol", type=bounded("an absolute tolerance", *ATOL), default=None,
                   metavar="ABS", help=f"absolute tolerance per step (default 1e-12; "
                   f"{number(ATOL[0])} to {number(ATOL[1])})")
    s.add_argument("--method", default="DOP853",
                   help="integrator: DOP853 (default), RK45, RK23, Radau, BDF, LSODA")
    add_known_option(s, "applied as a load through the run", "that varies as the run goes")
    s.add_argument("--max-steps", default=None, metavar="N",
                   type=bounded("a whole number of steps", 1, MAX_STEPS, integer=True,
                                zero="no limit"),
                   help=f"stop with a message after N integrator steps (default 1000000, "
                   f"at most {number(MAX_STEPS)}; 0: no limit)")
    s.add_argument("--max-wall", type=seconds("a number of seconds", 0, MAX_WALL, lo_open=True),
                   default=None, metavar="SECONDS",
                   help="stop with a message after this much wall-clock time (default: no "
                   f"limit; at most {number(MAX_WALL)} s)")
    add_progress_options(s)
    add_axes_option(s)
    s.set_defaults(run=simulate)

    s = sub.add_parser("plot", help="plot a saved run: angular velocity, energy, momentum, "
                       "drift, joint reactions", description="Plot the angular-velocity "
                       "components, kinetic energy and angular momentum of a saved run over "
                       "time, and their relative drift, in one multi-panel figure. A run "
                       "that stores joint reactions (every run of a model with joints) gets "
                       "a third row: the reaction force components (N) and moment "
                       "components (N m) over time, +R on the child, each along its "
                       "joint-frame axis (or with --axes world each joint's force and moment "
                       "in world axes) (the first 12 of each kind; a kind the joints do not "
                       "have, such as the moments of a planar revolute joint, gets no panel).")
    s.add_argument("trajectory", metavar="RUN.npz",
                   help="a trajectory saved by 'mbody simulate -o'")
    s.add_argument("-o", "--output", required=True, metavar="FILE",
                   help="the figure: .png, .pdf or .svg")
    s.add_argument("--body", action="append", default=None, metavar="NAME",
                   help="bodies for the angular-velocity panel (repeatable; default the "
                   "first 6)")
    s.add_argument("--against", metavar="DRIVER|time", default=None,
                   help="a run with drivers: plot the efforts and bearing loads against this "
                   "driver's coordinate (default: the first driver; degrees for an angle) or "
                   "against time")
    s.add_argument("--motion", action="store_true",
                   help="a run with drivers: plot the bodies' motion, energy and momentum "
                   "instead of the drivers' figure")
    add_axes_option(s, saved=True)
    s.set_defaults(run=plot, output_suffixes={"-o": PICTURE_SUFFIXES})


def simulate(a: argparse.Namespace) -> int:
    from mbody.simulate.simulation import DEFAULT_ATOL, DEFAULT_MAX_STEPS, DEFAULT_RTOL, summary
    from mbody.simulate.simulation import simulate as _simulate

    max_steps = DEFAULT_MAX_STEPS if a.max_steps is None else int(a.max_steps)
    unit, given = a.t_end
    if unit == "s":  # before the model is read
        check_samples(given, a.fps)
    output_suffix(a.output, "-o", "a run file (.npz)", (".npz",), a.force)
    model = load_model(a.model)
    _refuse_integrator_options(a, model)
    t_end = given if unit == "s" else turns_end(model, given)
    if unit != "s":
        check_samples(t_end, a.fps)
    if a.output:  # fail now, not after a long integration
        from mbody.util.atomic import ensure_writable

        ensure_writable(a.output)
    known = parse_known(a.known)
    traj = _simulate(model, t_end, a.fps,
                     rtol=DEFAULT_RTOL if a.rtol is None else a.rtol,
                     atol=DEFAULT_ATOL if a.atol is None else a.atol, method=a.method,
                     known=known,
                     progress=show_progress(a),
                     max_steps=max_steps or None, max_wall=a.max_wall, axes=a.axes)
    if a.output:
        traj.save(a.output)
    print(summary(traj, a.output), file=output_stream(a.output))
    return EXIT_OK


def _refuse_integrator_options(a: argparse.Namespace, model: Model) -> None:
    """A fully driven model's run is kinematic (each sample solved, nothing integrated):
    an integrator's option given for it would be ignored (review R7-17), so it is refused."""
    from mbody.solve.kinematics import fully_driven

    given = [flag for flag, value in (("--method", a.method != "DOP853" and a.method),
                                      ("--rtol", a.rtol), ("--atol", a.atol),
                                      ("--max-steps", a.max_steps), ("--max-wall", a.max_wall))
             if value is not None and value is not False]
    if given and fully_driven(model):
        raise MbodyError(f"{', '.join(given)} {'does' if len(given) == 1 else 'do'} not apply: "
                         f"{model.name!r} is fully driven, so its run is kinematic (each "
                         "sample's pose solved from the drivers, nothing integrated); leave "
                         f"{'it' if len(given) == 1 else 'them'} out (mbody kinematics MODEL "
                         "makes the same run)")


def end_time(given: tuple[str, float] | None, t_start: float, turn: float | None) -> float:
    """The last sample's time (s): `given` by --t-end in seconds or in turns of `turn`
    s each (the first driver's, when it turns at a constant rate), else one turn, else
    1 s, after `t_start`. An end in turns is held to --t-end's bound in seconds."""
    from mbody.simulate.kinematic import DEFAULT_SPAN

    if given is not None and given[0] == "s":
        return given[1]
    if turn is None:
        if given is None:
            return t_start + DEFAULT_SPAN
        raise MbodyError(f"--t-end {given[1]:g} rev: this model's first driver does not turn "
                         "at a constant rate, so a turn has no fixed time; give the end in "
                         "seconds")
    turns = given[1] if given is not None else 1.0
    t_end = t_start + turns * turn
    if not abs(t_end) <= T_END_MAX:  # a driver barely turning: 1e-90 rad/s
        said = f"--t-end {turns:g} rev" if given is not None else "the default end (a turn)"
        raise MbodyError(f"{said} is t = {t_end:.3g} s ({turns:g} x {turn:.3g} s, the first "
                         f"driver's turn); at most {T_END_MAX:g} s: give --t-end in seconds")
    return t_end


def turns_end(model, turns: float) -> float:
    """The time (s) of `turns` turns of `model`'s first driver from t = 0 (``--t-end '2
    rev'``), as kinematics reads it (`end_time`), within --t-end's range."""
    from mbody.simulate.kinematic import revolution

    if not len(model.drivers or ()):
        raise MbodyError(f"--t-end {turns:g} rev: this model has no driver, so a turn has no "
                         "fixed time; give the end in seconds")
    t_end = end_time(("rev", turns), 0.0, revolution(model))
    if t_end < T_END_MIN:
        raise MbodyError(f"--t-end {turns:g} rev is t = {t_end:.3g} s; at least "
                         f"{number(T_END_MIN)} s: give --t-end in seconds")
    return t_end


def check_samples(t_end: float, fps: float, flags: str = "--t-end x --fps") -> None:
    """Refuse a run of more than SAMPLES_MAX samples before any work (exit 2)."""
    samples = math.floor(t_end * fps + 1e-9) + 1
    if samples > SAMPLES_MAX:
        raise MbodyError(f"{flags} asks for {number(samples)} samples ({number(t_end)} s "
                         f"at {number(fps)} per second); at most {number(SAMPLES_MAX)} (give "
                         "a shorter time or fewer per second)")


def plot(a: argparse.Namespace) -> int:
    from mbody.present.plot import save_plot
    from mbody.simulate.trajectory import Trajectory
    from mbody.util.atomic import ensure_writable

    ensure_writable(a.output)  # before the figure is drawn (a second or two)
    regular_file(a.trajectory, "a run file written by 'mbody simulate -o RUN.npz'")
    traj = Trajectory.load(a.trajectory)
    save_plot(traj, a.output, a.body, against=a.against, motion=a.motion, axes=a.axes)
    print(f"wrote {a.output}", file=output_stream(a.output))
    return EXIT_OK

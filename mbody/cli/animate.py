"""animate: a self-contained HTML page of the motion, or the live meshcat viewer."""

from __future__ import annotations

import argparse
import math
import signal
import sys
import time
from pathlib import Path
from types import FrameType
from typing import Any

from mbody.cli.common import (
    EXIT_OK,
    bounded,
    number,
    output_stream,
    output_suffix,
    regular_file,
    seconds,
)
from mbody.cli.sim import T_END_MAX, T_END_MIN
from mbody.errors import MbodyError
from mbody.util.atomic import refuse_overwriting_inputs

T_END, FPS = 10.0, 60.0
"""`mbody.simulate`'s defaults, which a MODEL is simulated with (tests keep them equal;
the simulator is not imported at start-up)."""
FRAMES_MAX, FPS_MAX, HOLD_MAX = 100_000, 1000.0, 1e7
"""Most frames a page holds when a model is simulated for it (28 minutes at 60 per
second; each frame is every body's pose in the page), most frames per second, and the
longest --hold (s)."""


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser(
        "animate", help="play the motion in meshcat: an offline HTML page or the live viewer",
        description="Animate SOURCE, a run file (.npz from `mbody simulate`) or a model "
        "(simulated first). Writes a self-contained page (no server, no network) with "
        "every body drawn as its shape (or its inertia-equivalent box), a grid, and "
        "play/pause and time controls; the camera is fitted to the motion (all bodies "
        "over the whole run, and the arrows drawn), looking along the plane's normal for "
        "a planar model. With --live, serves meshcat's viewer on "
        "127.0.0.1 only until Ctrl-C.")
    s.add_argument("source", metavar="MODEL|RUN",
                   help="a model (.yaml, .xml, .urdf) or a run (.npz)")
    s.add_argument("-o", "--output", metavar="HTML",
                   help="the page to write (default: SOURCE's name with .html; with --live "
                   "a page is written only if this is given)")
    s.add_argument("--model", metavar="MODEL",
                   help="the model of a run file (default: the model file it names)")
    s.add_argument("--forces", action="store_true",
                   help="draw applied forces and gravity (m g at each mass centre) in yellow "
                   "and couples in magenta, as arrows")
    s.add_argument("--reactions", action="store_true",
                   help="draw each joint's reaction on its child (red: force at the joint "
                   "point; dark red: couple)")
    s.add_argument("--body", metavar="NAME", action="append",
                   help="draw only this body (repeatable)")
    s.add_argument("--t-end", type=seconds("a number of seconds", T_END_MIN, T_END_MAX),
                   metavar="S", help=f"seconds to simulate when SOURCE is a model (default "
                   f"{T_END:g}; refused with a run file, which plays as saved; t_end x fps "
                   f"at most {number(FRAMES_MAX)} frames)")
    s.add_argument("--fps", type=bounded("a number of frames per second", 0, FPS_MAX, lo_open=True),
                   metavar="N", help=f"frames per second when SOURCE is a model (default "
                   f"{FPS:g}; at most {number(FPS_MAX)}; refused with a run file)")
    s.add_argument("--live", action="store_true",
                   help="serve the live viewer on 127.0.0.1 and print its URL; Ctrl-C stops")
    s.add_argument("--hold", type=seconds("a number of seconds", 0, HOLD_MAX, lo_open=True),
                   metavar="S",
                   help="with --live: stop after S seconds instead of waiting for Ctrl-C "
                   f"(at most {number(HOLD_MAX)})")
    s.add_argument("--mode", type=int, metavar="K",
                   help="play mode K of the linearisation (numbered as mbody modes lists "
                   "them) instead of a simulation: three periods of its shape about the "
                   "model's initial state")
    s.add_argument("--equilibrium", action="store_true",
                   help="with --mode: about the static equilibrium nearest the initial pose")
    s.set_defaults(run=animate)


def _mode(a: argparse.Namespace):
    """(trajectory, model) of `mbody animate MODEL --mode K`."""
    from mbody.cli.common import load_model
    from mbody.present.modes import moves
    from mbody.simulate.modes import mode_trajectory
    from mbody.solve.linearize import linearize

    if a.source.lower().endswith(".npz"):
        raise MbodyError("--mode needs a model, not a run file")
    if a.t_end is not None:
        raise MbodyError("--t-end does not apply with --mode (three periods are played)")
    model = load_model(a.source)
    state = None
    if a.equilibrium:
        from mbody.solve.equilibrium import equilibrium

        state = equilibrium(model)
    lin = linearize(model, state)
    traj = mode_trajectory(lin, a.mode, fps=a.fps or FPS)
    for w in traj.info.get("warnings", []):
        print(f"mbody: warning: {w}", file=sys.stderr)
    if lin.stable is None and not a.equilibrium and not moves(lin):  # as `mbody modes`
        print("mbody: warning: so the motion played is not an oscillation about rest; "
              "--equilibrium plays the mode about the static equilibrium nearest the pose",
              file=sys.stderr)
    return traj, model


def _warn(traj: Any, run_file: bool) -> None:
    """The run's warnings on stderr, as `mbody simulate` gives them: every one of a run
    made here; of a run file's, the spin its frames alias (review R7-16: the page shows
    that spin turning slower or backwards), the others said when it was made."""
    from mbody.simulate.simulation import SPIN_WARNING

    hint = ("; this page's frames are the run file's samples: simulate the model again "
            "with that --fps" if run_file else "")
    for w in traj.info.get("warnings", []):
        if not run_file or w.startswith(SPIN_WARNING):
            print(f"mbody: warning: {w}{hint}", file=sys.stderr)


def _with_values(a: argparse.Namespace) -> tuple[Any, Any]:
    """(source, model) for `resolve`: with ``--set``, the model files read with the
    values set (`load_model`); a run file's motion is computed already."""
    if not getattr(a, "set_values", None):
        return a.source, a.model
    from mbody.cli.common import load_model

    model = load_model(a.model) if a.model else None
    if a.source.lower().endswith((".yaml", ".yml", ".xml", ".urdf")):
        return load_model(a.source), model
    from mbody.present.animate.source import is_run_file

    if not is_run_file(a.source):
        return load_model(a.source), model
    if model is None:
        raise MbodyError(f"--set changes a model's values, and {a.source} is a run whose "
                         "motion is computed already: give the model file to simulate it "
                         "with them, or --model for the loads drawn on this run")
    return a.source, model


def _stop(signum: int, frame: FrameType | None) -> None:  # SIGTERM ends --live like Ctrl-C
    raise KeyboardInterrupt


def animate(a: argparse.Namespace) -> int:
    from mbody.present.animate import LiveViewer, build_scene, page_html, resolve
    from mbody.present.animate.source import is_run_file
    from mbody.util.atomic import write_atomic

    if a.hold is not None and not a.live:
        raise MbodyError("--hold only applies with --live")
    t_end, fps = a.t_end or T_END, a.fps or FPS
    frames = math.floor(t_end * fps + 1e-9) + 1
    if frames > FRAMES_MAX:
        raise MbodyError(f"--t-end x --fps asks for {number(frames)} frames "
                         f"({number(t_end)} s at {number(fps)} per second); a page holds at "
                         f"most {number(FRAMES_MAX)} (give a shorter time or fewer per "
                         "second)")
    source = Path(a.source)
    out = a.output or (None if a.live or not source.name else source.with_suffix(".html").name)
    if out:  # fail now, not after simulating
        from mbody.util.atomic import ensure_writable

        output_suffix(out, "-o", "an HTML page", (".html", ".htm"), a.force)

        refuse_overwriting_inputs([("-o", out)], [("the input", a.source)]
                                  + ([("the model", a.model)] if a.model else []))
        ensure_writable(out)
    if not a.source.lower().endswith((".yaml", ".yml")):  # a model may come through a pipe
        regular_file(a.source, "a model (.yaml) or a run file (.npz)")
    if a.equilibrium and a.mode is None:
        raise MbodyError("--equilibrium only applies with --mode")
    if a.mode is not None:
        traj, model = _mode(a)
    else:
        run_file = Path(a.source).is_file() and is_run_file(a.source)  # else: no such file
        for flag, value in (("--t-end", a.t_end), ("--fps", a.fps)):
            if run_file and value is not None:  # review R7-17: it was ignored silently
                raise MbodyError(f"{flag} does not apply to a run file ({a.source} plays "
                                 f"as saved); simulate the model again with {flag}, or "
                                 "animate the model file itself")
        source_arg, model_arg = _with_values(a)
        traj, model = resolve(source_arg, model_arg, t_end=a.t_end, fps=a.fps)
        _warn(traj, run_file)
    extra = [b for b in model.body_names if b not in traj.body_names]
    if extra and (a.forces or a.reactions):  # loads are evaluated at the run's states
        raise MbodyError(f"the model {model.name!r} has bodies the run {a.source} does not "
                         f"have ({', '.join(extra[:6])}{' ...' if len(extra) > 6 else ''}): "
                         "its forces and reactions cannot be drawn on that run; give the "
                         "model the run was computed from")
    scene = build_scene(traj, model, forces=a.forces, bodies=a.body, reactions=a.reactions)
    what = (f"{len(scene.paths)} bod{'y' if len(scene.paths) == 1 else 'ies'}, "
            f"{scene.frames} frames, {scene.duration:g} s")
    if out:
        html = page_html(scene)
        path = write_atomic(out, html)
        print(f"wrote {path} ({len(html.encode()) / 1e6:.1f} MB: {what})",
              file=output_stream(out))
    if not a.live:
        return EXIT_OK

    previous = signal.signal(signal.SIGTERM, _stop)
    # Ctrl-C stops the viewer even when this process was started with SIGINT ignored (a
    # shell's background job, nohup): Python then leaves it ignored instead of raising
    # KeyboardInterrupt, and the viewer would only stop when killed
    previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    viewer = None
    try:
        viewer = LiveViewer()
        viewer.show(scene)
        print(f"meshcat viewer (127.0.0.1 only): {viewer.url}  ({what}; Ctrl-C stops it)",
              flush=True)
        deadline = time.monotonic() + (a.hold if a.hold is not None else float("inf"))
        while time.monotonic() < deadline:
            time.sleep(min(0.2, max(0.0, deadline - time.monotonic())))
    except KeyboardInterrupt:
        pass
    finally:
        if viewer is not None:
            viewer.close()
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)
    print("viewer stopped", file=sys.stderr)
    return EXIT_OK

"""equilibrium: a configuration at rest where every acceleration vanishes."""

from __future__ import annotations

import argparse
import sys

from mbody.cli.common import (
    EXIT_OK,
    EXIT_UNMET,
    MODEL_HELP,
    add_axes_option,
    load_model,
    seconds,
)


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser(
        "equilibrium", help="a configuration at rest where the accelerations vanish",
        description="Find a static equilibrium of MODEL near its file's pose, the drivers "
        "held where their laws put them at time --t: Newton's method in the motions the "
        "joints allow. Prints whether one was found, how far each body moved, the pose, the "
        "stiffness's eigenvalues (stable, unstable or neutral) and the reactions that carry "
        "the loads at rest. Exit 1 when none is found.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--t", type=seconds("a time in seconds", -1e9, 1e9), default=0.0,
                   metavar="T", help="time (s) at which the drivers are held and the loads "
                   "evaluated (default 0)")
    s.add_argument("--json", action="store_true", help="machine-readable output")
    add_axes_option(s)
    s.set_defaults(run=equilibrium)


def equilibrium(a: argparse.Namespace) -> int:

    from mbody.equations.assemble import assemble
    from mbody.present.text import pose_text, reaction_table_text, world_reaction_text
    from mbody.solve.equilibrium import find_equilibrium, held
    from mbody.solve.linearize import STEADY_RTOL
    from mbody.util import jsontext

    model = load_model(a.model)
    found = find_equilibrium(model, t=a.t)
    state = found.state
    # the reactions of the model as the equilibrium holds it: its drivers at their pose,
    # at rest (with the file's speeds, the state at rest would break every speed driver,
    # review R7-5); the same values, since at rest no velocity term acts
    asm = assemble(held(model, a.t), state)
    sol = asm.solve(axes=a.axes) if found.found and model.reactions else None
    if a.json:
        jsontext.dump({
            "model": model.name, "found": found.found, "iterations": found.iterations,
            "moved_m": found.moved[0], "turned_rad": found.moved[1],
            "stiffness": found.stiffness.tolist(), "stable": found.stable,
            "position": state.position.tolist(), "quaternion": state.quaternion.tolist(),
            "bodies": list(model.body_names),
            "reactions": dict(sol.reactions) if sol else {},
            "reaction_axes": a.axes}, sys.stdout)
    else:
        print(f"{model.name!r}: {found}")
    if not found.found:
        print("mbody: cannot solve: no equilibrium from the file's pose; start from a pose "
              "nearer one (the file's positions), or check that the loads can balance (a "
              "constant torque on a free wheel never does)", file=sys.stderr)
        return EXIT_UNMET
    if a.json:
        return EXIT_OK
    print(pose_text(model, state, STEADY_RTOL))
    if len(found.stiffness):
        print("stiffness eigenvalues, M^-1 K: the squared frequencies of small oscillations "
              "about it (1/s^2; negative: a direction it falls away along): "
              + ", ".join(f"{k:.6g}" for k in found.stiffness))
    if sol is not None and sol.reactions:
        print()
        print(world_reaction_text(model, sol) if sol.axes == "world"
              else reaction_table_text(asm, sol))
    return EXIT_OK

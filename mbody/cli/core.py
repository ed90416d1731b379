"""check, assemble, solve: the model, its equations and its accelerations."""

from __future__ import annotations

import argparse
import sys

from mbody.cli.common import (
    EXIT_OK,
    MODEL_HELP,
    add_axes_option,
    add_known_option,
    load_model,
    output_stream,
    output_suffix,
    parse_known,
)
from mbody.errors import MbodyError


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("check", help="validate a model and summarise it (graph, mobility)",
                       description="Validate MODEL and print its bodies, loads, joints, "
                       "reaction unknowns, body/joint graph and mobility count.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.set_defaults(run=check)

    s = sub.add_parser("assemble", help="print every body's free body and Newton-Euler pair",
                       description="For every body: its free-body list and its Newton and "
                       "Euler equations with numbers filled in and reactions named; then the "
                       "sizes of the stacked M, b, Q, G.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--body", metavar="NAME", help="only this body")
    s.add_argument("--latex", metavar="FILE", nargs="?", const="-",
                   help="write a LaTeX document (each body's pair, the stacked system) to "
                   "FILE, or to standard output without FILE")
    s.add_argument("--symbolic", action="store_true",
                   help="write each body's pair with symbols (m, I_G or I_1, w_1, loads by "
                   "name, reaction labels) instead of numbers; with --latex, as a LaTeX "
                   "document (needs sympy: the 'symbolic' extra)")
    s.add_argument("--answers-key", metavar="FILE",
                   help="write every body's rows (or --body's) as an answers file (.yaml) "
                   "that mbody verify finds all correct: the answer key, to test a grading "
                   "before giving out an assignment; --set values go in its set:; '-' for "
                   "standard output")
    s.set_defaults(run=assemble, output_suffixes={"--answers-key": (".yaml", ".yml")})

    s = sub.add_parser("solve", help="accelerations of every body and the unknown reactions",
                       description="Accelerations of every body. Reaction values given in "
                       "the file or with --known are applied as loads; the unknown ones are "
                       "solved together with the accelerations (M v_dot - G lambda = Q - b, "
                       "G^T v_dot = gamma) and printed as a reaction table, with the backward "
                       "error, a condition estimate and any redundant constraints named.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    add_known_option(s, "applied as a load", "taken at the state's time (t = 0 s for the "
                     "model's initial state)")
    s.add_argument("--json", action="store_true", help="machine-readable output")
    add_axes_option(s)
    s.set_defaults(run=solve)


def check(a: argparse.Namespace) -> int:
    from mbody.equations.assemble import assemble as _assemble
    from mbody.equations.joints import joint_errors
    from mbody.equations.topology import topology
    from mbody.present.text import model_summary

    model = load_model(a.model, warn=False)  # the summary lists the warnings itself
    # the rank test from G's columns: dense blocks, no scipy.sparse (start-up time)
    topo = topology(model, columns=_assemble(model).columns if model.reactions else None)
    print(model_summary(model, topo))
    broken = joint_errors(model, model.initial)
    if broken:
        print("warning: the initial state breaks joint constraints: " + ", ".join(broken)
              + "; move or set the bodies' positions and velocities so the joints hold",
              file=sys.stderr)
    print(f"\nOK: {a.model} is a valid model.")
    return EXIT_OK


def assemble(a: argparse.Namespace) -> int:
    from mbody.equations.assemble import assemble as _assemble
    from mbody.present.text import assembly_text, body_text

    output_suffix(a.latex, "--latex", "LaTeX", (".tex",), a.force)
    if a.answers_key is not None:
        return _answers_key(a)
    model = load_model(a.model)
    asm = _assemble(model)
    if a.symbolic:
        return _symbolic(asm, a)
    if a.latex is not None:
        from mbody.cli.export import latex

        return latex(asm, a.latex, a.body)
    if a.body:
        try:
            print(body_text(asm.bodies[a.body], model.dimension))
        except KeyError as exc:
            raise MbodyError(exc.args[0]) from None
    else:
        print(assembly_text(asm))
    return EXIT_OK


def _answers_key(a: argparse.Namespace) -> int:
    """`mbody assemble MODEL --answers-key FILE [--body NAME]`."""
    from mbody.answers.key import answer_key
    from mbody.util.atomic import ensure_writable, write_atomic

    if a.latex is not None or a.symbolic:
        raise MbodyError("--answers-key writes the rows as an answers file; give it "
                         "without --latex and --symbolic")
    output_suffix(a.answers_key, "--answers-key", "YAML", (".yaml", ".yml"), a.force)
    if a.answers_key != "-":
        ensure_writable(a.answers_key)  # before the work
    model = load_model(a.model)
    text = answer_key(model, bodies=None if a.body is None else [a.body])
    if a.answers_key == "-":
        sys.stdout.write(text)
        return EXIT_OK
    n = text.count("\n  - {body: ")
    print(f"wrote {write_atomic(a.answers_key, text)}  ({n} equation{'s' if n != 1 else ''})",
          file=output_stream(a.answers_key))
    return EXIT_OK


def _symbolic(asm, a: argparse.Namespace) -> int:
    """`mbody assemble MODEL --symbolic [--body NAME] [--latex [FILE]]`."""
    from importlib.util import find_spec

    from mbody.util.atomic import write_atomic

    if find_spec("sympy") is None:
        raise MbodyError("--symbolic needs sympy; install it with: pip install "
                         "'mbody[symbolic]'")
    try:
        sym = asm.symbolic(None if a.body is None else [a.body])
    except KeyError as exc:
        raise MbodyError(exc.args[0]) from None
    if a.latex is None:
        print(sym.text() if a.body is None else sym.bodies[0].text())
    elif a.latex == "-":
        sys.stdout.write(sym.document())
    else:
        try:
            print(f"wrote {write_atomic(a.latex, sym.document())}",
                  file=output_stream(a.latex))
        except OSError as exc:
            raise MbodyError(f"cannot write {a.latex}: {exc.strerror or exc}") from None
    return EXIT_OK


def solve(a: argparse.Namespace) -> int:
    from mbody.equations.assemble import assemble as _assemble
    from mbody.present.text import reaction_table_text, solution_text, world_reaction_text
    from mbody.util import jsontext

    model = load_model(a.model)
    asm = _assemble(model)
    sol = asm.solve(known=parse_known(a.known), condition=True, axes=a.axes)
    if a.json:
        acc = sol.accelerations.tolist()
        by_body = {name: {model.coordinates[r]: acc[r] for r in model.body_rows(i)}
                   for i, name in enumerate(model.body_names)}
        jsontext.dump({"model": model.name, "coordinates": sol.coordinates,
                       "accelerations": acc, "by_body": by_body,
                       "reactions": dict(sol.reactions), "solved": list(sol.solved),
                       "not_unique": list(sol.not_unique), "backward_error": sol.residual,
                       "condition": sol.condition, "warnings": sol.warnings,
                       "reaction_axes": sol.axes}, sys.stdout)
    else:
        print(solution_text(sol, model))
        if sol.reactions:
            print()
            print(world_reaction_text(model, sol) if sol.axes == "world"
                  else reaction_table_text(asm, sol))
    return EXIT_OK

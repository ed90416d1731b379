"""lagrange, modes: the equations in generalized coordinates; small oscillations and
stability about an equilibrium or a steady motion."""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from collections.abc import Iterator

from mbody.cli.common import (
    EXIT_OK,
    EXPORT_SUFFIXES,
    MODEL_HELP,
    PICTURE_SUFFIXES,
    VIEW_HELP,
    add_known_option,
    add_progress_options,
    load_model,
    output_suffix,
    parse_known,
    show_progress,
)
from mbody.errors import MbodyError, OutputError


def _coordinates(text: str | None) -> list[str] | None:
    if text is None:
        return None
    labels = [c.strip() for c in text.split(",") if c.strip()]
    if not labels:
        raise MbodyError("--coordinates expects labels separated by commas, e.g. "
                         "--coordinates O.angle,A.angle")
    return labels


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser(
        "lagrange", help="the equations in generalized coordinates, M(q) q'' = f(q, q')",
        description="The Newton-Euler equations of MODEL projected onto generalized "
        "coordinates (one per degree of freedom: by default each driver's coordinate, the "
        "joint coordinates of a spanning tree, a free body's own): v = T q' + v_e, "
        "M = T^T M T, f = T^T (Q - b - M a0); the reactions drop out. Printed at the "
        "model's initial state; with --symbolic, M(q) and f(q, q') in symbols (planar "
        "trees; needs sympy).")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--coordinates", metavar="LABELS",
                   help="the coordinates, separated by commas (joint coordinates such as "
                   "O.angle, P.displacement, or a body's own such as rod.theta, rod.x); one "
                   "per degree of freedom")
    s.add_argument("--symbolic", action="store_true",
                   help="M(q) and f(q, q') with symbols (m_<body>, I_<body>, g, loads by "
                   "name), in compact trigonometric form; planar trees only")
    s.add_argument("--latex", metavar="FILE", nargs="?", const="-",
                   help="write a LaTeX document to FILE, or to standard output without FILE")
    s.add_argument("-o", "--output", metavar="FILE", action="append", default=[],
                   help="export q, M, f, T... with their labels: a file ending in .npz, .mat "
                   "or .json (repeatable)")
    add_known_option(s, "applied as a load, its joint then not held",
                     "taken at the state's time")
    add_progress_options(s, "what a long computation is doing")
    s.set_defaults(run=lagrange, output_suffixes={"-o": EXPORT_SUFFIXES})

    s = sub.add_parser(
        "modes", help="natural frequencies, damping ratios, mode shapes and stability",
        description="Linearise MODEL about its initial state (an equilibrium, or a steady "
        "motion such as a spin about a principal axis), or with --equilibrium about the "
        "static equilibrium nearest it: M dq'' + D dq' + K dq = 0 in generalized "
        "coordinates, K with the constraint forces' geometric stiffness. Prints each "
        "mode's eigenvalue, natural frequency (rad/s, Hz), damping ratio and shape, and "
        "the verdict: stable, unstable (a mode grows) or none (not a steady state).")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--equilibrium", action="store_true",
                   help="linearise about the static equilibrium nearest the initial pose "
                   "(Newton's method; stable or not)")
    s.add_argument("--coordinates", metavar="LABELS",
                   help="the free coordinates, separated by commas (default: those of "
                   "mbody lagrange, less the drivers')")
    s.add_argument("--picture", metavar="FILE",
                   help="draw the mode shapes to FILE (.svg, .png or .pdf)")
    s.add_argument("--view", metavar="VIEW", help="the --picture's view of " + VIEW_HELP)
    s.add_argument("--json", action="store_true", help="machine-readable output")
    add_progress_options(s, "what a long computation is doing")
    s.set_defaults(run=modes, output_suffixes={"--picture": PICTURE_SUFFIXES})


@contextlib.contextmanager
def _writing(target: str) -> Iterator[None]:
    try:
        yield
    except OutputError:
        raise
    except OSError as exc:
        raise MbodyError(f"cannot write {target}: {exc.strerror or exc}") from None


def _need_sympy() -> None:
    from importlib.util import find_spec

    if find_spec("sympy") is None:
        raise MbodyError("--symbolic needs sympy; install it with: pip install "
                         "'mbody[symbolic]'")


def lagrange(a: argparse.Namespace) -> int:
    from mbody.equations.generalized import generalized
    from mbody.io.export.generalized import write_generalized
    from mbody.present.lagrange import (
        generalized_document,
        generalized_text,
        symbolic_text,
        too_many_to_write,
    )
    from mbody.util.atomic import ensure_writable, write_atomic
    from mbody.util.progress import Progress

    for out in a.output:
        ensure_writable(out)
    output_suffix(a.latex, "--latex", "LaTeX", (".tex",), a.force)
    if a.latex not in (None, "-"):
        ensure_writable(a.latex)
    model = load_model(a.model)
    with Progress(show_progress(a), f"lagrange {model.name}") as bar:
        g = generalized(model, None, _coordinates(a.coordinates),
                        parse_known(a.known) or None, progress=bar)
        if a.latex is not None and not a.symbolic and too_many_to_write(len(g.f)):
            raise MbodyError(too_many_to_write(len(g.f)))
        sym = None
        if a.symbolic:
            _need_sympy()
            sym = g.symbolic(progress=bar)
        for out in a.output:
            bar.step(f"writing {out}")
            with _writing(out):
                path = write_generalized(g, out)
            bar.close()
            print(f"wrote {path}", file=sys.stderr if a.latex == "-" else sys.stdout)
        bar.step("writing the equations")
        if a.latex is not None:
            doc = generalized_document(g, sym)
            bar.close()
            if a.latex == "-":
                sys.stdout.write(doc)
            else:
                with _writing(a.latex):
                    print(f"wrote {write_atomic(a.latex, doc)}")
            return EXIT_OK
        text = symbolic_text(sym) if sym is not None else generalized_text(g)
    print(text)
    return EXIT_OK


def modes(a: argparse.Namespace) -> int:
    from mbody.present.modes import modes_text, verdict
    from mbody.solve.linearize import linearize
    from mbody.util.atomic import ensure_writable
    from mbody.util.progress import Progress

    if a.view is not None:  # checked as fbd and report check it, before any work
        from mbody.present.draw import parse_view

        parse_view(a.view)
    if a.picture:
        ensure_writable(a.picture)
    model = load_model(a.model)
    state, about = None, f"its initial state (t = {model.initial.t:g} s)"
    with Progress(show_progress(a), f"modes {model.name}") as bar:
        if a.equilibrium:
            from mbody.solve.equilibrium import equilibrium

            state = equilibrium(model, progress=bar)
            about = "the static equilibrium nearest its initial pose"
        lin = linearize(model, state, coordinates=_coordinates(a.coordinates), progress=bar)
        if a.picture:
            from mbody.present.draw import save_figure
            from mbody.present.draw.modes import modes_figure

            bar.step(f"drawing {a.picture}")
            with _writing(a.picture):
                path = save_figure(modes_figure(lin, view=a.view), a.picture)
            bar.close()
            print(f"wrote {path}", file=sys.stderr if a.json else sys.stdout)
        bar.step("writing the modes")
        if a.json:
            doc = {"model": model.name, "about": about, "coordinates": lin.coordinates,
                   "left_out": list(lin.left_out), "steady": lin.steady,
                   "stable": lin.stable, "verdict": verdict(lin), "tolerance": lin.tolerance,
                   "modes": [{"kind": m.kind,
                              "eigenvalue": [m.eigenvalue.real, m.eigenvalue.imag],
                              "frequency_rad_s": _finite(m.frequency),
                              "frequency_hz": _finite(m.frequency_hz),
                              "damping_ratio": _finite(m.damping_ratio),
                              "shape": [[z.real, z.imag] for z in m.shape]}
                             for m in lin.modes],
                   "M": lin.M.tolist(), "D": lin.D.tolist(), "K": lin.K.tolist(),
                   "warnings": list(lin.warnings)}
            text = json.dumps(doc, indent=2)
        else:
            text = modes_text(lin, about)
    print(text)
    return EXIT_OK


def _finite(x: float) -> float | None:
    return float(x) if x == x and abs(x) != float("inf") else None

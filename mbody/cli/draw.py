"""fbd, graph, report: pictures of every body's free body, of the body/joint graph, and
one self-contained HTML page with all of it."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from mbody.cli.common import EXIT_OK, MODEL_HELP, load_model
from mbody.errors import MbodyError, did_you_mean

VIEW_HELP = ("spatial models: iso (default), front, top, side, or ELEV,AZIM in degrees "
             "(for example 30,-60)")


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("fbd", help="draw every body's free-body diagram (svg, png or pdf)",
                       description="Write one picture per body (or only --body NAME): its "
                       "outline, mass centre and axes, applied forces, gravity, couples and "
                       "reaction components (dashed), with the body's Newton-Euler pair "
                       "under the drawing. Files are named fbd_<body>.<format>.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("-o", "--output", metavar="DIR", default=".",
                   help="folder for the pictures (created if missing; default: .)")
    s.add_argument("--body", metavar="NAME", help="only this body")
    s.add_argument("--format", choices=("svg", "png", "pdf"), default="svg",
                   help="picture format (default: svg)")
    s.add_argument("--view", metavar="VIEW", default="iso", help=VIEW_HELP)
    s.add_argument("--dpi", type=int, default=150, help="resolution of png pictures")
    s.set_defaults(run=fbd)

    s = sub.add_parser("graph", help="draw the body/joint graph",
                       description="Draw the bodies and ground as nodes and every joint as "
                       "an edge labelled with its type and number of reaction components.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("-o", "--output", metavar="FILE", default="graph.svg",
                   help="picture file; its extension (.svg, .png, .pdf) sets the format "
                   "(default: graph.svg)")
    s.set_defaults(run=graph)

    s = sub.add_parser("report", help="write one self-contained HTML page for the model",
                       description="One offline HTML page: the model summary, the topology "
                       "picture, the sizes of the stacked M, b, Q, G, the accelerations "
                       "and joint reactions solved at the initial state (with units), and "
                       "every body's free-body diagram and equations.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("-o", "--output", metavar="FILE", default="report.html",
                   help="the page to write (default: report.html)")
    s.add_argument("--view", metavar="VIEW", default="iso", help=VIEW_HELP)
    s.add_argument("--answers", metavar="FILE", help="a student's equations (a YAML answers "
                   "file, see mbody verify): shown beside the expected rows")
    s.set_defaults(run=report)


def _file_name(body: str, taken: set[str]) -> str:
    """fbd_<body> with only portable characters, unique within one run."""
    stem = "fbd_" + (re.sub(r"[^A-Za-z0-9._-]+", "_", body).strip("._") or "body")
    name, k = stem, 2
    while name.lower() in taken:
        name, k = f"{stem}_{k}", k + 1
    taken.add(name.lower())
    return name


def fbd(a: argparse.Namespace) -> int:
    from mbody.equations.assemble import assemble
    from mbody.present.draw import fbd_scene, parse_view, save_figure

    parse_view(a.view)  # a bad view is reported before any work
    model = load_model(a.model)
    if a.body is not None and a.body not in model.index:
        hint = did_you_mean(a.body, model.body_names)
        raise MbodyError(f"no body named {a.body!r} in {a.model}"
                         + (f" ({hint})" if hint else "")
                         + "; its bodies: " + ", ".join(model.body_names[:20])
                         + (" ..." if model.n > 20 else ""))
    if a.dpi <= 0:
        raise MbodyError(f"--dpi must be a positive number of dots per inch, got {a.dpi}")
    asm = assemble(model)
    names = [a.body] if a.body is not None else list(model.body_names)
    out, taken = Path(a.output), set[str]()
    if out.exists() and not out.is_dir():
        raise MbodyError(f"-o {a.output}: not a folder (fbd writes one picture per body)")
    for name in names:
        fig = fbd_scene(asm.bodies[name].fbd, view=a.view)
        path = save_figure(fig, out / f"{_file_name(name, taken)}.{a.format}", a.format,
                           dpi=a.dpi)
        print(f"wrote {path}  (body {name})")
    return EXIT_OK


def graph(a: argparse.Namespace) -> int:
    from mbody.equations.assemble import assemble
    from mbody.model.graph import topology
    from mbody.present.draw import FORMATS, graph_scene, save_figure

    fmt = Path(a.output).suffix.lstrip(".").lower()
    if fmt not in FORMATS:
        raise MbodyError(f"-o {a.output}: the file name must end in "
                         + ", ".join("." + f for f in FORMATS) + " (it sets the format)")
    model = load_model(a.model)
    topo = topology(model, assemble(model).G if model.reactions else None)
    path = save_figure(graph_scene(model, topo), a.output, fmt)
    print(f"wrote {path}  ({model.n} bodies, {len(model.joints)} joints, "
          f"mobility {topo.mobility})")
    return EXIT_OK


def report(a: argparse.Namespace) -> int:
    from mbody.present.draw import parse_view
    from mbody.present.report import write_report

    parse_view(a.view)
    model = load_model(a.model)
    answers = None
    if a.answers is not None:
        from mbody.answers.verify import verify

        answers = verify(model, a.answers)
    path = write_report(model, a.output, view=a.view, answers=answers)
    print(f"wrote {path}  ({model.n} bod{'y' if model.n == 1 else 'ies'})")
    return EXIT_OK

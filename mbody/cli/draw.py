"""fbd, graph, report: pictures of every body's free body, of the body/joint graph, and
one self-contained HTML page with all of it."""

from __future__ import annotations

import argparse
import hashlib
import re
from pathlib import Path

from mbody.cli.common import (
    EXIT_OK,
    MODEL_HELP,
    PICTURE_FORMATS,
    PICTURE_SUFFIXES,
    VIEW_HELP,
    add_axes_option,
    bounded,
    load_model,
    output_stream,
    output_suffix,
    regular_file,
)
from mbody.errors import MbodyError, did_you_mean
from mbody.util.atomic import refuse_overwriting_inputs

DPI = (10, 600)
"""The resolutions `fbd --dpi` accepts (dots per inch): below 10 FreeType cannot draw the
text; above 600 a picture of 8 inches takes a gigabyte of memory to draw."""


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("fbd", help="draw every body's free-body diagram (svg, png or pdf)",
                       description="Write one picture per body (or only --body NAME): its "
                       "outline, mass centre and axes, applied forces, gravity, couples and "
                       "reaction components (dashed), with the body's Newton-Euler pair "
                       "under the drawing (--no-equations: without it, for a handout). Files "
                       "are named fbd_<body>.<format>; all of them are written, or none (a "
                       "failure leaves the folder as it was).")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("-o", "--output", metavar="DIR", default=".",
                   help="folder for the pictures (created if missing; default: .)")
    s.add_argument("--body", metavar="NAME", help="only this body")
    s.add_argument("--image-format", choices=PICTURE_FORMATS, default="svg",
                   help="picture format (default: svg)")
    s.add_argument("--view", metavar="VIEW", default="iso", help=VIEW_HELP)
    s.add_argument("--dpi", type=bounded("a whole number of dots per inch", *DPI, integer=True),
                   default=150, metavar="N",
                   help=f"resolution of png pictures, {DPI[0]} to {DPI[1]} (default 150)")
    s.add_argument("--no-equations", action="store_true",
                   help="leave the body's Newton-Euler pair out from under the drawing: the "
                   "diagram alone, for an assignment's handout")
    s.set_defaults(run=fbd)

    s = sub.add_parser("graph", help="the body/joint graph: as text, or drawn with -o",
                       description="The bodies and ground as nodes and every joint as an "
                       "edge (parent -> child) with its type and number of reaction "
                       "components, then the graph's loops, connected parts and mobility. "
                       "Printed as text; with -o FILE, drawn as a picture instead.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("-o", "--output", metavar="FILE",
                   help="draw the graph into this picture; its extension (.svg, .png, .pdf) "
                   "sets the format")
    s.set_defaults(run=graph, output_suffixes={"-o": PICTURE_SUFFIXES})

    s = sub.add_parser("report", help="write one self-contained HTML page for the model",
                       description="One offline HTML page: the model summary, the topology "
                       "picture, the sizes of the stacked M, b, Q, G, the accelerations "
                       "and joint reactions solved at the initial state (with units; in "
                       "world axes with --axes world), and every body's free-body diagram "
                       "and equations.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("-o", "--output", metavar="FILE", default="report.html",
                   help="the page to write (default: report.html)")
    s.add_argument("--view", metavar="VIEW", default="iso", help=VIEW_HELP)
    s.add_argument("--answers", metavar="FILE", help="a student's equations (a YAML answers "
                   "file, see mbody verify): shown beside the expected rows")
    add_axes_option(s)
    s.set_defaults(run=report)


FILE_STEM_MAX = 100
"""Longest picture file name fbd makes, before its number and extension, in characters
(ASCII, so bytes too): a file system allows 255 bytes a name, and a body's name may be
longer (`check` accepts a 300-character name)."""


def _file_name(body: str, taken: set[str]) -> str:
    """fbd_<body> with only portable characters, unique within one run (a repeat numbered
    _2, _3...); a name too long for a file (`FILE_STEM_MAX`) cut short with 8 hex digits
    of the body's whole name, so that two long names that begin alike stay apart."""
    stem = "fbd_" + (re.sub(r"[^A-Za-z0-9._-]+", "_", body).strip("._") or "body")
    if len(stem) > FILE_STEM_MAX:
        digest = hashlib.sha256(body.encode("utf-8", "surrogatepass")).hexdigest()[:8]
        stem = f"{stem[:FILE_STEM_MAX - 9]}_{digest}"
    name, k = stem, 2
    while name.lower() in taken:
        name, k = f"{stem}_{k}", k + 1
    taken.add(name.lower())
    return name


def fbd(a: argparse.Namespace) -> int:
    from mbody.equations.assemble import assemble
    from mbody.present.draw import fbd_scene, parse_view, save_figure
    from mbody.util.atomic import atomic_folder

    parse_view(a.view)  # a bad view is reported before any work
    out = Path(a.output)
    if out.suffix.lower() in PICTURE_SUFFIXES and not out.is_dir():
        # a picture's name where the folder goes: it would become a folder of that name
        fmt = out.suffix.lower().lstrip(".")
        raise MbodyError(f"-o {a.output}: fbd -o is a folder; the pictures are named "
                         f"fbd_<body>.<format> inside it; did you mean -o "
                         f"{out.parent} --image-format {fmt}?")
    if out.exists() and not out.is_dir():
        raise MbodyError(f"-o {a.output}: not a folder (fbd writes one picture per body)")
    model = load_model(a.model)
    if a.body is not None and a.body not in model.index:
        hint = did_you_mean(a.body, model.body_names)
        raise MbodyError(f"no body named {a.body!r} in {a.model}"
                         + (f" ({hint})" if hint else "")
                         + "; its bodies: " + ", ".join(model.body_names[:20])
                         + (" ..." if model.n > 20 else ""))
    asm = assemble(model)
    names = [a.body] if a.body is not None else list(model.body_names)
    taken = set[str]()
    files = [(name, f"{_file_name(name, taken)}.{a.image_format}") for name in names]
    refuse_overwriting_inputs([("-o", str(out / f)) for _, f in files],
                              [("the model", a.model)])
    with atomic_folder(out) as tmp:  # every picture, or none
        for name, file in files:
            fig = fbd_scene(asm.bodies[name].fbd, view=a.view, equations=not a.no_equations)
            save_figure(fig, tmp / file, a.image_format, dpi=a.dpi)
    for name, file in files:
        print(f"wrote {out / file}  (body {name})")
    return EXIT_OK


def graph(a: argparse.Namespace) -> int:
    from mbody.equations.assemble import assemble
    from mbody.equations.topology import topology
    from mbody.model.reprs import count
    from mbody.present.draw import FORMATS, graph_scene, save_figure

    fmt = Path(a.output).suffix.lstrip(".").lower() if a.output else None
    if a.output and fmt not in FORMATS:
        raise MbodyError(f"-o {a.output}: the file name must end in "
                         + ", ".join("." + f for f in FORMATS) + " (it sets the format)")
    model = load_model(a.model)
    topo = topology(model, assemble(model).G if model.reactions else None)
    if not a.output:
        print(graph_text(model, topo))
        return EXIT_OK
    path = save_figure(graph_scene(model, topo), a.output, fmt)
    print(f"wrote {path}  ({count(model.n, 'body', 'bodies')}, "
          f"{count(len(model.joints), 'joint')}, mobility {topo.mobility})",
          file=output_stream(a.output))
    return EXIT_OK


def graph_text(model, topo) -> str:
    """`mbody graph MODEL` without -o: every joint as an edge, then the graph summary."""
    from mbody.model.model import count
    from mbody.present.text import graph_summary

    lines = [f"body/joint graph of {model.name!r}: {count(model.n, 'body', 'bodies')} + "
             f"ground, {count(len(model.joints), 'joint')} (edges: joint, type, parent -> "
             "child, reaction components)"]
    shown = model.joints[:200]
    width = max([len(j.name) for j in shown] + [1])
    kinds = max([len(j.type) for j in shown] + [1])
    for j in shown:
        lines.append(f"  {j.name:<{width}}  {j.type:<{kinds}}  {j.parent} -> {j.child}  "
                     f"({count(len(j.labels), 'reaction component')})")
    if len(model.joints) > len(shown):
        lines.append(f"  ... and {len(model.joints) - len(shown)} more")
    lines.append(graph_summary(model, topo))
    lines.append("(draw it with -o FILE.svg, .png or .pdf)")
    return "\n".join(lines)


def report(a: argparse.Namespace) -> int:
    from mbody.present.draw import parse_view
    from mbody.present.report import write_report

    parse_view(a.view)
    output_suffix(a.output, "-o", "an HTML page", (".html", ".htm"), a.force)
    model = load_model(a.model)
    answers = None
    if a.answers is not None:
        from mbody.answers.verify import verify

        regular_file(a.answers, "a YAML answers file")
        answers = verify(model, a.answers)
    path = write_report(model, a.output, view=a.view, answers=answers, axes=a.axes)
    print(f"wrote {path}  ({model.n} bod{'y' if model.n == 1 else 'ies'})",
          file=output_stream(a.output))
    return EXIT_OK

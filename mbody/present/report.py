"""One self-contained HTML page per model: summary, topology, every body's free-body
diagram and Newton-Euler pair, and the sizes of the stacked ``M v̇ + b = Q + G λ``.

Everything is inline (pictures as SVG elements, styles in the page): it opens offline,
links to nothing outside itself, and prints as a hand-in.
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mbody import __version__
from mbody import conventions as cv
from mbody.equations.assemble import Assembly, assemble
from mbody.io.atomic import write_atomic
from mbody.model.graph import topology
from mbody.model.model import Model
from mbody.present.draw import fbd_scene, figure_svg, graph_scene
from mbody.present.text import body_text, model_summary

MAX_BODIES = 200
"""Bodies drawn in one report; larger models list the rest by name."""

_CSS = """
body { font-family: "DejaVu Sans", Arial, Helvetica, sans-serif; margin: 2em auto;
       max-width: 980px; color: #1d232b; line-height: 1.4; padding: 0 1em; }
h1 { font-size: 1.7em; margin-bottom: 0.2em; }
h2 { border-bottom: 2px solid #1f4e9c; padding-bottom: 0.2em; margin-top: 2em; }
h3 { margin-top: 1.6em; }
pre { background: #f5f6f8; border: 1px solid #dde1e6; padding: 0.8em; overflow-x: auto;
      font-size: 0.85em; line-height: 1.35; }
figure { margin: 1em 0; text-align: center; }
figure svg { max-width: 100%; height: auto; }
figcaption { font-size: 0.9em; color: #555; }
table { border-collapse: collapse; margin: 0.5em 0; }
td, th { border: 1px solid #cfd5dc; padding: 0.25em 0.8em; text-align: left; }
th { background: #eef1f5; }
nav ol { columns: 2; }
.muted { color: #666; font-size: 0.9em; }
section.body { page-break-before: always; }
"""


def _e(s: object) -> str:
    return html.escape(str(s), quote=True)


def report_html(model: Model, *, asm: Assembly | None = None,
                view: str | Sequence[float] | None = "iso",
                max_bodies: int = MAX_BODIES) -> str:
    """The report page as one HTML string (UTF-8, no external resources)."""
    asm = assemble(model) if asm is None else asm
    topo = topology(model, asm.G if model.reactions else None)
    planar = model.dimension == cv.PLANAR
    shown = list(model.body_names[:max_bodies])
    title = f"mbody report: {model.name}"

    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>",
           f"<h1>{_e(model.name)}</h1>",
           f'<p class="muted">{"planar" if planar else "spatial"} model'
           + (f" from <code>{_e(model.file)}</code>" if model.file else "")
           + f"; free-body diagrams and Newton-Euler equations by mbody {_e(__version__)}."
           " Equations: M v̇ + b = Q + G λ, one block of rows per body in file order"
           + (" (x, y, θ)." if planar else
              " (Newton x, y, z in world axes, then Euler 1, 2, 3 in body axes).") + "</p>"]
    if model.description:
        out.append(f"<p>{_e(model.description.strip())}</p>")

    out.append("<nav><h2>Contents</h2><ol>"
               '<li><a href="#summary">Model summary</a></li>'
               '<li><a href="#topology">Topology</a></li>'
               '<li><a href="#stacked">Stacked equations</a></li>')
    out += [f'<li><a href="#body-{k}">Body {_e(b)}</a></li>' for k, b in enumerate(shown)]
    out.append("</ol></nav>")

    out.append('<section id="summary"><h2>Model summary</h2>'
               f"<pre>{_e(model_summary(model, topo))}</pre></section>")

    out.append('<section id="topology"><h2>Topology</h2><figure>'
               f"{figure_svg(graph_scene(model, topo), prefix='graph-')}"
               "<figcaption>Bodies and ground are the nodes; every joint is an edge labelled "
               "with its type and the number of its reaction components.</figcaption>"
               "</figure></section>")

    sh = asm.shape
    rows = "".join(f"<tr><td>{k}</td><td>{' × '.join(map(str, v))}</td><td>{_e(what)}</td>"
                   "</tr>" for (k, v), what in zip(sh.items(), (
                       "block-diagonal mass matrix", "gyroscopic terms ω × (J ω)",
                       "applied forces and moments (gravity, springs included)",
                       "one column per reaction unknown"), strict=True))
    unknown = [r for r in asm.reactions if r not in model.known_reactions]
    out.append('<section id="stacked"><h2>Stacked equations</h2>'
               "<p>M v̇ + b = Q + G λ with "
               f"{len(asm.coordinates)} rows ({model.rows_per_body} per body) and "
               f"{len(asm.reactions)} reaction components ({len(unknown)} unknown).</p>"
               f"<table><tr><th>matrix</th><th>size</th><th>what it holds</th></tr>{rows}"
               "</table>"
               f"<p class=\"muted\">Sign rule: {_e(cv.SIGN_RULE)}.</p></section>")

    for k, name in enumerate(shown):
        eq = asm.bodies[name]
        svg = figure_svg(fbd_scene(eq.fbd, view=view), prefix=f"b{k}-")
        out.append(f'<section class="body" id="body-{k}"><h2>Body {_e(name)}</h2>'
                   f"<figure>{svg}<figcaption>Free-body diagram of {_e(name)}: applied "
                   "forces solid, gravity at the mass centre, reaction components dashed."
                   "</figcaption></figure>"
                   f"<h3>Free body and Newton-Euler pair</h3>"
                   f"<pre>{_e(body_text(eq, model.dimension))}</pre></section>")
    if model.n > len(shown):
        rest = ", ".join(model.body_names[len(shown):])
        out.append(f"<p>{model.n - len(shown)} more bodies not drawn: {_e(rest)}.</p>")
    out.append("</body></html>")
    return "\n".join(out)


def write_report(model: Model, path: str | Path, **kwargs: Any) -> Path:
    """Write `report_html(model, **kwargs)` to `path` atomically (UTF-8)."""
    return write_atomic(path, report_html(model, **kwargs))

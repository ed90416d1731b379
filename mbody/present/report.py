"""One self-contained HTML page per model: summary, topology, every body's free-body
diagram and Newton-Euler pair, the sizes of the stacked ``M v̇ + b = Q + G λ``, and its
solution at the file's state (accelerations by body, reactions by label, with units).

Everything is inline (pictures as SVG elements, styles in the page): it opens offline,
links to nothing outside itself, and prints as a hand-in.
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import __version__, joint_types
from mbody import conventions as cv
from mbody.answers.verify import check_assembly_of
from mbody.conventions import check_axes
from mbody.equations.assemble import Assembly, Solution, assemble
from mbody.equations.topology import topology
from mbody.errors import MbodyError
from mbody.model.model import Model
from mbody.present.answers import answers_section
from mbody.present.draw import fbd_scene, figure_svg, graph_scene
from mbody.present.text import body_text, joint_status, model_summary
from mbody.util.atomic import write_atomic
from mbody.util.formatting import num

if TYPE_CHECKING:
    from mbody.answers.verify import Verification

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
                max_bodies: int = MAX_BODIES, answers: Verification | None = None,
                axes: str = "joint") -> str:
    """The report page as one HTML string (UTF-8, no external resources); with `answers`
    (what `mbody.verify` found), a student's equations beside the expected rows, and the
    whole page of the model the verdicts are of (with the answers' ``set:`` values, if
    any; an `asm` given must be of that model); `axes`:
    the solution's reactions along their joint frames ("joint") or, each joint's force
    and moment on its child, in world axes ("world")."""
    check_axes(axes)
    if answers is not None and answers.values:
        # the verdicts are of the model with the answers' `set:` values: the pictures, the
        # equations and the solution are of that model too, not of the class's
        model = model.with_values(dict(answers.values))
        if asm is not None:
            check_assembly_of(model, asm)
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
           + (" with the answers' values " + ", ".join(f"<code>{_e(p)}={_e(v)}</code>"
                                                      for p, v in answers.values)
              if answers is not None and answers.values else "")
           + f"; free-body diagrams and Newton-Euler equations by mbody {_e(__version__)}."
           " Equations: M v̇ + b = Q + G λ, one block of rows per body in file order"
           + (" (x, y, θ)." if planar else
              " (Newton x, y, z in world axes, then Euler 1, 2, 3 in body axes).") + "</p>"]
    if model.description:
        out.append(f"<p>{_e(model.description.strip())}</p>")

    out.append("<nav><h2>Contents</h2><ol>"
               '<li><a href="#summary">Model summary</a></li>'
               '<li><a href="#topology">Topology</a></li>'
               '<li><a href="#stacked">Stacked equations</a></li>'
               '<li><a href="#solution">Solution at the initial state</a></li>'
               + ('<li><a href="#answers">Your equations</a></li>' if answers is not None
                  else ""))
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

    out.append(_solution_section(asm, axes))
    if answers is not None:
        out.append(answers_section(answers))

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


_UNITS = {"x": "m/s²", "y": "m/s²", "z": "m/s²"}
_SYMBOLS = {"x": "a<sub>x</sub>", "y": "a<sub>y</sub>", "z": "a<sub>z</sub>",
            "w1": "α<sub>1</sub>", "w2": "α<sub>2</sub>", "w3": "α<sub>3</sub>",
            "theta": "α"}


def _num(x: float) -> str:
    """As `mbody solve` prints numbers: 6 significant digits, rounding noise as 0."""
    return num(x)


def _quiet(x: np.ndarray, rel: float = 1e-10) -> np.ndarray:
    """Values below `rel` times the largest one shown as 0: rounding noise, not data."""
    top = float(np.max(np.abs(x), initial=0.0))
    return np.where(np.abs(x) <= rel * top, 0.0, x)


def _solution_section(asm: Assembly, axes: str = "joint") -> str:
    """The solved accelerations by body and every reaction's value, at the file's state
    (what `mbody solve` prints, with ``--axes world`` when `axes` is "world"), or why the
    model cannot be solved there."""
    model = asm.model
    head = ('<section id="solution"><h2>Solution at the initial state</h2>'
            f"<p>At t = {_num(asm.state.t)} s, the state written in the file. ")
    try:
        sol = asm.solve(axes=axes)
    except MbodyError as e:
        return head + f"The equations cannot be solved there: {_e(e)}</p></section>"
    rows = cv.PLANAR_ROWS if model.dimension == cv.PLANAR else cv.SPATIAL_ROWS
    unknown = [r for r in asm.reactions if r not in model.known_reactions]
    out = [head + ("No joints, so v̇ = M⁻¹ (Q − b)." if not asm.reactions else
                   "Every reaction is given, so v̇ = M⁻¹ (Q − b + G λ)." if not unknown else
                   f"The {len(unknown)} unknown reaction components are solved with the "
                   "joints' constraints (the mechanism's accelerations).")
           + (" Newton rows in world axes, Euler rows in body axes." if len(rows) == 6
              else "") + "</p>"]
    acc = _quiet(np.asarray(sol.accelerations, dtype=np.float64))
    header = "".join(f"<th>{_SYMBOLS[r]} ({_UNITS.get(r, 'rad/s²')})</th>" for r in rows)
    body_rows = "".join(
        f"<tr><td>{_e(name)}</td>"
        + "".join(f"<td>{_num(v)}</td>" for v in acc[model.body_rows(i)]) + "</tr>"
        for i, name in enumerate(model.body_names))
    out.append(f'<h3>Accelerations</h3><table class="solution" id="accelerations">'
               f"<tr><th>body</th>{header}</tr>{body_rows}</table>")
    if sol.reactions and axes == "world":
        out.append(_world_reactions(model, sol))
    elif sol.reactions:
        is_moment = asm.columns.is_moment
        lam = _quiet(np.array([sol.reactions[r] for r in model.reactions], dtype=np.float64))
        solved, not_unique = set(sol.solved), set(sol.not_unique)
        lines = "".join(
            f"<tr><td>{_e(label)}</td><td>{_num(lam[c])}</td>"
            f"<td>{'N·m' if is_moment[c] else 'N'}</td><td>"
            + ("not unique" if label in not_unique else "solved" if label in solved
               else "given") + "</td></tr>"
            for c, label in enumerate(model.reactions))
        out.append('<h3>Joint reactions</h3><p>Each component acts along (or about) its '
                   "joint-frame axis: +R on the child, −R on the parent.</p>"
                   '<table class="solution" id="reactions"><tr><th>reaction</th>'
                   f"<th>value</th><th>unit</th><th>status</th></tr>{lines}</table>")
    if sol.residual is not None:
        out.append(f'<p class="muted">Solved by {_e(sol.method)}; relative backward error '
                   f"{sol.residual:.1e}.</p>")
    out += [f"<p><strong>Warning:</strong> {_e(w)}</p>" for w in sol.warnings]
    out.append("</section>")
    return "".join(out)


def _world_reactions(model: Model, sol: Solution) -> str:
    """The reactions table in world axes: each joint's force and moment on its child
    (`mbody.equations.world`), the drivers' efforts as they are; a joint's status is its
    components' (`joint_status`)."""
    labels = list(sol.reactions)
    values = _quiet(np.array([sol.reactions[r] for r in labels], dtype=np.float64))
    status = joint_status(model, sol)
    drivers = set(model.reaction_table.driver_names)
    child = {j.name: j.child for j in model.joints}
    lines = "".join(
        f"<tr><td>{_e(label)}</td><td>{_num(v)}</td>"
        f"<td>{'N·m' if joint_types.is_moment(label) else 'N'}</td>"
        f"<td>{_e('driver effort' if name in drivers else 'on ' + child[name])}</td>"
        f"<td>{_e(status.get(name, 'given'))}</td></tr>"
        for label, v, name in zip(labels, values, (lab.split('.', 1)[0] for lab in labels),
                                  strict=True))
    return ("<h3>Joint reactions in world axes</h3><p>Each joint's force F and moment M on "
            "its child at the joint point, along world x, y, z (−F, −M on the parent); a "
            "driver's effort about, or along, its joint's axis. The free-body diagrams below "
            "draw each component along its joint frame.</p>"
            '<table class="solution" id="reactions"><tr><th>reaction</th><th>value</th>'
            f"<th>unit</th><th>acts</th><th>status</th></tr>{lines}</table>")


def write_report(model: Model, path: str | Path, **kwargs: Any) -> Path:
    """Write `report_html(model, **kwargs)` to `path` atomically (UTF-8)."""
    return write_atomic(path, report_html(model, **kwargs))

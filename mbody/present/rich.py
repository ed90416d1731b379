"""What a notebook shows for mbody's objects: HTML, LaTeX, and a body's text block.

The objects' ``_repr_html_``, ``_repr_latex_`` and ``BodyEquations.__str__`` are thin
methods that import this module inside the method and call the functions here: this
module imports the modules that define those objects (through `mbody.present.text`,
`latex`, `plot`, `draw` and `animate`), so an import at the top of theirs would close an
import cycle (``tools/check_imports.py`` allows exactly these display methods to import
the presentation layer). Nothing here runs at ``import mbody``; matplotlib and meshcat
are imported by the functions that draw, on first display.

    model_html(model)        summary tables and the body/joint graph
    assembly_html(asm)       every body (up to MAX_BODIES): free body, equations, unknowns
    body_html(asm.bodies[b]) one body: diagram, forces (applied / reaction), the pair
    solution_html(sol)       accelerations and reactions by body, with units
    trajectory_html(traj)    run facts and the plots; the 3-D animation with
                             (EMBED_ANIMATION, on by default), or `animation(traj)`
    *_latex                  the equations as display math for Jupyter
"""

from __future__ import annotations

import base64
import itertools
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.conventions import REACTION
from mbody.equations.assemble import assemble
from mbody.equations.topology import topology
from mbody.model.model import count
from mbody.present import latex, text
from mbody.present.animate import build_scene, page_html
from mbody.present.html import Markup, block, table, tag
from mbody.simulate.simulation import conserved_lines
from mbody.util.formatting import num

if TYPE_CHECKING:
    from mbody.equations.assemble import Assembly, Solution
    from mbody.equations.fbd import BodyEquations, Equation
    from mbody.model.model import Model
    from mbody.simulate.trajectory import Trajectory

MAX_BODIES = 8
"""Bodies an Assembly display draws and writes out (the rest: ``asm.bodies[name]``)."""
MAX_ROWS = 50
"""Rows of any one table (bodies, loads, joints, accelerations, reactions)."""
MAX_GRAPH = 60
"""Largest number of bodies whose body/joint graph is drawn in a Model display."""
PLOT_DPI = 60
"""Resolution of the Trajectory display's plots (PNG, about 80 KB for two bodies)."""
EMBED_ANIMATION = True
"""Whether a Trajectory display embeds the 3-D animation (a run is shown moving, beside
its plots). The page inlines meshcat's viewer, about 0.9 MB in every such display and so
in the saved notebook: set it False for light notebooks, and call ``animation(traj)``
where a run should play."""

_ids = itertools.count()


def _prefix() -> str:
    """A new id prefix for an inline SVG: many pictures share one notebook page."""
    return f"mbody{next(_ids)}-"


def _n(x: float) -> str:
    """6 significant digits; rounding noise written 0 (`mbody.util.formatting.num`)."""
    return num(float(x))


def _v(x: Any, dim: int) -> str:
    x = np.asarray(x, dtype=float)
    return "(" + ", ".join(_n(v) for v in (x[:2] if dim == cv.PLANAR else x)) + ")"


def _more(k: int, what: str) -> list[Markup]:
    return [tag("p", f"... and {k} more {what}", class_="muted")] if k > 0 else []


def _svg(scene: Any) -> Markup:
    from mbody.present.draw import figure_svg  # matplotlib: on first display only

    return Markup(tag("figure", Markup(figure_svg(scene, prefix=_prefix()))))


# -- Model -------------------------------------------------------------------------------
def model_html(model: Model) -> str:
    """A Model as HTML: bodies, loads, joints and reactions as tables; the body/joint
    graph (up to `MAX_GRAPH` bodies) with tree/loops and mobility.

    Parameters
    ----------
    model : Model

    Returns
    -------
    str
        One ``div`` (well-formed XHTML).
    """
    dim = model.dimension
    kind = "planar" if dim == cv.PLANAR else "spatial"
    parts: list[object] = []
    if model.description:
        parts.append(tag("p", model.description.strip()))
    facts = [f"{kind}, {count(model.n, 'body', 'bodies')}, {count(len(model.loads), 'load')}"
             f", {count(len(model.joints), 'joint')}"]
    if model.file:
        facts.append(f"file {model.file}")
    if np.any(model.gravity):
        facts.append(f"gravity {_v(model.gravity, dim)} m/s² (world axes)")
    parts.append(tag("p", "; ".join(facts)))

    rows = []
    for name in model.body_names[:MAX_ROWS]:
        b = model.bodies[name]
        if b.particle:
            inertia = "particle (no rotational inertia)"
        elif dim == cv.PLANAR:
            inertia = f"I_G {_n(b.I_G)}"
        else:
            J = np.asarray(b.inertia)
            inertia = ("diag " + _v(np.diag(J), 3) if np.allclose(J, np.diag(np.diag(J)))
                       else "full, principal " + _v(np.linalg.eigvalsh(J), 3))
        rows.append([name, _n(b.mass), inertia])
    parts += [tag("p", tag("b", "Bodies"), " in stacking order"),
              table(["body", "mass (kg)", "inertia about G (kg m²)"], rows, numeric=[1]),
              *_more(model.n - MAX_ROWS, "bodies")]
    if model.loads:
        parts += [tag("p", tag("b", "Applied loads"), " (known inputs)"),
                  table(["load", "type", "on", "value", "where"],
                        [_load_row(ld, dim) for ld in model.loads[:MAX_ROWS]]),
                  *_more(len(model.loads) - MAX_ROWS, "loads")]
    asm = assemble(model)
    topo = topology(model, columns=asm.columns) if model.reactions else topology(model)
    if model.joints:
        known = model.known_reactions
        rows = [[j.name, j.type, f"{j.parent} → {j.child}", _v(j.at, dim),
                 ", ".join(f"{k} = {_n(known[k])}" if k in known else k for k in j.labels)]
                for j in model.joints[:MAX_ROWS]]
        parts += [tag("p", tag("b", "Joints"), " and their reaction components "
                      "(constraint forces: unknown unless given)"),
                  table(["joint", "type", "parent → child", "at (world, m)",
                         "reaction components"], rows),
                  *_more(len(model.joints) - MAX_ROWS, "joints")]
    graph = text.graph_summary(model, topo)
    if model.n <= MAX_GRAPH:
        from mbody.present.draw import graph_scene  # networkx and matplotlib

        parts.append(_svg(graph_scene(model, topo)))
    parts.append(tag("pre", graph))
    parts += [tag("p", f"warning: {w}", class_="warn") for w in model.warnings]
    return block(f"Model {model.name!r}", *parts,
                 note="next: asm = mbody.assemble(model); asm.bodies[name]; asm.solve(); "
                      "mbody.simulate(model, t_end)")


def _load_row(ld: Any, dim: int) -> list[str]:
    """name, type, bodies, value with unit and axes, point (a spring: k, rest, damping)."""
    on = " - ".join(ld.bodies)
    if ld.type == "spring":
        return [ld.name, "spring", on, f"k {_n(ld.stiffness)} N/m, damping "
                f"{_n(ld.damping)} N s/m", f"rest length {_n(ld.rest_length)} m"]
    vec = np.zeros(3) if ld.vector is None else ld.vector
    if ld.type == "torque":
        value = (f"{_n(vec[2])} N m" if dim == cv.PLANAR
                 else f"{_v(vec, 3)} N m ({ld.frame} axes)")
        where = "-"
    else:
        value, where = f"{_v(vec, dim)} N ({ld.frame} axes)", f"{_v(ld.at[0], dim)} m from G"
    if ld.expressions:  # the formulas, not their values at t = 0
        value += "; " + ", ".join(f"{'xyz'[k]} = {x}" for k, x in sorted(ld.expressions.items()))
    return [ld.name, ld.type, on, value, where]


# -- equations ---------------------------------------------------------------------------
def _body_parts(eq: BodyEquations, view: str = "iso") -> list[object]:
    from mbody.present.draw import fbd_scene  # matplotlib's fonts lay the labels out

    f, dim = eq.fbd, eq.fbd.dimension
    rows = []
    for fo in f.forces:
        name, point, comp, mom = text.force_cells(fo, dim, minus="−", size=f.size)  # drawn
        what = (("reaction, unknown" if fo.value is None else "reaction, given")
                if fo.kind == REACTION else "couple" if fo.couple else fo.kind)
        rows.append([name, what, point, comp, mom])
    unknown = [fo.label for fo in f.forces if fo.unknown]
    applied = [fo.name for fo in f.forces if fo.kind != REACTION]
    lines = ["Newton (world axes):", *(f"  {x}" for x in eq.newton)]
    lines += ([("Euler (about G, z):" if dim == cv.PLANAR else "Euler (about G, body axes):"),
               *(f"  {x}" for x in eq.euler)] if eq.euler
              else ["Euler: none (a particle has no rotation)"])
    pos = _v(f.W_position, dim)
    return [
        tag("p", f"mass {_n(f.mass)} kg, mass centre at {pos} m (world)"),
        _svg(fbd_scene(f, view=view, equations=False)),
        tag("p", tag("b", "Free body"), " (point from G in body axes; components in world "
            "axes; moment about G" + (")" if dim == cv.PLANAR else " in body axes)")),
        table(["force", "kind", "point (m)", "components", "moment about G (N m)"], rows)
        if rows else tag("p", "(no forces)"),
        tag("p", tag("b", "Applied"), " (known): " + (", ".join(applied) or "none") + "; ",
            tag("b", "constraint"), " (reaction unknowns): " + (", ".join(unknown) or "none")),
        tag("pre", "\n".join(lines)),
    ]


def body_html(eq: BodyEquations, view: str = "iso") -> str:
    """One body as HTML: its free-body diagram, the forces on it as a table (applied
    and constraint forces apart), its Newton-Euler pair and its reaction unknowns.

    Parameters
    ----------
    eq : BodyEquations
        ``asm.bodies[name]``.
    view : str
        Spatial bodies: the diagram's view (`mbody.present.draw.projection`).

    Returns
    -------
    str
        One ``div`` (well-formed XHTML).
    """
    return block(f"Body {eq.body!r}", *_body_parts(eq, view),
                 note="print(it) for the text block; mbody.draw_fbd(it.fbd) for a figure; "
                      ".equations for the rows")


def assembly_html(asm: Assembly) -> str:
    """An Assembly as HTML: the stacked system's sizes, then each body (up to
    `MAX_BODIES`) as in `body_html`.

    Parameters
    ----------
    asm : Assembly

    Returns
    -------
    str
        One ``div`` (well-formed XHTML).
    """
    model = asm.model
    rows = cv.PLANAR_ROWS if model.dimension == cv.PLANAR else cv.SPATIAL_ROWS
    unknown = [r for r in asm.reactions if r not in model.known_reactions]
    sizes = table(["", "size", "holds"], [
        [k, " × ".join(map(str, v)), what] for (k, v), what in zip(asm.shape.items(), (
            "block-diagonal masses and inertias", "gyroscopic terms ω × (J ω)",
            "applied forces and moments", "one column per reaction component"), strict=True)])
    parts: list[object] = [
        tag("p", f"M v̇ + b = Q + G λ at t = {asm.state.t:g} s; rows per body: "
            + ", ".join(rows) + ("" if model.dimension == cv.PLANAR else
                                 " (Newton in world axes, Euler in body axes)")
            + f"; {len(asm.reactions)} reaction components, {len(unknown)} unknown"),
        sizes]
    for name in model.body_names[:MAX_BODIES]:
        parts += [tag("h4", f"Body {name!r}"), *_body_parts(asm.bodies[name])]
    parts += _more(model.n - MAX_BODIES, "bodies: asm.bodies[name]")
    return block(f"Assembly of {model.name!r}", *parts,
                 note="next: asm.solve() for accelerations and reactions; asm.bodies[name]; "
                      "asm.M, asm.b, asm.Q, asm.G")


def _clean(x: np.ndarray, rel: float = 1e-10) -> np.ndarray:
    """Values below `rel` times the largest written 0: rounding noise, not data."""
    x = np.asarray(x, dtype=float)
    return np.where(np.abs(x) <= rel * float(np.max(np.abs(x), initial=0.0)), 0.0, x)


def _unit(label: str) -> str:
    """A reaction component's unit: moments in N m, forces and tensions in N."""
    return joint_types.unit(label)


def solution_html(sol: Solution) -> str:
    """A Solution as HTML: accelerations by body with units, then every reaction
    component with its unit and whether it was solved or given.

    Parameters
    ----------
    sol : Solution

    Returns
    -------
    str
        One ``div`` (well-formed XHTML).
    """
    by_body: dict[str, list[str]] = {}
    acc = _clean(sol.accelerations)
    for label, a in zip(sol.coordinates, acc, strict=True):
        body, row = label.rsplit(".", 1)
        unit = "m/s²" if row in ("x", "y", "z") else "rad/s²"
        by_body.setdefault(body, []).append(f"{cv.ACCELERATION_NAMES.get(row, row)} = "
                                            f"{_n(a)} {unit}")
    spatial = any(c.endswith(".w1") for c in sol.coordinates)
    parts: list[object] = [
        tag("p", tag("b", "Accelerations"), " (a: mass centre, world axes; "
            + ("ω̇: body axes)" if spatial else "alpha: about z)")),
        table(["body", "accelerations"],
              [[b, ", ".join(v)] for b, v in itertools.islice(by_body.items(), MAX_ROWS)]),
        *_more(len(by_body) - MAX_ROWS, "bodies: sol.as_dict()")]
    labels = list(sol.reactions)
    if labels:
        lam = _clean(np.array([sol.reactions[r] for r in labels]))
        solved, free = set(sol.solved), set(sol.not_unique)
        status = {lab: "not unique" if lab in free else "solved" for lab in solved}
        world = sol.axes == "world"
        if world:  # a joint's world force and moment mix its components: theirs decide
            by_joint: dict[str, set[str]] = {}
            for lab, st in status.items():
                by_joint.setdefault(lab.split(".", 1)[0], set()).add(st)
            status = {j: st.pop() if len(st) == 1 else "partly solved"
                      for j, st in by_joint.items()}
        rows = [[lab, f"{_n(v)} {_unit(lab)}",
                 status.get(lab.split(".", 1)[0] if world else lab, "given")]
                for lab, v in zip(labels[:MAX_ROWS], lam, strict=False)]
        where = ("each joint's force and moment on its child, world axes" if world else
                 "on the child, along the joint axes")
        parts += [tag("p", tag("b", "Reactions"), f" ({where})"),
                  table(["component", "value", "status"], rows, numeric=[1]),
                  *_more(len(labels) - MAX_ROWS, "components: sol.reactions")]
    if sol.residual is not None:
        parts.append(tag("p", f"solve: {sol.method}; relative backward error "
                              f"{sol.residual:.1e}", class_="muted"))
    parts += [tag("p", f"warning: {w}", class_="warn") for w in sol.warnings]
    return block("Solution", *parts, note="sol[label], sol.as_dict(), sol.reactions[label]")


def equation_latex(eq: Equation) -> str:
    """One row as display math (``$$ ... $$``) for Jupyter.

    Parameters
    ----------
    eq : Equation

    Returns
    -------
    str
    """
    return "$$\\begin{aligned}" + latex.equation_latex(eq) + "\\end{aligned}$$"


def body_latex(eq: BodyEquations) -> str:
    """One body's Newton-Euler pair as display math (`mbody.present.latex.body_latex`).

    Parameters
    ----------
    eq : BodyEquations

    Returns
    -------
    str
    """
    return "$$" + latex.body_latex(eq) + "$$"


def assembly_latex(asm: Assembly) -> str:
    """The stacked system as display math (`mbody.present.latex.stacked_latex`).

    Parameters
    ----------
    asm : Assembly

    Returns
    -------
    str
    """
    return "$$" + latex.stacked_latex(asm) + "$$"


# -- Trajectory --------------------------------------------------------------------------
def _plot_png(traj: Trajectory) -> Markup:
    from mbody.present.draw import figure_bytes  # matplotlib
    from mbody.present.plot import plot_trajectory

    png = base64.b64encode(figure_bytes(plot_trajectory(traj), "png", dpi=PLOT_DPI))
    return Markup(tag("figure", tag("img", src="data:image/png;base64," + png.decode("ascii"),
                                    alt="angular velocities, energy, angular momentum, "
                                        "drift" + (", reactions" if traj.reaction_labels
                                                   else ""))))


def trajectory_html(traj: Trajectory) -> str:
    """A Trajectory as HTML: the run's facts, its plots (a PNG: ω, energy, angular
    momentum, drift, reactions) and, with `EMBED_ANIMATION` (the default), the 3-D
    animation.

    Parameters
    ----------
    traj : Trajectory

    Returns
    -------
    str
        One ``div`` (well-formed XHTML).
    """
    info = traj.info
    t = traj.t
    facts = [["bodies", ", ".join(traj.body_names[:12])
              + (f" ... ({traj.n})" if traj.n > 12 else "")],
             ["samples", f"{len(t)}, t = {t[0]:g} .. {t[-1]:g} s" if len(t) else "none"]]
    if "integrator" in info:
        facts.append(["integrator", f"{info['integrator']}, rtol {info.get('rtol', '?')}, "
                                    f"{info.get('steps', '?')} steps"])
    # a drift figure where the model conserves the quantity, else why it does not
    facts += [[what, said] for what, said in conserved_lines(info)]
    if isinstance(info.get("joint_position_drift"), float):
        facts.append(["joint position drift (m)", f"{info['joint_position_drift']:.2e}"])
    if traj.reaction_labels:
        facts.append(["reaction series", ", ".join(traj.reaction_labels[:20])
                      + (" ..." if len(traj.reaction_labels) > 20 else "")
                      + (" (world axes)" if info.get("reaction_axes") == "world" else "")])
    parts: list[object] = [table(["", ""], facts)]
    if len(t) > 1 and traj.mass is not None:
        parts.append(_plot_png(traj))
    parts += [tag("p", f"warning: {w}", class_="warn") for w in info.get("warnings", [])]
    if EMBED_ANIMATION and traj.model_yaml:
        parts.append(Markup(Animation(traj)._repr_html_()))
    return block(f"Trajectory of {traj.model_name or 'a model'!r}", *parts,
                 note="next: mbody.present.rich.animation(traj, reactions=True) for the "
                      "reaction arrows, mbody.animate(traj, 'run.html', model=model) for a "
                      "page, traj.save('run.npz')")


class Animation:
    """The offline 3-D animation page of a trajectory, shown in a notebook as an
    ``iframe`` whose ``srcdoc`` is the whole page (meshcat's viewer inlined, about
    0.9 MB; nothing is fetched).

    Parameters
    ----------
    traj : Trajectory
        The motion.
    model : Model, optional
        Its model (default: rebuilt from the YAML text the trajectory carries).
    height : int
        The frame's height in pixels.
    **options
        Passed to `mbody.present.animate.build_scene`: ``forces``, ``reactions``,
        ``bodies``.
    """

    def __init__(self, traj: Trajectory, model: Model | None = None, *, height: int = 420,
                 **options: Any):
        self.traj, self.model, self.height, self.options = traj, model, height, options

    def page(self) -> str:
        """The page's HTML text (`mbody.present.animate.page_html`).

        Returns
        -------
        str
        """
        model = self.model if self.model is not None else self.traj.model()
        return page_html(build_scene(self.traj, model, **self.options))

    def __repr__(self) -> str:
        return (f"<Animation of {self.traj.model_name!r}: {len(self.traj)} samples; shown as "
                "an iframe in a notebook, .page() for the HTML>")

    def _repr_html_(self) -> str:
        return str(tag("iframe", srcdoc=self.page(), width="100%", height=str(self.height),
                       style="border:1px solid #ccd", title="mbody animation"))


def animation(traj: Trajectory, model: Model | None = None, **options: Any) -> Animation:
    """The trajectory's 3-D animation, to show in a notebook (see `Animation`).

    Parameters
    ----------
    traj : Trajectory
    model : Model, optional
        Default: rebuilt from the trajectory's stored YAML.
    **options
        ``height`` (pixels), and `build_scene`'s ``forces``, ``reactions``, ``bodies``.

    Returns
    -------
    Animation
    """
    return Animation(traj, model, **options)


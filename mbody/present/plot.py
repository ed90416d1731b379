"""Plots of a trajectory: what people look at after a run.

    ω(t) body axes;  T(t) = ½ Σ m vᵀv + ½ Σ ωᵀ J ω  (and E = T + V);  H(t) world axes;
    drift  |E(t) − E(0)| / max(|E(0)|, max T)  and  ‖H(t) − H(0)‖ / max ‖H‖

One `matplotlib.figure.Figure` (Agg canvas, no pyplot: safe in scripts, servers and
tests); `save_plot` draws it in memory and writes it atomically, the format taken from
the file's extension.
"""

from __future__ import annotations

import io
import os
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mbody import conventions as cv
from mbody import joint_types
from mbody.conventions import check_axes
from mbody.errors import MbodyError, option_name, option_setting
from mbody.present.draw.fonts import drawable
from mbody.simulate.axes import in_world_axes
from mbody.simulate.trajectory import Trajectory
from mbody.util.atomic import write_atomic

MAX_BODIES = 6
"""Bodies drawn in the angular-velocity panel (the rest are summed in the others)."""
FORMATS = ("png", "pdf", "svg")


def _text(name: str) -> str:
    """A name as the figure can draw it: characters DejaVu Sans lacks as <U+XXXX>, and a
    '$' that would start mathtext escaped."""
    return drawable(name).replace("$", r"\$")


def _energy_momentum(traj: Trajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """(T, E, H, momentum label), from the run's series when present."""
    s = traj.series
    T = s["kinetic_energy"] if "kinetic_energy" in s else traj.kinetic_energy()
    E = s.get("energy", T)
    if "angular_momentum" in s:
        H = s["angular_momentum"]
        kind = traj.info.get("angular_momentum_kind", "about the world origin")
    else:
        H, kind = traj.angular_momentum(), "total, about the world origin"
    return T, E, H, kind


def _relative(x: np.ndarray, scale: float) -> np.ndarray:
    """|x − x(0)| / scale, floored at 1e-17 so that a log axis can show exact zeros."""
    d = np.abs(x - x[0]) if x.ndim == 1 else np.linalg.norm(x - x[0], axis=1)
    return np.maximum(d / scale, 1e-17) if scale > 0 else np.full(len(x), 1e-17)


def plot_trajectory(traj: Trajectory, bodies: list[str] | None = None) -> Figure:
    """Panels two to a row: ω components, energy, angular momentum, relative drift, and for
    a run with joint reactions their force and moment components. A panel with nothing to
    show (no moment components: a planar revolute joint, a spherical one) is left out, not
    drawn as empty axes; an odd last panel spans its row."""
    traj.need_samples()
    names = list(bodies) if bodies else list(traj.body_names[:MAX_BODIES])
    unknown = [b for b in names if b not in traj.body_names]
    if unknown:
        raise MbodyError(f"no body named {unknown[0]!r} in this trajectory")
    idx = [traj.body_names.index(b) for b in names]
    t = traj.t
    T, E, H, kind = _energy_momentum(traj)

    panels: list[Callable[[Axes], None]] = [
        lambda a: _omega_panel(traj, a, idx, names),
        lambda a: _energy_panel(t, T, E, a),
        lambda a: _momentum_panel(traj, H, kind, a),
        lambda a: _drift_panel(traj, T, E, H, a),
    ]
    for moment in (False, True):
        sel = _reaction_columns(traj, moment)
        if sel:
            panels.append(partial(_reaction_panel, traj, moment=moment, sel=sel))

    rows = (len(panels) + 1) // 2
    fig = Figure(figsize=(11, 1.5 + 3 * rows), layout="constrained")
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(rows, 2)
    title = (f"{_text(traj.model_name or 'trajectory')}: {traj.n} "
             f"bod{'y' if traj.n == 1 else 'ies'}")
    if traj.info:
        title += (f", {traj.info.get('integrator', '')} rtol {traj.info.get('rtol', 0):g}")
    if len(panels) > 4:  # reactions shown: say in which axes
        title += f"; reactions in {_axes_words(traj)}"
    fig.suptitle(title)
    for k, draw in enumerate(panels):
        r, c = divmod(k, 2)
        lone = k == len(panels) - 1 and c == 0
        a = fig.add_subplot(grid[r, :] if lone else grid[r, c])
        draw(a)
        a.set_xlabel("t (s)")
        a.grid(True, alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize="small", ncol=2 if len(a.lines) > 6 else 1)
    return fig


def _omega_panel(traj: Trajectory, a: Axes, idx: list[int], names: list[str]) -> None:
    t, w = traj.t, traj.angular_velocity
    for i, b in zip(idx, names, strict=True):
        shown = _text(b)
        if traj.dimension == cv.PLANAR:
            a.plot(t, w[:, i], label=f"{shown} θ̇")
        else:
            for c in range(3):
                a.plot(t, w[:, i, c], label=f"{shown} ω{c + 1}")
    shown = "" if len(names) == traj.n else f" (first {len(names)} of {traj.n} bodies)"
    a.set_title("angular velocity, body axes" + shown)
    a.set_ylabel("rad/s")


def _energy_panel(t: np.ndarray, T: np.ndarray, E: np.ndarray, a: Axes) -> None:
    a.plot(t, T, label="kinetic T")
    if not np.allclose(E, T):
        a.plot(t, E, label="T + V")
    # From zero: a conserved energy is a flat line, not rounding noise blown up.
    lo, hi = min(0.0, float(T.min()), float(E.min())), max(float(T.max()), float(E.max()))
    a.set_ylim(lo - 0.05 * (hi - lo + 1e-300), hi + 0.05 * (hi - lo) + 1e-300)
    a.set_title("energy")
    a.set_ylabel("J")


def _momentum_panel(traj: Trajectory, H: np.ndarray, kind: str, a: Axes) -> None:
    t = traj.t
    if traj.dimension == cv.PLANAR:
        a.plot(t, H[:, 2], label="H_z")
    else:
        for c, lab in enumerate("xyz"):
            a.plot(t, H[:, c], label=f"H_{lab}")
        a.plot(t, np.linalg.norm(H, axis=1), "k--", lw=1, label="|H|")
    a.set_title(f"angular momentum, world axes ({kind})")
    a.set_ylabel("kg m²/s")


def _drift_panel(traj: Trajectory, T: np.ndarray, E: np.ndarray, H: np.ndarray,
                 a: Axes) -> None:
    t = traj.t
    e_scale = max(abs(float(E[0])), float(np.max(np.abs(T))))
    h_scale = float(np.max(np.linalg.norm(H, axis=1)))
    a.semilogy(t, _relative(E, e_scale), label="energy")
    a.semilogy(t, _relative(H, h_scale), label="angular momentum")
    conserved = [q for q, key in (("energy", "energy_conserved"),
                                  ("momentum", "angular_momentum_conserved"))
                 if traj.info.get(key)]
    a.set_title("relative change" + (f" (conserved: {', '.join(conserved)})"
                                      if conserved else " (nothing conserved)"))


MAX_REACTIONS = 12
"""Reaction components drawn per panel (the first ones in label order)."""


def _reaction_columns(traj: Trajectory, moment: bool) -> list[int]:
    """Columns of `traj.reactions` holding moment (N m) or force (N) components."""
    if not traj.reaction_labels or traj.reactions.ndim != 2 or traj.reactions.shape[1] == 0:
        return []
    return [k for k, lab in enumerate(traj.reaction_labels)
            if joint_types.is_moment(lab) == moment]


def _axes_words(traj: Trajectory) -> str:
    """The axes a run's reactions are in, in words (``info["reaction_axes"]``; a run saved
    before world axes existed is in joint axes)."""
    return "world axes" if traj.info.get("reaction_axes") == "world" else "joint axes"


def _reaction_panel(traj: Trajectory, a: Axes, *, moment: bool, sel: list[int]) -> None:
    """Reaction components over time, forces (N) or moments (N m), acting +R on the
    child and −R on the parent: each along its joint-frame axis, or in world axes each
    joint's force and moment on its child (``info["reaction_axes"]``)."""
    labels = list(traj.reaction_labels)
    for k in sel[:MAX_REACTIONS]:
        a.plot(traj.t, traj.reactions[:, k], label=_text(labels[k]))
    more = f" (first {MAX_REACTIONS} of {len(sel)})" if len(sel) > MAX_REACTIONS else ""
    a.set_title(f"joint reaction {'moments' if moment else 'forces'}, {_axes_words(traj)}"
                f"{more}")
    a.set_ylabel("N m" if moment else "N")


def save_plot(traj: Trajectory, path: str | os.PathLike[str], bodies: list[str] | None = None,
              dpi: int = 120, against: str | None = None, motion: bool = False,
              axes: str | None = None) -> Path:
    """Plot `traj` and write the figure atomically; format from the extension. A run with
    drivers gets their figure (`mbody.present.drive_plot`, against `against`: 'time' or a
    driver) unless `motion` asks for the bodies' motion. `axes`: the reactions' axes,
    'world' (a run saved in joint axes is turned into world axes with the model it
    carries, `mbody.simulate.axes.in_world_axes`) or 'joint'; None: as saved."""
    from mbody.present.drive_plot import drivers_of, plot_driven

    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in FORMATS:
        raise MbodyError(f"cannot write {str(path)!r}: the plot format comes from the "
                         f"extension, one of {', '.join('.' + f for f in FORMATS)}")
    if axes is not None:
        check_axes(axes)
        saved = traj.info.get("reaction_axes", "joint")
        if axes == "world":
            traj = in_world_axes(traj)
        elif saved == "world" and len(traj.reaction_labels):
            world = option_setting("axes", "world")
            raise MbodyError("this run stores its reactions in world axes (it was made with "
                             f"{world}), which do not give back the joint-frame "
                             f"components; plot it without {option_setting('axes', 'joint')}, "
                             f"or run it again without {world}")
    if against is not None and (motion or not drivers_of(traj)):
        raise MbodyError(f"{option_name('against')} applies to a run with drivers (their "
                         "figure), not to the motion's")
    fig = (plot_driven(traj, against) if drivers_of(traj) and not motion
           else plot_trajectory(traj, bodies))
    # drawn in memory first: a writer failing half-way (a full disk) must meet a complete
    # picture, not matplotlib's pdf or png stream in the middle of its compression
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=dpi)
    return write_atomic(path, buf.getvalue())

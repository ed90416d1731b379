"""Plots of a trajectory: what people look at after a run.

    ω(t) body axes;  T(t) = ½ Σ m vᵀv + ½ Σ ωᵀ J ω  (and E = T + V);  H(t) world axes;
    drift  |E(t) − E(0)| / max(|E(0)|, max T)  and  ‖H(t) − H(0)‖ / max ‖H‖

One `matplotlib.figure.Figure` (Agg canvas, no pyplot: safe in scripts, servers and
tests); `save_plot` writes it atomically, the format taken from the file's extension.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mbody import conventions as cv
from mbody.errors import MbodyError
from mbody.io.atomic import atomic_path
from mbody.simulate.trajectory import Trajectory

MAX_BODIES = 6
"""Bodies drawn in the angular-velocity panel (the rest are summed in the others)."""
FORMATS = ("png", "pdf", "svg")


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
    """A 2 × 2 figure: ω components, energy, angular momentum, relative drift."""
    names = list(bodies) if bodies else list(traj.body_names[:MAX_BODIES])
    unknown = [b for b in names if b not in traj.body_names]
    if unknown:
        raise MbodyError(f"no body named {unknown[0]!r} in this trajectory")
    idx = [traj.body_names.index(b) for b in names]
    t = traj.t
    T, E, H, kind = _energy_momentum(traj)

    has_reactions = bool(traj.reaction_labels) and traj.reactions.shape[1] > 0
    fig = Figure(figsize=(11, 10.5 if has_reactions else 7.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots(3 if has_reactions else 2, 2)
    title = f"{traj.model_name or 'trajectory'}: {traj.n} bod{'y' if traj.n == 1 else 'ies'}"
    if traj.info:
        title += (f", {traj.info.get('integrator', '')} rtol {traj.info.get('rtol', 0):g}")
    fig.suptitle(title)

    a = ax[0, 0]
    w = traj.angular_velocity
    for i, b in zip(idx, names, strict=True):
        if traj.dimension == cv.PLANAR:
            a.plot(t, w[:, i], label=f"{b} θ̇")
        else:
            for c in range(3):
                a.plot(t, w[:, i, c], label=f"{b} ω{c + 1}")
    shown = "" if len(names) == traj.n else f" (first {len(names)} of {traj.n} bodies)"
    a.set_title("angular velocity, body axes" + shown)
    a.set_ylabel("rad/s")

    a = ax[0, 1]
    a.plot(t, T, label="kinetic T")
    if not np.allclose(E, T):
        a.plot(t, E, label="T + V")
    # From zero: a conserved energy is a flat line, not rounding noise blown up.
    lo, hi = min(0.0, float(T.min()), float(E.min())), max(float(T.max()), float(E.max()))
    a.set_ylim(lo - 0.05 * (hi - lo + 1e-300), hi + 0.05 * (hi - lo) + 1e-300)
    a.set_title("energy")
    a.set_ylabel("J")

    a = ax[1, 0]
    if traj.dimension == cv.PLANAR:
        a.plot(t, H[:, 2], label="H_z")
    else:
        for c, lab in enumerate("xyz"):
            a.plot(t, H[:, c], label=f"H_{lab}")
        a.plot(t, np.linalg.norm(H, axis=1), "k--", lw=1, label="|H|")
    a.set_title(f"angular momentum, world axes ({kind})")
    a.set_ylabel("kg m²/s")

    a = ax[1, 1]
    e_scale = max(abs(float(E[0])), float(np.max(np.abs(T))))
    h_scale = float(np.max(np.linalg.norm(H, axis=1)))
    a.semilogy(t, _relative(E, e_scale), label="energy")
    a.semilogy(t, _relative(H, h_scale), label="angular momentum")
    conserved = [q for q, key in (("energy", "energy_conserved"),
                                  ("momentum", "angular_momentum_conserved"))
                 if traj.info.get(key)]
    a.set_title("relative change" + (f" (conserved: {', '.join(conserved)})"
                                      if conserved else " (nothing conserved)"))
    if has_reactions:
        _reaction_panels(traj, ax[2, 0], ax[2, 1])
    for a in ax.flat:
        a.set_xlabel("t (s)")
        a.grid(True, alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize="small", ncol=2 if len(a.lines) > 6 else 1)
    return fig


MAX_REACTIONS = 12
"""Reaction components drawn per panel (the first ones in label order)."""


def _reaction_panels(traj: Trajectory, forces_ax, moments_ax) -> None:
    """Reaction components over time: forces (N) on one panel, moments (N m) on the other;
    each on its joint frame axis, acting +R on the child and −R on the parent."""
    labels = list(traj.reaction_labels)
    for ax, moment, unit in ((forces_ax, False, "N"), (moments_ax, True, "N m")):
        sel = [k for k, lab in enumerate(labels) if lab.split(".", 1)[1].startswith("M") == moment]
        for k in sel[:MAX_REACTIONS]:
            ax.plot(traj.t, traj.reactions[:, k], label=labels[k])
        more = f" (first {MAX_REACTIONS} of {len(sel)})" if len(sel) > MAX_REACTIONS else ""
        ax.set_title(f"joint reaction {'moments' if moment else 'forces'}, joint axes{more}"
                     if sel else f"no joint reaction {'moments' if moment else 'forces'}")
        ax.set_ylabel(unit)


def save_plot(traj: Trajectory, path: str | os.PathLike[str], bodies: list[str] | None = None,
              dpi: int = 120) -> Path:
    """Plot `traj` and write the figure atomically; format from the extension."""
    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in FORMATS:
        raise MbodyError(f"cannot write {str(path)!r}: the plot format comes from the "
                         f"extension, one of {', '.join('.' + f for f in FORMATS)}")
    fig = plot_trajectory(traj, bodies)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=dpi)
    return Path(path)

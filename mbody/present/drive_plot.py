"""The figure of a driven run: what the motors give and the bearings carry.

    efforts (N m, N) │ bearing loads |F| per joint (N)
    force components │ power: drivers', applied loads', d(T + V)/dt (W)

against the first driver's coordinate (degrees for an angle, unwrapped: a revolution
reads 0..360 from the start) or against time. A run that stores its drivers (series
``driver:<name>``, `mbody.simulate.kinematic.driver_series`) gets it from `save_plot`.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mbody import joint_types
from mbody.errors import MbodyError, did_you_mean, option_name, option_setting
from mbody.present.draw.fonts import drawable
from mbody.simulate.trajectory import Trajectory

MAX_LINES = 12
"""Lines drawn per panel (the first ones in label order)."""


def drivers_of(traj: Trajectory) -> list[dict]:
    """The run's drivers as saved (name, joint, kind, effort label); [] without."""
    facts = traj.info.get("drivers") or []
    return [f for f in facts if f"driver:{f.get('name')}" in traj.series]


def plot_driven(traj: Trajectory, against: str | None = None) -> Figure:
    """The four panels of the module doc; `against` is 'time' or a driver's name (default:
    the first driver)."""
    drivers = drivers_of(traj)
    if not drivers:
        raise MbodyError(f"this run has no drivers: plot it without {option_name('against')}")
    names = [d["name"] for d in drivers]
    if against is None:
        against = names[0]
    if against != "time" and against not in names:
        hint = did_you_mean(against, ["time", *names])
        raise MbodyError(f"{option_setting('against', against)}: expected 'time' or a driver "
                         f"of this run ({', '.join(names)})" + (f"; {hint}" if hint else ""))
    x, xlabel = _abscissa(traj, drivers, against)
    fig = Figure(figsize=(11, 8), layout="constrained")
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(2, 2)
    axes = ((traj.info.get("reaction_axes") or "joint") + " axes").replace(
        "joint axes", "joint-frame axes")
    fig.suptitle(f"{drawable(traj.model_name or 'run')}: driven by "
                 f"{', '.join(names)}; reactions in {axes}")
    panels = (partial_efforts, partial_bearings, partial_components, partial_power)
    for k, draw in enumerate(panels):
        a = fig.add_subplot(grid[divmod(k, 2)])
        draw(traj, drivers, x, a)
        a.set_xlabel(xlabel)
        a.grid(True, alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize="small", ncol=2 if len(a.lines) > 6 else 1)
        if against != "time" and drivers[names.index(against)]["kind"] == "angle":
            _degree_ticks(a, x)
    return fig


def _abscissa(traj: Trajectory, drivers: list[dict], against: str
              ) -> tuple[np.ndarray, str]:
    if against == "time":
        return traj.t, "t (s)"
    d = next(f for f in drivers if f["name"] == against)
    q = np.asarray(traj.series[f"driver:{against}"], dtype=float)
    if d["kind"] == "angle":
        q = np.degrees(q - q[0]) + math.degrees(float(q[0])) % 360.0
        return q, f"{against}: {d['joint']}'s angle (deg)"
    return q, f"{against}: {d['joint']}'s displacement (m)"


def _degree_ticks(a: Axes, x: np.ndarray) -> None:
    span = float(np.ptp(x)) if len(x) else 0.0
    if 90 <= span <= 2000:
        step = 45 if span <= 400 else 90 if span <= 800 else 180
        lo = math.floor(float(x.min()) / step) * step
        a.set_xticks(np.arange(lo, float(x.max()) + step, step))
        a.set_xlim(float(x.min()), float(x.max()))


def _labels(traj: Trajectory) -> list[str]:
    return list(traj.reaction_labels)


def partial_efforts(traj: Trajectory, drivers: list[dict], x: np.ndarray, a: Axes) -> None:
    labels = _labels(traj)
    for d in drivers:
        if d["effort"] in labels:
            unit = "N m" if d["kind"] == "angle" else "N"
            a.plot(x, traj.reactions[:, labels.index(d["effort"])],
                   label=f"{drawable(d['effort'])} ({unit})")
    a.axhline(0.0, color="k", lw=0.6)
    a.set_title("drivers' efforts (torque about, or force along, the driven axis)")
    units = sorted({"N m" if d["kind"] == "angle" else "N" for d in drivers})
    a.set_ylabel("  |  ".join(units))


def _force_groups(traj: Trajectory, drivers: list[dict]) -> dict[str, list[int]]:
    """joint -> the columns of its force components (not the drivers' efforts)."""
    efforts = {d["effort"] for d in drivers}
    out: dict[str, list[int]] = {}
    for k, lab in enumerate(_labels(traj)):
        if lab in efforts or joint_types.is_moment(lab):
            continue
        out.setdefault(lab.split(".", 1)[0], []).append(k)
    return out


def partial_bearings(traj: Trajectory, drivers: list[dict], x: np.ndarray, a: Axes) -> None:
    """|F| of each joint: the same in any axes (the components are orthonormal)."""
    for joint, cols in list(_force_groups(traj, drivers).items())[:MAX_LINES]:
        F = np.sqrt((traj.reactions[:, cols] ** 2).sum(axis=1))
        a.plot(x, F, label=f"|{drawable(joint)}|")
    a.set_ylim(bottom=0.0)
    a.set_title("bearing loads: each joint's force magnitude")
    a.set_ylabel("N")


def partial_components(traj: Trajectory, drivers: list[dict], x: np.ndarray, a: Axes
                       ) -> None:
    cols = [k for ks in _force_groups(traj, drivers).values() for k in ks]
    labels = _labels(traj)
    for k in cols[:MAX_LINES]:
        a.plot(x, traj.reactions[:, k], label=drawable(labels[k]))
    axes = "world axes" if traj.info.get("reaction_axes") == "world" else "joint-frame axes"
    more = f" (first {MAX_LINES} of {len(cols)})" if len(cols) > MAX_LINES else ""
    a.set_title(f"force components on the child, {axes}{more}")
    a.set_ylabel("N")


def partial_power(traj: Trajectory, drivers: list[dict], x: np.ndarray, a: Axes) -> None:
    s = traj.series
    if "driver_power" in s:
        a.plot(x, s["driver_power"], label="drivers' power")
    if "load_power" in s and np.any(s["load_power"]):
        a.plot(x, s["load_power"], label="applied loads' power")
    if "energy" in s and len(traj.t) > 2:
        a.plot(x, np.gradient(s["energy"], traj.t, edge_order=2), "k--", lw=1,
               label="d(T + V)/dt")
    a.axhline(0.0, color="k", lw=0.6)
    a.set_title("power (the two powers add up to d(T + V)/dt)")
    a.set_ylabel("W")

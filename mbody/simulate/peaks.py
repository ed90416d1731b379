"""A run's peaks: each reaction's and driver's effort's largest magnitude over the run,
when it happens, and where the first driver is then (what the summary of a run with
drivers prints, and what its JSON gives); and whether the samples are close enough for
those peaks (`sampling_warning`). Every run of a model with drivers records both through
`record_peaks`: a kinematic run (`mbody.simulate.kinematic`) and an integrated one of a
partly driven mechanism (`mbody.simulate`) alike."""

from __future__ import annotations

import math

import numpy as np

from mbody.model.expressions import Expression
from mbody.model.model import Model
from mbody.simulate.trajectory import Trajectory

PEAK_SAMPLES = 36
"""Samples a revolution, of a driver turning at a steady rate, below which a run's peaks
are warned about (`sampling_warning`). A load that varies as a sine of the driver's
angle, sampled N times a revolution, reads at its largest sample as little as
cos(pi / N) of its peak (the peak half-way between two samples): 1 - cos(pi / N) is 13 %
at N = 6, 1.5 % at 18, 0.38 % at 36 and 0.1 % at 72. A mechanism's loads carry the
rate's harmonics too, the h-th read up to 1 - cos(h pi / N) low: the shipped driven
slider-crank's peaks, sampled 36 times a revolution, read at most 0.8 % low whatever the
samples' phase (the motor torque; the main bearing's 0.35 %), and 6 times a revolution up
to 25 %. One sample every 10 degrees keeps a sine's peak within 0.4 % and the
slider-crank's within 1 %."""
SPARSE = "peaks sampled too sparsely"
"""How the warning of samples too sparse for the drivers' motion begins."""


def reaction_unit(label: str) -> str:
    """The unit of a run's reaction or effort by its label: "N m" for a moment (a
    component ``M...``: ``O.Mz``, ``motor.M``), else "N"."""
    return "N m" if label.rsplit(".", 1)[-1].startswith("M") else "N"


def peaks(model: Model, traj: Trajectory) -> list[dict]:
    """Each reaction's and effort's largest magnitude over the run: label, value (signed),
    unit, time, and the first driver's coordinate then (its law at that time: degrees
    for an angle, m for a displacement)."""
    d = model.drivers
    out: list[dict] = []
    if not len(traj.reaction_labels) or not len(traj.t):
        return out
    R = np.asarray(traj.reactions)
    at = np.argmax(np.abs(R), axis=0)
    for c, label in enumerate(traj.reaction_labels):
        k = int(at[c])
        tk = float(traj.t[k])
        entry = {"label": label, "value": float(R[k, c]),
                 "unit": reaction_unit(label),
                 "t": tk}
        if d is not None and len(d.names):
            value = float(d.laws[0][0](tk))
            angle = d.component[0] == "M"
            entry["driver"] = d.names[0]
            entry["driver_value"] = math.degrees(value) if angle else value
            entry["driver_unit"] = "deg" if angle else "m"
        out.append(entry)
    return out


def record_peaks(model: Model, traj: Trajectory) -> None:
    """What every run of a model with drivers stores of its peaks: ``info["peaks"]``
    (`peaks`) and, when its samples are too sparse for the drivers' motion, that warning
    among ``info["warnings"]`` (`sampling_warning`)."""
    traj.info["peaks"] = peaks(model, traj)
    warning = sampling_warning(model, traj)
    if warning:
        traj.info.setdefault("warnings", []).append(warning)


def steady_rate(rate: Expression, t: np.ndarray) -> float | None:
    """A driver's rate f′ (rad/s or m/s) when it has one nonzero value at every time in
    `t` (a ``speed`` driver, a law of constant slope), else None."""
    times = np.asarray(t, dtype=float)
    values = np.broadcast_to(np.asarray(rate(times), dtype=float), times.shape)
    if not values.size:
        return None
    w = float(values.flat[0])
    if w == 0.0 or not math.isfinite(w) or float(np.abs(values - w).max()) > 1e-12 * abs(w):
        return None
    return w


def steady_turning(model: Model, t: np.ndarray) -> list[int]:
    """The drivers that turn a joint (an angle) at a steady rate at the times t
    (`steady_rate`): those whose samples a revolution `sampling_warning` checks."""
    d = model.drivers
    if d is None:
        return []
    return [i for i, (component, law) in enumerate(zip(d.component, d.laws, strict=True))
            if component == "M" and steady_rate(law[1], t) is not None]


def samples_a_turn(per_second: float, rate: float) -> float:
    """Samples a revolution of a driver turning at `rate` (rad/s), `per_second` samples
    per second."""
    return 2.0 * math.pi * per_second / abs(rate)


def sparse_text(name: str, rate: float, per_turn: float, sampling: str) -> str:
    """The start of the warning of `PEAK_SAMPLES` not reached: driver `name` turns at
    `rate` (rad/s) and `sampling` ("60 fps is", "its run has") `per_turn` samples a
    revolution of it; how low a peak between two samples can read (1 - cos(pi / N) for a
    sine of the driver's angle)."""
    n = f"{per_turn:.3g}"
    low = (f"up to {100.0 * (1.0 - math.cos(math.pi / per_turn)):.2g} % low when the load "
           f"varies as a sine of {name}'s angle (1 - cos(180 deg / {n})), more with its "
           "harmonics" if per_turn > 2.0 else
           "as low as nothing: two samples a revolution or fewer can miss it entirely")
    return (f"{SPARSE}: {name} turns at {abs(rate) * 30.0 / math.pi:.4g} rpm, and "
            f"{sampling} {n} samples a revolution; a peak that falls between two samples "
            f"reads {low}")


def sampling_warning(model: Model, traj: Trajectory) -> str | None:
    """The warning of a run sampled fewer than `PEAK_SAMPLES` times a revolution of a
    driver turning at a steady rate (the fastest such driver): its peaks can read low.
    It says how many samples a revolution there are, how low a sampled peak can read
    (1 - cos(pi / N) for a sine of the driver's angle), and what to do: a higher fps, or
    for a fully driven mechanism `mbody kinematics`, whose default is a sample a degree.
    None without such a driver (a law whose rate varies is not checked) or with fewer
    than two samples."""
    d = model.drivers
    fps = float(traj.info.get("fps") or 0.0)
    if d is None or not len(d.names) or fps <= 0.0 or len(traj.t) < 2:
        return None
    fastest: tuple[float, str, float] | None = None  # (samples a revolution, name, rad/s)
    for i in steady_turning(model, traj.t):
        w = steady_rate(d.laws[i][1], traj.t)
        assert w is not None
        per_turn = samples_a_turn(fps, w)
        if fastest is None or per_turn < fastest[0]:
            fastest = (per_turn, d.names[i], abs(w))
    if fastest is None or fastest[0] >= PEAK_SAMPLES * (1.0 - 1e-9):
        return None
    per_turn, name, w = fastest
    need = math.ceil(PEAK_SAMPLES * w / (2.0 * math.pi) * (1.0 - 1e-12))
    sine = 100.0 * (1.0 - math.cos(math.pi / PEAK_SAMPLES))
    return (sparse_text(name, w, per_turn, f"{fps:g} fps is")
            + ", and the energy check's work, summed over so few samples, is as coarse. "
            f"Use --fps {need} or more ({PEAK_SAMPLES} samples a revolution: a sine's peak "
            f"within {sine:.2g} %)"
            + (", or mbody kinematics without --fps, whose default is one revolution at a "
               "sample a degree" if traj.info.get("kinematic") else ""))

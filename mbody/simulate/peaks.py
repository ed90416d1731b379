"""A run's peaks: each reaction's and driver's effort's largest magnitude over the run,
when it happens, and where the first driver is then (what the summary of a run with
drivers prints, and what its JSON gives)."""

from __future__ import annotations

import math

import numpy as np

from mbody.model.model import Model
from mbody.simulate.trajectory import Trajectory


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
                 "unit": "N m" if label.rsplit(".", 1)[-1].startswith("M") else "N",
                 "t": tk}
        if d is not None and len(d.names):
            value = float(d.laws[0][0](tk))
            angle = d.component[0] == "M"
            entry["driver"] = d.names[0]
            entry["driver_value"] = math.degrees(value) if angle else value
            entry["driver_unit"] = "deg" if angle else "m"
        out.append(entry)
    return out

"""Seeded random models for property tests, written as model dicts for `mbody.load(dict)`.

Everything here is built from the contract alone (not from mbody's internals) so that the
tests can recompute expected values independently: rotations come from scipy, joint frames
and reaction components from the contract's text (section 4).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

# Contract section 4: the components each joint type has.
COMPONENTS = {
    2: {"revolute": ("Fx", "Fy"), "prismatic": ("Fy", "Mz"), "fixed": ("Fx", "Fy", "Mz")},
    3: {
        "revolute": ("Fx", "Fy", "Fz", "Mx", "My"),
        "prismatic": ("Fx", "Fy", "Mx", "My", "Mz"),
        "cylindrical": ("Fx", "Fy", "Mx", "My"),
        "universal": ("Fx", "Fy", "Fz", "Mt"),
        "spherical": ("Fx", "Fy", "Fz"),
        "fixed": ("Fx", "Fy", "Fz", "Mx", "My", "Mz"),
    },
}


def _f(a) -> list[float]:
    """A plain list of Python floats (what a YAML file would give)."""
    return [float(x) for x in np.ravel(a)]


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    return Rotation.random(random_state=rng).as_matrix()


def box_principal(rng: np.random.Generator, mass: float) -> np.ndarray:
    """Principal moments of a random uniform box: always physically realisable."""
    a, b, c = rng.uniform(0.2, 1.5, 3)
    return mass / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])


def full_inertia(rng: np.random.Generator, mass: float) -> np.ndarray:
    """A full (non-diagonal) inertia tensor in body axes: S diag(I) Sᵀ, S random."""
    S = random_rotation(rng)
    J = S @ np.diag(box_principal(rng, mass)) @ S.T
    return 0.5 * (J + J.T)


def perpendicular(rng: np.random.Generator, a: np.ndarray) -> np.ndarray:
    v = rng.normal(size=3)
    v -= (v @ a) * a
    return v / np.linalg.norm(v)


def rotation_of(body: dict) -> np.ndarray:
    """W_R_B of a spatial body dict (scipy, independent of mbody)."""
    o = body.get("orientation")
    if o is None:
        return np.eye(3)
    if "quaternion" in o:
        return Rotation.from_quat(o["quaternion"], scalar_first=True).as_matrix()
    if "matrix" in o:
        return np.array(o["matrix"], float)
    return Rotation.from_euler(o.get("sequence", "ZYX"), o["euler"]).as_matrix()


def spatial_model(seed: int, n: int = 4, *, n_joints: int = 4, n_forces: int = 6,
                  n_torques: int = 3, n_springs: int = 2, gravity: bool = True,
                  known: bool = True, joint_types: tuple[str, ...] | None = None) -> dict:
    """A random spatial model: full inertias, rotated bodies (quaternion, Euler or matrix),
    world- and body-frame forces at offsets, couples, damped springs, every joint type.
    With `known`, every reaction component gets a random value in `reactions:`."""
    rng = np.random.default_rng(seed)
    bodies = []
    for i in range(n):
        m = float(rng.uniform(0.5, 5.0))
        R = random_rotation(rng)
        kind = ("quaternion", "euler", "matrix")[i % 3]
        if kind == "quaternion":
            orient = {"quaternion": _f(Rotation.from_matrix(R).as_quat(scalar_first=True))}
        elif kind == "euler":
            orient = {"euler": _f(Rotation.from_matrix(R).as_euler("ZYX")), "sequence": "ZYX"}
        else:
            orient = {"matrix": [_f(r) for r in R]}
        bodies.append({
            "name": f"b{i}", "mass": m,
            "inertia": ([_f(r) for r in full_inertia(rng, m)] if i % 4 != 3
                        else _f(box_principal(rng, m))),
            "position": _f(rng.normal(size=3)), "orientation": orient,
            "velocity": _f(rng.normal(size=3)), "angular_velocity": _f(rng.normal(size=3)),
        })
    names = [b["name"] for b in bodies]
    loads: list[dict] = []
    for k in range(n_forces):
        loads.append({"name": f"f{k}", "type": "force", "body": str(rng.choice(names)),
                      "force": _f(rng.normal(scale=10, size=3)),
                      "at": _f(rng.normal(scale=0.5, size=3)),
                      "frame": ("world", "body")[k % 2]})
    for k in range(n_torques):
        loads.append({"name": f"t{k}", "type": "torque", "body": str(rng.choice(names)),
                      "torque": _f(rng.normal(scale=3, size=3)),
                      "frame": ("world", "body")[k % 2]})
    for k in range(n_springs):
        a, b = rng.choice(["ground", *names], 2, replace=False)
        loads.append({"name": f"s{k}", "type": "spring", "bodies": [str(a), str(b)],
                      "at": [_f(rng.normal(scale=0.5, size=3)) for _ in range(2)],
                      "stiffness": float(rng.uniform(10, 100)),
                      "rest_length": float(rng.uniform(0, 1)),
                      "damping": float(rng.uniform(0, 5))})
    types = joint_types or tuple(COMPONENTS[3])
    joints = []
    for k in range(n_joints):
        typ = types[k % len(types)]
        parent, child = rng.choice(["ground", *names], 2, replace=False)
        if child == "ground":
            parent, child = child, parent
        j = {"name": f"J{k}", "type": typ, "parent": str(parent), "child": str(child),
             "at": _f(rng.normal(size=3))}
        if typ not in ("spherical", "fixed") or rng.random() < 0.5:
            ax = rng.normal(size=3)
            ax /= np.linalg.norm(ax)
            j["axis"] = _f(ax)
            if typ == "universal":
                j["axis2"] = _f(perpendicular(rng, ax))
        joints.append(j)
    model = {"model": f"random-spatial-{seed}", "dimension": 3, "bodies": bodies,
             "loads": loads, "joints": joints}
    if gravity:
        model["gravity"] = _f(rng.normal(scale=5, size=3))
    if known and joints:
        model["reactions"] = {f"{j['name']}.{c}": float(rng.normal(scale=5))
                              for j in joints for c in COMPONENTS[3][j["type"]]}
    return model


def planar_model(seed: int, n: int = 4, *, n_joints: int = 4, n_forces: int = 5,
                 n_torques: int = 2, n_springs: int = 2, gravity: bool = True,
                 known: bool = True) -> dict:
    """A random planar model with every planar joint type, offsets, springs and gravity."""
    rng = np.random.default_rng(seed)
    bodies = [{"name": f"p{i}", "mass": float(rng.uniform(0.5, 5)),
               "inertia": float(rng.uniform(0.05, 2)),
               "position": _f(rng.normal(size=2)), "angle": float(rng.uniform(-3, 3)),
               "velocity": _f(rng.normal(size=2)), "angular_velocity": float(rng.normal())}
              for i in range(n)]
    names = [b["name"] for b in bodies]
    loads: list[dict] = []
    for k in range(n_forces):
        loads.append({"name": f"f{k}", "type": "force", "body": str(rng.choice(names)),
                      "force": _f(rng.normal(scale=10, size=2)),
                      "at": _f(rng.normal(scale=0.5, size=2)),
                      "frame": ("world", "body")[k % 2]})
    for k in range(n_torques):
        loads.append({"name": f"t{k}", "type": "torque", "body": str(rng.choice(names)),
                      "torque": float(rng.normal(scale=3))})
    for k in range(n_springs):
        a, b = rng.choice(["ground", *names], 2, replace=False)
        loads.append({"name": f"s{k}", "type": "spring", "bodies": [str(a), str(b)],
                      "at": [_f(rng.normal(scale=0.5, size=2)) for _ in range(2)],
                      "stiffness": float(rng.uniform(10, 100)),
                      "rest_length": float(rng.uniform(0, 1)),
                      "damping": float(rng.uniform(0, 5))})
    types = tuple(COMPONENTS[2])
    joints = []
    for k in range(n_joints):
        typ = types[k % len(types)]
        parent, child = rng.choice(["ground", *names], 2, replace=False)
        if child == "ground":
            parent, child = child, parent
        j = {"name": f"J{k}", "type": typ, "parent": str(parent), "child": str(child),
             "at": _f(rng.normal(size=2))}
        if typ == "prismatic" or rng.random() < 0.5:
            j["axis"] = _f(rng.normal(size=2))
        joints.append(j)
    model = {"model": f"random-planar-{seed}", "dimension": 2, "bodies": bodies,
             "loads": loads, "joints": joints}
    if gravity:
        model["gravity"] = _f(rng.normal(scale=5, size=2))
    if known and joints:
        model["reactions"] = {f"{j['name']}.{c}": float(rng.normal(scale=5))
                              for j in joints for c in COMPONENTS[2][j["type"]]}
    return model

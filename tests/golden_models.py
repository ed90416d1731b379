"""The models and states today's results were recorded on (tools/make_golden.py) and the
compiled core is held to (tests/test_golden.py): every shipped model, seeded random
mechanisms of every joint type (planar and spatial, trees and loops, some with known
reactions), a chain of particle links, the four-bar chain near and at its flat position
(the null-space route; redundant at flat), a bar pinned twice (more unknowns than rows),
and a 16-rod chain (80 unknowns, band-ordered)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from fourbar_chain import FourbarChain
from randmodels import planar_model, spatial_model

import mbody

MODELS = sorted((Path(__file__).resolve().parent.parent / "models").glob("*.yaml"))

PARTICLES = {  # particle links: ground -> p1 -> p2 (particle parent), a rod on p2
    "model": "particle-chain", "dimension": 3, "gravity": [0, 0, -9.81],
    "bodies": [
        {"name": "p1", "mass": 1.0, "inertia": 0, "position": [0.6, 0.0, -0.8]},
        {"name": "p2", "mass": 0.5, "inertia": 0, "position": [0.9, 0.4, -1.5]},
        {"name": "rod", "mass": 2.0, "inertia": [0.1, 0.2, 0.25],
         "position": [1.0, 0.5, -2.0], "velocity": [0.1, -0.2, 0.3],
         "angular_velocity": [0.5, -1.0, 2.0]},
    ],
    "joints": [
        {"name": "O", "type": "spherical", "parent": "ground", "child": "p1", "at": [0, 0, 0]},
        {"name": "A", "type": "spherical", "parent": "p1", "child": "p2", "at": [0.6, 0, -0.8]},
        {"name": "B", "type": "spherical", "parent": "p2", "child": "rod", "at": [0.9, 0.4, -1.5]},
    ],
}


def random_model(kind: str, seed: int, known: str = "none") -> mbody.Model:
    make = planar_model if kind == "planar" else spatial_model
    spec = make(seed, n=5, n_joints=6, known=known != "none")
    if known == "some":  # every other component given, the rest solved
        spec["reactions"] = dict(list(spec["reactions"].items())[::2])
    return mbody.load(spec)


def pinned_twice(dimension: int) -> dict:
    at = [[0, 0], [1, 0], [1, 0]] if dimension == 2 else [[0, 0, 0], [1, 0, 0], [1, 0, 0]]
    pos = [[0.5, 0], [1.5, 0.2]] if dimension == 2 else [[0.5, 0, 0], [1.5, 0.2, 0]]
    spec = {"model": "twice", "dimension": dimension,
            "gravity": [0, -9.81] + ([0] if dimension == 3 else []),
            "bodies": [{"name": "bar", "mass": 1.0, "inertia": 0.1 if dimension == 2
                        else [0.01, 0.1, 0.1], "position": pos[0]},
                       {"name": "arm", "mass": 0.5, "inertia": 0.05 if dimension == 2
                        else [0.01, 0.05, 0.05], "position": pos[1]}],
            "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "bar",
                        "at": at[0]},
                       {"name": "P", "type": "revolute", "parent": "ground", "child": "bar",
                        "at": at[1]},
                       {"name": "Q", "type": "revolute", "parent": "bar", "child": "arm",
                        "at": at[2]}]}
    if dimension == 3:
        for j in spec["joints"]:
            j["axis"] = [0, 0, 1]
    return spec


def chain16() -> dict:
    n = 16
    bodies = [{"name": f"r{i}", "mass": 1.0 + 0.1 * i, "inertia": [0.01, 0.1, 0.1],
               "position": [0.5 + i, 0, 0], "angular_velocity": [0, 0.3 * i, 0.5]}
              for i in range(n)]
    joints = [{"name": f"J{i}", "type": "revolute", "parent": "ground" if i == 0
               else f"r{i - 1}", "child": f"r{i}", "at": [float(i), 0, 0],
               "axis": [0, 1 if i % 2 else 0, 1]} for i in range(n)]
    return {"model": "chain", "dimension": 3, "gravity": [0, 0, -9.81], "bodies": bodies,
            "joints": joints}


def all_models() -> list[tuple[str, mbody.Model]]:
    """(id, model) of every case (module docstring)."""
    out = [(p.stem, mbody.load(p)) for p in MODELS]
    for kind in ("planar", "spatial"):
        for seed in range(4):
            out.append((f"{kind}{seed}", random_model(kind, seed)))
        for seed in (10, 11):
            out.append((f"{kind}{seed}-some", random_model(kind, seed, "some")))
    out.append(("particles", mbody.load(PARTICLES)))
    chain = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)
    for theta in (1e-4, 1e-6, 1e-8, 0.0):
        out.append((f"fourbar-chain-{theta:g}", mbody.loads(chain.yaml(theta, 1.5))))
    for d in (2, 3):
        out.append((f"pinned-twice-{d}", mbody.load(pinned_twice(d))))
    out.append(("chain16", mbody.load(chain16())))
    return out


def moved_state(model: mbody.Model, seed: int, t: float = 0.3) -> mbody.State:
    """The file's state moved and spun at random (joints broken: the formulas must agree
    on inconsistent states too)."""
    rng = np.random.default_rng(seed)
    s = model.initial
    q = s.quaternion + rng.normal(scale=0.1, size=s.quaternion.shape)
    v = s.velocity + rng.normal(size=s.velocity.shape)
    w = s.omega + rng.normal(size=s.omega.shape)
    if model.dimension == 2:
        q[:, 1:3] = 0.0
        v[:, 2] = 0.0
        w[:, :2] = 0.0
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w[model.particle] = 0.0  # a particle does not turn (its rows are translations only)
    return s.replace(position=s.position + rng.normal(scale=0.1, size=s.position.shape),
                     quaternion=q, velocity=v, omega=w, t=t)


def state_vector(model: mbody.Model, state: mbody.State) -> np.ndarray:
    """[x | q | v | ω | θ (planar)], as a simulation integrates it."""
    theta = (2.0 * np.arctan2(state.quaternion[:, 3], state.quaternion[:, 0])
             if model.dimension == 2 else ())
    return np.concatenate((state.position.ravel(), state.quaternion.ravel(),
                           state.velocity.ravel(), state.omega.ravel(), theta))

"""The registry of joint types (mbody/joint_types): each type is consistent with itself,
with the docs' table, and with the physics: its reaction components forbid exactly the
relative motions the type does not list (Gᵀ v = 0 along every allowed motion, and the
joint's columns of G are independent)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import mbody
from mbody import conventions as cv
from mbody import joint_types as jt
from mbody.joint_types import base as jb

ROOT = Path(__file__).resolve().parent.parent
EVERY = [(d, name) for d in (jt.PLANAR, jt.SPATIAL) for name in jt.type_names(d)]


def test_the_docs_table_is_the_registry():
    page = (ROOT / "docs" / "model-format.md").read_text(encoding="utf-8")
    assert jt.docs_table() in page


@pytest.mark.parametrize(("dim", "name"), EVERY)
def test_components_and_motions_add_up_to_the_relative_freedom(dim, name):
    t = jt.joint_type(dim, name)
    freedom = {jb.ROTATION: 1, jb.TRANSLATION: 1, jb.BALL: 3}
    assert len(t.components) + sum(freedom[m.what] for m in t.motions) == (
        3 if dim == jt.PLANAR else 6)
    assert len(set(t.component_names)) == len(t.components)
    expected = {jb.FORCE_ALONG: jt.FORCE, jb.LINK: jt.FORCE, jb.TILT: jt.MOMENT,
                jb.LOCK: jt.MOMENT, jb.RIGHT_ANGLE: jt.MOMENT, jb.TURN: jt.MOMENT,
                jb.SCREW: jt.WRENCH}
    for c in (*t.components, *(c for cs in t.particle.values() for c in cs)):
        assert expected[c.kind] == c.what == jt.what(c.name)
        assert 0 <= c.axis <= 2
    if dim == jt.PLANAR:  # a planar joint's components act in the plane: Fx, Fy, Mz
        assert {c.name for c in t.components} <= {"Fx", "Fy", "Mz"}
    assert cv.JOINT_COMPONENTS[dim][name] == t.component_names


def _two_bodies(dim: int, name: str, rng: np.random.Generator) -> tuple[str, np.ndarray]:
    """A model text: a turned parent body on a fixed joint to ground and a child joined to
    it by a joint of type `name` at a point off both mass centres; and the joint's axes."""
    t = jt.joint_type(dim, name)
    spatial = dim == jt.SPATIAL
    n = 3 if spatial else 2
    axis = rng.normal(size=n)
    axis /= np.linalg.norm(axis)
    axis2 = None
    if t.param("axis2"):
        axis2 = np.cross(axis, rng.normal(size=3))
        axis2 /= np.linalg.norm(axis2)

    def body(bname: str, x: np.ndarray) -> dict:
        b = {"name": bname, "mass": 1.5, "position": x.tolist()}
        if spatial:
            b["inertia"] = [0.2, 0.3, 0.4]
            b["orientation"] = {"euler": rng.uniform(-1, 1, 3).tolist()}
        else:
            b["inertia"] = 0.2
            b["angle"] = float(rng.uniform(-1, 1))
        return b

    at = rng.normal(size=n)
    joint = {"name": "J", "type": name, "parent": "p", "child": "c", "at": at.tolist(),
             "axis": axis.tolist()}
    if axis2 is not None:
        joint["axis2"] = axis2.tolist()
    if t.param("pitch"):
        joint["pitch"] = 0.05
    doc = {"model": f"{name}-check", "dimension": dim,
           "bodies": [body("p", rng.normal(size=n)), body("c", rng.normal(size=n))],
           "joints": [{"name": "W", "type": "fixed", "parent": "ground", "child": "p",
                       "at": [0.0] * n}, joint]}
    return yaml.safe_dump(doc), at


@pytest.mark.parametrize(("dim", "name"), EVERY)
def test_each_allowed_motion_keeps_every_component_and_the_rest_is_forbidden(dim, name):
    rng = np.random.default_rng(sum(map(ord, name)) + dim)
    text, at = _two_bodies(dim, name, rng)
    model = mbody.loads(text)
    t = jt.joint_type(dim, name)
    j = next(j for j in model.joints if j.name == "J")
    E = np.asarray(j.W_E0)  # the joint frame at the file's pose, world axes
    P = np.pad(at, (0, 3 - len(at)))
    st = model.initial
    R = st.W_R_B
    c = model.index["c"]
    cols = [k for k, lab in enumerate(model.reactions) if lab.startswith("J.")]
    assert len(cols) == len(t.components)
    G = mbody.assemble(model).G.toarray()[:, cols]
    rows = model.body_rows(c)

    def twist(w_world: np.ndarray, v_world: np.ndarray) -> np.ndarray:
        """The generalized velocity of the child alone moving with angular velocity
        w_world about P plus translation v_world (the parent at rest)."""
        v6 = np.zeros(6)
        v6[:3] = v_world + np.cross(w_world, st.position[c] - P)
        v6[3:] = R[c].T @ w_world
        v = np.zeros(len(model.coordinates))
        v[rows] = v6[[0, 1, 5]] if dim == jt.PLANAR else v6
        return v

    h = 0.05 / (2 * np.pi)
    allowed = []
    for m in t.motions:
        if m.what == jb.BALL:
            allowed += [twist(e, np.zeros(3)) for e in np.eye(3)]
            continue
        a = E[:, m.axis] if m.on == "parent" else np.asarray(j.axis2)
        if dim == jt.PLANAR and m.what == jb.ROTATION:
            a = np.array([0.0, 0.0, 1.0])
        if m.what == jb.ROTATION:
            screw = any(comp.kind == jb.SCREW for comp in t.components)
            allowed.append(twist(a, h * a if screw else np.zeros(3)))
        else:
            allowed.append(twist(np.zeros(3), a))
    for v in allowed:  # Gᵀ v: the relative velocities the joint forbids, all zero
        assert np.abs(G.T @ v).max() <= 1e-12 * max(1.0, np.abs(v).max())
    # ... and the components are independent: nothing else is allowed
    assert np.linalg.matrix_rank(G[rows], tol=1e-10) == len(t.components)

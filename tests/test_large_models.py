"""Large models (issue 15): what `Model` derives on first use equals what it built eagerly.

The reaction table keeps only each component's joint and axis and derives the rest from the
per-joint `JointTable`; `Body`, `Load` and `Joint` records are made when first asked for.
Here the per-component arrays are rebuilt the way `Model.from_spec` built them before
(every joint's frame and points, repeated per component, `joint_table` picked back out with
np.unique) and compared bit for bit on every shipped model, models with particles (pins,
links, a particle parent), every joint type, and the benchmark's files, through both paths.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import mbody
from mbody import conventions as cv
from mbody import joint_types
from mbody.model import fast
from mbody.model.loader import load_text
from mbody.model.model import BodyRecords, Model, Records
from mbody.model.validate import JointSpecTable, validate

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from bench_load import chain_spec, free_bodies_spec  # noqa: E402
from test_fast import assert_same_model, check_both, located  # noqa: E402

DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
SHIPPED = sorted((ROOT / "models").glob("*.yaml"))

PARTICLES = """
model: particles
dimension: 3
gravity: [0, 0, -9.81]
bodies:
  - {name: arm, mass: 2.0, inertia: [0.1, 0.2, 0.25], position: [0.3, 0, 0],
     angular_velocity: [0, 0, 1.5], velocity: [0, 0.45, 0]}
  - {name: bob, mass: 0.5, inertia: 0, position: [0.6, 0.4, 0], velocity: [-0.6, 0.9, 0.4]}
  - {name: ball, mass: 0.3, inertia: 0, position: [0.6, 0.4, -0.5]}
  - {name: rod, mass: 1.0, inertia: [0.1, 0.1, 0.01], position: [0.6, 0.4, -1.0]}
joints:
  - {name: A, type: revolute, parent: ground, child: arm, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: B, type: revolute, parent: arm, child: bob, at: [0.6, 0, 0], axis: [1, 0, 0]}
  - {name: C, type: spherical, parent: bob, child: ball, at: [0.6, 0.4, 0]}
  - {name: D, type: spherical, parent: ball, child: rod, at: [0.6, 0.4, -0.5]}
"""
"""A link (B), a link from a particle parent (C), a pin on a particle parent (D)."""


def dump(spec: dict) -> str:
    return yaml.dump(spec, Dumper=DUMPER, sort_keys=False, default_flow_style=None, width=200)


def every_joint_type() -> str:
    spec = chain_spec(14)
    kinds = ["spherical", "fixed", "cylindrical", "prismatic", "universal", "revolute",
             "universal", "spherical"]
    for j, kind in zip(spec["joints"], kinds, strict=False):
        j["type"] = kind
        if kind == "universal":
            j["axis"], j["axis2"] = [0.0, 0.0, 2.0], [0.0, 1.0, 0.0]
        if kind == "spherical":
            del j["axis"]
    spec["joints"][9]["axis"] = [0.0, -0.0, 1.0]  # the same axis but for a sign bit
    spec["joints"][10]["axis"] = [1.0, 1.0, 0.0]
    return dump(spec)


def eager_reaction_table(model: Model, spec=None) -> dict[str, np.ndarray | tuple[str, ...]]:
    """The reaction table's per-component fields as `Model.from_spec` built them before
    issue 15: per joint, its frame and points at the initial pose (from its record; the
    points the file gives on each body where `spec` has them), then one row per
    component."""
    js = list(model.joints)
    nj = len(js)
    idx = model.index
    particle = {b for b in model.body_names if model.bodies[b].particle}
    W_E0 = np.array([j.W_E0 for j in js]).reshape(nj, 3, 3)
    at = np.array([j.at for j in js], dtype=float).reshape(nj, 3)
    p = np.array([idx.get(j.parent, -1) for j in js], dtype=np.intp)
    c = np.array([idx[j.child] for j in js], dtype=np.intp)
    ground = p < 0
    R0, x0 = model.initial.W_R_B, model.initial.position
    Rp = np.where(ground[:, None, None], np.eye(3), R0[p] if nj else np.zeros((0, 3, 3)))
    xp = np.where(ground[:, None], 0.0, x0[p] if nj else np.zeros((0, 3)))
    Rc, xc = R0[c], x0[c]
    RpT, RcT = Rp.transpose(0, 2, 1), Rc.transpose(0, 2, 1)
    P_E = RpT @ W_E0
    C_E = RcT @ W_E0
    B_r_child = (RcT @ (at - xc)[:, :, None])[:, :, 0]
    B_r_parent = np.where(ground[:, None], at, (RpT @ (at - xp)[:, :, None])[:, :, 0])
    axis2 = np.array([j.axis2 if j.axis2 is not None else np.zeros(3) for j in js],
                     dtype=float).reshape(nj, 3)
    js_spec = None if spec is None else (
        spec.joint_table if spec.joint_table is not None
        else JointSpecTable.from_specs(spec.joints, idx))
    if js_spec is not None and js_spec.body_points is not None:
        on = js_spec.body_points
        B_r_child[on], B_r_parent[on] = js_spec.at_child[on], js_spec.at_parent[on]
    C_axis2 = (RcT @ axis2[:, :, None])[:, :, 0]
    p_particle = np.array([j.parent in particle for j in js], dtype=bool)
    c_particle = np.array([j.child in particle for j in js], dtype=bool)
    B_r_child[c_particle] = 0.0
    B_r_parent[p_particle] = 0.0
    link = np.array([j.particle_joint == "link" for j in js], dtype=bool)
    length = np.zeros(nj)
    if link.any():
        P_c = xc + (Rc @ B_r_child[:, :, None])[:, :, 0]
        P_p = np.where(ground[:, None], B_r_parent, xp + (Rp @ B_r_parent[:, :, None])[:, :, 0])
        length[link] = np.linalg.norm((P_c - P_p)[link], axis=1)
    # the reference predates the helical joint (its coupled component Wz): such a joint's
    # rows are left out here, and compared by tests/test_new_joint_types.py
    comps = [j.components if known_joint(j) else () for j in js]
    row_joint = np.repeat(np.arange(nj, dtype=np.intp),
                          np.array([len(cs) for cs in comps], dtype=np.intp))
    axis = np.array([6 if comp == "Mt" else cv.LINK_AXIS if comp == cv.LINK
                     else cv.COMPONENTS.index(comp) for cs in comps for comp in cs],
                    dtype=np.intp)
    free_turn = np.array([j.type in ("revolute", "cylindrical") for j in js],
                         dtype=bool)[row_joint]
    column = np.where(axis == 6, 2, axis % 3)
    registry = [joint_types.joint_type(model.dimension, j.type) for j in js]
    parts = [(t.particle[j.particle_joint] if j.particle_joint else t.components)
             if known_joint(j) else () for t, j in zip(registry, js, strict=True)]
    return {
        "component": np.array([joint_types.COMPONENT_CODE[c.name] for cs in parts
                               for c in cs], dtype=np.intp),
        "kind": np.array([c.kind for cs in parts for c in cs], dtype=np.intp),
        "frame_axis": np.array([c.axis for cs in parts for c in cs], dtype=np.intp),
        "is_moment": np.array([c.what == joint_types.MOMENT for cs in parts for c in cs],
                              dtype=bool),
        "labels": tuple(f"{j.name}.{comp}" for j, cs in zip(js, comps, strict=True)
                        for comp in cs),
        "joint": row_joint, "parent": p[row_joint], "child": c[row_joint], "axis": axis,
        "P_E": P_E[row_joint, :, column].reshape(-1, 3), "B_r_child": B_r_child[row_joint],
        "C_axis2": C_axis2[row_joint], "B_r_parent": B_r_parent[row_joint],
        "P_E3": P_E[row_joint], "C_E3": C_E[row_joint],
        "rot_kind": np.where(axis < 3, 0, np.where(axis == 6, 3, np.where(free_turn, 1, 2)))
        .astype(np.intp),
        "link": axis == cv.LINK_AXIS, "particle_parent": p_particle[row_joint],
        "length": np.where(axis == cv.LINK_AXIS, length[row_joint], 0.0),
    }


def known_joint(j) -> bool:
    """Whether the eager reference knows every component of joint record `j`."""
    return all(c in cv.COMPONENTS or c in ("Mt", cv.LINK) for c in j.components)


def same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def assert_derived_equal_eager(model: Model, spec=None) -> None:
    rt = model.reaction_table
    assert not set(rt.DERIVED) & set(vars(rt))  # nothing derived before it is asked for
    old = eager_reaction_table(model, spec)
    assert set(old) == {"joint", "component", "kind", "frame_axis", *rt.DERIVED}
    # the joints' rows the reference knows; the drivers' efforts come last, after them
    known = np.array([known_joint(j) for j in model.joints], dtype=bool)
    m, nd = len(rt.joint), len(rt.driver_names)
    rows = np.flatnonzero(known[rt.joint] & (np.arange(m) < m - nd))
    for k, v in old.items():
        if k == "labels":
            assert tuple(rt.labels[i] for i in rows) == v
        else:
            assert same_bits(np.asarray(getattr(rt, k))[rows], v), k
    # each driver's effort: on its joint, named <driver>.M or .F, a moment for an angle
    d = model.drivers
    for i, name in enumerate(rt.driver_names):
        r = m - nd + i
        assert name == d.names[i] and rt.joint[r] == d.joint[i]
        assert rt.labels[r] == f"{name}.{d.component[i]}"
        assert bool(rt.is_moment[r]) == (d.component[i] == "M")
    # the joint table as it was picked back out of the reaction table
    first = (np.unique(old["joint"], return_index=True)[1] if len(old["joint"])
             else np.zeros(0, int))
    jt = model.joint_table
    for k in ("parent", "child", "B_r_child", "B_r_parent", "P_E3", "C_E3", "C_axis2", "link",
              "particle_parent", "length"):
        assert same_bits(np.asarray(getattr(jt, k))[known], np.asarray(old[k])[first]), k
    assert same_bits(np.asarray(jt.first)[known], rows[first])
    assert jt.names == tuple(j.name for j in model.joints)


def texts() -> list[tuple[str, str]]:
    out = [(p.stem, p.read_text()) for p in SHIPPED]
    out += [(f"{p.stem}-dumped", dump(yaml.safe_load(p.read_text()))) for p in SHIPPED]
    return out + [("particles", PARTICLES), ("joint-types", every_joint_type()),
                  ("chain", dump(chain_spec(40))), ("free", dump(free_bodies_spec(30)))]


@pytest.mark.parametrize("name, text", texts(), ids=lambda x: x if len(x) < 40 else "")
def test_derived_reaction_table_equals_the_eager_one(name, text, monkeypatch):
    """Through the located path, and the fast path wherever it reads the file."""
    spec = validate(load_text(text, "m.yaml"))
    assert_derived_equal_eager(Model.from_spec(spec), spec)
    monkeypatch.setattr(fast, "MIN_BYTES", 0)
    spec = fast.fast_spec(text, "m.yaml")
    if spec is not None:
        assert_derived_equal_eager(Model.from_spec(spec), spec)


def test_the_generated_files_take_the_fast_path_and_match_the_located_one(monkeypatch):
    """Files a few chunks long (the default chunk size), with loads and joints: both paths
    build the same model (tests/test_fast.py compares every array and record)."""
    for spec in (chain_spec(1500), free_bodies_spec(600)):
        text = dump(spec)
        assert len(text) > 3 * fast.CHUNK
        fast_model = Model.from_spec(fast.fast_spec(text, "m.yaml"))
        assert_derived_equal_eager(fast_model)
        assert_same_model(fast_model, Model.from_spec(validate(load_text(text, "m.yaml"))))


def test_records_behave_as_the_tuples_and_dict_they_replace():
    model = mbody.loads(PARTICLES)
    bodies, joints = model.bodies, model.joints
    assert isinstance(bodies, BodyRecords) and isinstance(joints, Records)
    assert list(bodies) == list(model.body_names) and len(bodies) == 4
    assert "bob" in bodies and "ground" not in bodies and 3 not in bodies
    assert bodies.get("nobody") is None
    with pytest.raises(KeyError):
        bodies["nobody"]
    bob = bodies["bob"]
    assert bob is bodies["bob"]  # made once
    assert (bob.name, bob.index, bob.mass, bob.particle) == ("bob", 1, 0.5, True)
    assert [b.name for b in bodies.values()] == list(model.body_names)
    assert dict(bodies.items())["rod"].inertia[2, 2] == 0.01
    assert not bodies["rod"].inertia.flags.writeable
    np.testing.assert_array_equal(model.particle, [False, True, True, False])
    assert len(joints) == 4 and joints[-1] is joints[3] and joints[3].name == "D"
    assert [j.name for j in joints[1:3]] == ["B", "C"] and isinstance(joints[1:3], tuple)
    assert joints.index(joints[2]) == 2 and joints[2] in joints
    with pytest.raises(IndexError):
        joints[4]
    b = joints[1]
    assert (b.parent, b.child, b.type, b.particle_joint, b.components) == \
        ("arm", "bob", "revolute", "link", ("T", "Fz"))
    np.testing.assert_array_equal(b.axis, [1, 0, 0])
    assert joints[2].axis is None and joints[0].parent == cv.GROUND
    assert [j.labels for j in joints][0] == ["A.Fx", "A.Fy", "A.Fz", "A.Mx", "A.My"]


def test_load_records_of_the_fast_path(monkeypatch):
    monkeypatch.setattr(fast, "MIN_BYTES", 0)
    spec = free_bodies_spec(5)
    spec["loads"][2]["frame"] = "body"
    model = mbody.loads(dump(spec))
    assert isinstance(model.loads, Records)
    located = Model.from_spec(validate(load_text(dump(spec), "m.yaml")))
    assert len(model.loads) == len(located.loads) == 5
    for a, b in zip(model.loads, located.loads, strict=True):
        assert (a.name, a.type, a.bodies, a.frame, a.stiffness, a.expressions) == \
            (b.name, b.type, b.bodies, b.frame, b.stiffness, b.expressions)
        assert same_bits(a.vector, b.vector) and same_bits(a.at[0], b.at[0])
    assert model.loads[2].frame == "body" and model.forces.in_body.tolist()[2]


def test_a_large_file_is_read_without_its_records():
    """What issue 15 is about: loading makes no per-body Python record, and the reaction
    table's per-component frames wait until assembly asks for them."""
    model = mbody.loads(dump(chain_spec(2000)))
    assert model.bodies._records._made.count(None) == 2000  # type: ignore[attr-defined]
    assert model.joints._made.count(None) == 2000  # type: ignore[attr-defined]
    assert not set(model.reaction_table.DERIVED) & set(vars(model.reaction_table))
    assert len(model.reactions) == 5 * 2000 and model.reactions[-1] == "j1999.My"



def test_a_run_keeps_each_bodys_look_without_making_records():
    """A run carries every body's shape and colour (what draws it without the file), read
    from the body table: the same values the records hold, with none of them made for it,
    nor a joint record for its conservation reasons."""
    model = mbody.load(ROOT / "models" / "gyroscope_gimbals.yaml")
    traj = mbody.simulate(model, t_end=0.05, fps=20, rtol=1e-6, atol=1e-8)
    assert model.bodies._records._made.count(None) == model.n  # type: ignore[attr-defined]
    assert model.joints._made.count(None) == len(model.joints)  # type: ignore[attr-defined]
    assert traj.info["momentum_not_conserved"].count("joints to ground") == 1
    records = [model.bodies[b] for b in model.body_names]
    assert traj.shapes == tuple(b.shape for b in records)
    assert traj.colors == tuple(b.color for b in records)
    assert any(c is not None for c in traj.colors) and any(s is not None for s in traj.shapes)
    grounded = [j.name for j in model.joints if j.parent == cv.GROUND]
    assert grounded and traj.info["momentum_not_conserved"].endswith(
        "joints to ground: " + ", ".join(grounded))

def _edit(text: str, pattern: str, new: str, nth: int = 7) -> str:
    """`text` with the `nth` match of `pattern` (a regex) replaced by `new`."""
    m = list(re.finditer(pattern, text, re.M))[nth]
    return text[:m.start()] + new + text[m.end():]


CHAIN = dump(chain_spec(40))
EDITS = {
    "decimal comma": (r"mass: [0-9.]+", "mass: 1,5", False),
    "list in a list": (r"position: \[[^\n]*\]", "position: [[1.5, 0.0], 0.0]", False),
    "widths that make up for each other": (
        r"mass: [0-9.]+\n  inertia: \[[^\n]*\]\n  position: \[[^\n]*\]",
        "mass: 1,5\n  inertia: [0.3, 0.2, 0.2]\n  position: [1.5, 0.0]", False),
    "a bracket too many": (r"velocity: \[[^\n]*\]", "velocity: [0.0, 0.0, 0.0]]", False),
    "three-digit exponent": (r"position: \[[^\n]*\]", "position: [1.0e+100, 0.0, 0.0]", True),
    "two-digit exponents": (r"position: \[[^\n]*\]", "position: [1.5e-05, 2E+01, -3e7]", True),
    "spaces in a list": (r"velocity: \[[^\n]*\]", "velocity: [ 0.0 ,0.0,  0.0 ]", True),
    "no such body": (r"parent: b[0-9]+", "parent: b4000", False),
    "ground as a parent": (r"parent: b[0-9]+", "parent: ground", True),
    "a load on ground": (r"body: b[0-9]+", "body: ground", False),
    "a joint type of the plane": (r"type: revolute", "type: slider", False),
}


@pytest.mark.parametrize("edit", EDITS, ids=str)
def test_the_chunk_reader_refuses_what_the_located_path_refuses(edit, monkeypatch):
    """Each value in its own slot: a value cannot spill into its neighbour, a list cannot
    nest, and every name must be what the contract allows; a file either path refuses
    is refused (then the located path reports it), one both accept gives one model."""
    pattern, new, valid = EDITS[edit]
    text = _edit(CHAIN, pattern, new)
    assert text != CHAIN
    monkeypatch.setattr(fast, "MIN_BYTES", 0)
    assert isinstance(located(text), Model) == valid
    # the fast path accepts only what the located path accepts, and builds the same model;
    # it reads these valid edits itself (a three-digit exponent it leaves to the other)
    assert check_both(text) == (valid and edit != "three-digit exponent")

"""The fast path for large files (mbody.model.fast) against the located path.

The fast path must never accept a file the located path refuses, and must build the
same `Model`, bit for bit, from every file it accepts. Checked on every shipped model
re-written as ``yaml.dump`` writes it, on the benchmark's files, and on generated and
perturbed files (hypothesis). Anything it does not accept falls back to the located path,
so problems keep their file, line and column.
"""

from __future__ import annotations

import sys
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mbody
from mbody.errors import ModelError
from mbody.model import fast
from mbody.model.loader import load_text
from mbody.model.model import Model
from mbody.model.validate import validate

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from bench_load import chain_spec, free_bodies_spec  # noqa: E402

DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def dump(spec: dict) -> str:
    return yaml.dump(spec, Dumper=DUMPER, sort_keys=False, default_flow_style=None, width=200)


@pytest.fixture(autouse=True)
def any_size(monkeypatch):
    """Small texts take the fast path too (by default it skips them: nothing to gain)."""
    monkeypatch.setattr(fast, "MIN_BYTES", 0)


def located(text: str) -> Model | ModelError:
    try:
        return Model.from_spec(validate(load_text(text, "m.yaml")))
    except ModelError as exc:
        return exc


def same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def table_fields(table) -> list[str]:
    """Every field of a model table, those derived on first use included (the reaction
    table's per-component frames and points, labels...)."""
    return [f.name for f in fields(table)] + list(getattr(table, "DERIVED", ()))


def assert_same_model(m1: Model, m2: Model) -> None:
    """Every array and label of two models, compared bit for bit (-0.0 differs from 0.0)."""
    assert (m1.name, m1.dimension, m1.body_names) == (m2.name, m2.dimension, m2.body_names)
    for k in ("mass", "J", "J_inv", "gravity"):
        assert same_bits(getattr(m1, k), getattr(m2, k)), k
    for k in ("position", "quaternion", "velocity", "omega"):
        assert same_bits(getattr(m1.initial, k), getattr(m2.initial, k)), k
    for name, b in m1.bodies.items():
        c = m2.bodies[name]
        assert (b.index, b.mass, b.shape, b.color, b.particle) == \
            (c.index, c.mass, c.shape, c.color, c.particle)
        assert same_bits(b.inertia, c.inertia)
    for t1, t2 in ((m1.forces, m2.forces), (m1.springs, m2.springs),
                   (m1.reaction_table, m2.reaction_table), (m1.joint_table, m2.joint_table)):
        for k in table_fields(t1):
            v = getattr(t1, k)
            if isinstance(v, np.ndarray):
                assert same_bits(v, getattr(t2, k)), k
            elif k not in ("varying", "per_joint"):
                assert v == getattr(t2, k), k
    assert len(m1.loads) == len(m2.loads)
    for l1, l2 in zip(m1.loads, m2.loads, strict=True):
        assert (l1.name, l1.type, l1.bodies, l1.frame) == (l2.name, l2.type, l2.bodies, l2.frame)
        assert same_bits(l1.vector, l2.vector)
        assert all(same_bits(a, b) for a, b in zip(l1.at, l2.at, strict=True))
    assert len(m1.joints) == len(m2.joints)
    for j1, j2 in zip(m1.joints, m2.joints, strict=True):
        assert (j1.name, j1.type, j1.parent, j1.child, j1.components, j1.particle_joint) == \
            (j2.name, j2.type, j2.parent, j2.child, j2.components, j2.particle_joint)
        for k in ("at", "W_E0", "axis", "axis2"):
            a, b = getattr(j1, k), getattr(j2, k)
            assert (a is None) == (b is None), k
            assert a is None or same_bits(a, b), k
    assert m1.known_reactions == m2.known_reactions
    assert m1.warnings == m2.warnings == ()


def check_both(text: str) -> bool:
    """The fast path agrees with the located path on `text`; True if it took it."""
    spec = fast.fast_spec(text, "m.yaml")
    slow = located(text)
    if spec is None:
        return False
    assert not isinstance(slow, ModelError), f"fast path accepted a bad file: {slow}"
    assert_same_model(Model.from_spec(spec), slow)
    return True


SHIPPED = sorted((ROOT / "models").glob("*.yaml"))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_models_dumped_as_yaml_dump_writes(path):
    data = yaml.safe_load(path.read_text())
    check_both(dump(data))


def test_shipped_models_take_the_fast_path_where_they_can():
    taken = [p.stem for p in SHIPPED if check_both(dump(yaml.safe_load(p.read_text())))]
    assert len(taken) >= 2, taken  # those without shapes, angles in degrees, springs...


@pytest.mark.parametrize("spec", [free_bodies_spec(50), free_bodies_spec(1), chain_spec(30)],
                         ids=["free", "one", "chain"])
def test_benchmark_files_take_the_fast_path(spec):
    assert check_both(dump(spec))


def test_many_chunks_and_layouts(monkeypatch):
    """Items cut into several chunks, with several layouts mixed, keep their order."""
    monkeypatch.setattr(fast, "CHUNK", 300)
    spec = free_bodies_spec(40)
    for i, b in enumerate(spec["bodies"]):
        if i % 3 == 0:
            del b["orientation"]
        if i % 5 == 0:
            b["inertia"] = [1.0, 2.0, 2.5]
    for i, ld in enumerate(spec["loads"]):
        if i % 4 == 0:
            del ld["at"], ld["frame"]
    assert check_both(dump(spec))


def test_joint_types_and_axes():
    spec = chain_spec(12)
    for j, kind in zip(spec["joints"], ["spherical", "fixed", "cylindrical", "prismatic",
                                          "universal", "universal"], strict=False):
        j["type"] = kind
        if kind == "universal":
            j["axis"], j["axis2"] = [0.0, 0.0, 2.0], [0.0, 1.0, 0.0]
        if kind == "spherical":
            del j["axis"]
    assert check_both(dump(spec))


def test_planar_model():
    bodies = [{"name": f"p{i}", "mass": 1 + i, "inertia": 0.5, "position": [i, 0.5],
               "angle": 0.1 * i, "velocity": [0, 1], "angular_velocity": -2}
              for i in range(20)]
    loads = [{"name": f"t{i}", "type": "torque", "body": f"p{i}", "torque": 1.5}
             for i in range(20)]
    joints = [{"name": "A", "type": "revolute", "parent": "ground", "child": "p0",
               "at": [0, 0.5]}]
    assert check_both(dump({"model": "planar", "dimension": 2, "gravity": [0, -9.81],
                            "bodies": bodies, "loads": loads, "joints": joints,
                            "reactions": {"A.Fx": 0}}))


BAD_VALUES = ["010", "1_000", "0x1F", "1:20", ".inf", "-.inf", ".nan", "1e400", "1e-400",
              "-0", "+1", ".5", "1.", "true", "'3'", "~", "null", "1E+05", "1e5",
              "123456789012345678901234567", "9" * 120, "&a 1", "*a", "!!float 3", "[1, 2]",
              "[]", "{}", "ground", "b0", "b1", "abc def", "3 kg", "'30 deg'", "1e-320",
              "1e100", "1.0000001e100", "1e-101", "0.0", "-0.0", "0", "1 # note", "[1,2, 3]",
              "[1, 2, 3", "[[1, 2, 3]]", "\"b0\"", "b0.x", "force", "torque", "body", "x\ty",
              "[1, 2, 3]", "[0, 0, 0]", "[1, 0, 0, 0]", "[2, 0, 0, 0]", "[1, 1, 3]", "-1",
              "[1e-101, 1, 1]"]


@st.composite
def model_texts(draw):
    """A generated model file (2-D or 3-D), then up to three edits of its text."""
    dim = draw(st.sampled_from([2, 3]))
    n = draw(st.integers(1, 5))
    num = st.one_of(st.integers(-5, 5), st.floats(-10, 10, allow_subnormal=False),
                    st.sampled_from([0.0, -0.0, 1.5e-5, 2.5e20, 1e-120]))
    pos = st.floats(0.1, 10)
    vec = st.lists(num, min_size=dim, max_size=dim)
    bodies = []
    for i in range(n):
        b: dict = {"name": draw(st.sampled_from([f"b{i}", f"b{i}", f"b{i}", "b0", "c-1"]))}
        b["mass"] = draw(st.one_of(pos, st.sampled_from([0, -1, 3])))
        if dim == 2:
            b["inertia"] = draw(pos)
        elif draw(st.booleans()):
            b["inertia"] = draw(st.lists(pos, min_size=3, max_size=3))
        else:
            a = np.array(draw(st.lists(st.floats(-1, 1), min_size=9, max_size=9))).reshape(3, 3)
            J = a @ a.T + np.eye(3) * draw(st.sampled_from([0.0, 0.1, 1.0]))
            b["inertia"] = [[float(x) for x in row] for row in J]
        for key in ("position", "velocity"):
            if draw(st.booleans()):
                b[key] = draw(vec)
        if dim == 3 and draw(st.booleans()):
            b["orientation"] = {"quaternion": draw(st.sampled_from(
                [[1, 0, 0, 0], [0.5, 0.5, 0.5, 0.5], [0.6, 0.8, 0.0, 0.0], [2, 0, 0, 0]]))}
        if draw(st.booleans()):
            b["angular_velocity"] = draw(vec if dim == 3 else num)
        if dim == 2 and draw(st.booleans()):
            b["angle"] = draw(num)
        bodies.append(b)
    loads = []
    for i in range(draw(st.integers(0, 4))):
        kind = draw(st.sampled_from(["force", "torque"]))
        ld: dict = {"name": f"l{i}", "type": kind, "body": f"b{draw(st.integers(0, n))}"}
        ld[kind] = draw(vec) if kind == "force" or dim == 3 else draw(num)
        if kind == "force" and draw(st.booleans()):
            ld["at"] = draw(vec)
        if draw(st.booleans()):
            ld["frame"] = draw(st.sampled_from(["world", "body"]))
        loads.append(ld)
    spec: dict = {"model": "gen", "dimension": dim, "bodies": bodies}
    if loads:
        spec["loads"] = loads
    joints = []
    kinds = (["revolute", "prismatic", "fixed"] if dim == 2 else
             ["revolute", "prismatic", "cylindrical", "spherical", "fixed", "universal"])
    for i in range(draw(st.integers(0, 4))):
        kind = draw(st.sampled_from(kinds))
        j: dict = {"name": draw(st.sampled_from([f"j{i}", f"j{i}", "j0"])), "type": kind,
                   "parent": draw(st.sampled_from(["ground", "b0", f"b{i}"])),
                   "child": f"b{draw(st.integers(0, n))}", "at": draw(vec)}
        if draw(st.booleans()) or kind in ("prismatic", "universal", "cylindrical"):
            j["axis"] = draw(st.sampled_from([[0, 0, 1], [1, 0, 0], [0, 0, 0], [1, 1, 0],
                                              [0.6, 0.8, 0]]))[:dim]
        if kind == "universal":
            j["axis2"] = draw(st.sampled_from([[0, 1, 0], [0, 0, 1], [1, 0, 1e-7]]))
        joints.append(j)
    if joints:
        spec["joints"] = joints
    lines = dump(spec).split("\n")
    for _ in range(draw(st.integers(0, 3))):
        i = draw(st.integers(0, len(lines) - 1))
        line = lines[i]
        edit = draw(st.sampled_from(["value", "number", "append", "dup", "drop", "indent"]))
        if edit == "value" and ": " in line:
            lines[i] = line.split(": ")[0] + ": " + draw(st.sampled_from(BAD_VALUES))
        elif edit == "number" and "[" in line:
            items = line[line.index("[") + 1:line.rindex("]")].split(", ")
            k = draw(st.integers(0, len(items) - 1))
            items[k] = draw(st.sampled_from(BAD_VALUES))
            lines[i] = line[:line.index("[") + 1] + ", ".join(items) + "]"
        elif edit == "append":
            lines[i] = line + draw(st.sampled_from([" # c", "  ", "\t", " &x", ":"]))
        elif edit == "dup":
            lines.insert(i, line)
        elif edit == "drop":
            del lines[i]
        else:
            lines[i] = " " + line
    return "\n".join(lines)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(model_texts())
def test_fast_path_never_disagrees(text):
    check_both(text)


def test_generated_files_often_take_the_fast_path():
    """The property above is not vacuous: unedited generated files take the fast path."""
    taken = 0
    for n in range(1, 25):
        spec = free_bodies_spec(n, seed=n)
        spec["bodies"][0]["inertia"] = [1, 2, 2.5]
        taken += check_both(dump(spec))
    assert taken == 24


def test_a_problem_in_a_large_file_is_located(tmp_path):
    """One bad number among thousands of bodies: the located path names its line."""
    text = dump(free_bodies_spec(300))
    lines = text.split("\n")
    i = next(k for k, line in enumerate(lines) if line.startswith("  mass:") and k > 2000)
    lines[i] = "  mass: -2"
    path = tmp_path / "big.yaml"
    path.write_text("\n".join(lines))
    with pytest.raises(ModelError) as err:
        mbody.load(path)
    (issue,) = err.value.issues
    assert (issue.line, issue.column) == (i + 1, 9)
    assert "expected a number > 0" in issue.message


def test_misspelt_key_in_a_large_file_gets_a_hint(tmp_path):
    text = dump(free_bodies_spec(300)).replace("  velocity:", "  velocty:", 1)
    with pytest.raises(ModelError) as err:
        mbody.loads(text)
    (issue,) = err.value.issues
    assert "unknown key 'velocty'" in issue.message and "velocity" in issue.hint
    assert issue.line == text.split("\n").index(next(
        line for line in text.split("\n") if "velocty" in line)) + 1


def test_fast_path_declines_unhandled_forms():
    base = dump(free_bodies_spec(5))
    assert fast.fast_spec(base, "m") is not None
    for edit in [("  mass:", "  mass: &m"), ("b0", "'b0'"),
                 ("  velocity", "  color: red\n  velocity"), ("force: [", "force: ['2*t', "),
                 ("model:", "# note\nmodel:")]:
        text = base.replace(*edit, 1)
        spec = fast.fast_spec(text, "m")
        if edit[0] == "model:":  # a comment outside the lists is the located loader's
            assert spec is not None
        else:
            assert spec is None, edit


@pytest.mark.parametrize("spec", [free_bodies_spec(20), chain_spec(15)], ids=["free", "chain"])
def test_value_limit_is_the_located_readers(monkeypatch, spec):
    """The fast path counts keys and values as the located reader does, and refuses (leaves
    to the located path) exactly the files that reader refuses for their number."""
    from mbody.model import loader

    text = dump(spec)
    doc = load_text(text, "m.yaml")
    count = len(doc.marks) + len(doc.key_marks)
    monkeypatch.setattr(loader, "MAX_NODES", count)
    assert check_both(text)
    monkeypatch.setattr(loader, "MAX_NODES", count - 1)
    assert fast.fast_spec(text, "m.yaml") is None
    with pytest.raises(ModelError, match=f"more than {count - 1:_} values".replace("_", " ")):
        load_text(text, "m.yaml")


def test_value_limit_grows_with_the_file():
    from mbody.model.loader import MAX_NODES, value_limit

    assert value_limit(1000) == value_limit(32 * 2**20) == MAX_NODES
    assert value_limit(100 * 2**20) == 100 * 2**20 // 8


@pytest.mark.parametrize("tiny", ["0." + "0" * 400 + "1", "0." + "0" * 250 + "1e-99"])
def test_a_number_that_underflows_through_its_zeros_is_refused_by_both_paths(tiny):
    """A nonzero number below the smallest double is written with no three-digit exponent:
    the fast path must not read it as 0 where the located path refuses it as too small."""
    text = dump(free_bodies_spec(300))
    i = text.index("position: [") + len("position: [")
    text = text[:i] + tiny + text[text.index(",", i):]
    assert fast.fast_spec(text, "m.yaml") is None
    err = located(text)
    assert isinstance(err, ModelError)
    (issue,) = err.issues
    assert "position" in issue.key and "1e+100" not in issue.message, issue.message

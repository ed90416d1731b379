"""Values set by path (`Model.with_values`, ``--set PATH=VALUE``): the model built equals
a fresh load of the file written with that value; chained values compose; every rule of
the file applies to a value set, and a bad path or value is reported at the file's line
of its entry, naming the path, with a did-you-mean."""

from __future__ import annotations

import math
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.equations.pack import pack_model
from mbody.errors import MbodyError, ModelError
from mbody.model import source as source_module

ROOT = Path(__file__).resolve().parent.parent
SLIDER = ROOT / "models" / "slider_crank.yaml"
ARM = ROOT / "models" / "robots" / "two_link_arm.xml"


def driven_text() -> str:
    """The shipped slider-crank without its loads, its crank driven at 100 rad/s."""
    text = SLIDER.read_text()
    text = "\n".join(line for line in text.splitlines()
                     if "{name: gas" not in line and "{name: load" not in line)
    return text + "\ndrivers:\n  - {name: motor, joint: O, speed: 100}\n"


def same_model(a: mbody.Model, b: mbody.Model) -> None:
    """Every array the compiled core reads, the initial state and the labels, bit for bit."""
    Fa, Ia = pack_model(a)
    Fb, Ib = pack_model(b)
    assert np.array_equal(Ia, Ib)
    assert np.array_equal(Fa, Fb)
    for field in ("position", "quaternion", "velocity", "omega"):
        assert np.array_equal(getattr(a.initial, field), getattr(b.initial, field)), field
    assert a.reactions == b.reactions and a.coordinates == b.coordinates


@pytest.mark.parametrize(("path", "value", "line_old", "line_new"), [
    ("bodies.rod.mass", 2.0, "    mass: 0.6                              # kg",
     "    mass: 2.0"),
    ("bodies.rod.position.1", 0.02, "    position: [0.113377771730964, 0.0176776695296637]",
     "    position: [0.113377771730964, 0.02]"),
    ("bodies.crank.angle", "50 deg", "    angle: 45 deg", "    angle: 50 deg"),
    ("joints.P.axis", [1, 0.5], "     axis: [1, 0]}", "     axis: [1, 0.5]}"),
    ("bodies.piston.shape.box.0", 0.09, "    shape: {box: [0.07, 0.07]}             # 70 mm bore",
     "    shape: {box: [0.09, 0.07]}"),
    ("gravity", [0, -1.62], "gravity: [0, -9.81]", "gravity: [0, -1.62]"),
])
def test_a_value_set_equals_the_file_written_with_it(path, value, line_old, line_new):
    """The file's own lines edited by hand and loaded give the same model, bit for bit
    (the shape-derived inertia follows a changed mass or shape, the joint frame a changed
    axis)."""
    text = SLIDER.read_text()
    assert line_old in text
    edited = mbody.loads(text.replace(line_old, line_new), str(SLIDER))
    same_model(mbody.load(SLIDER).with_values({path: value}), edited)


def test_a_driver_speed_with_units_and_the_assembled_pose():
    """``"100 rpm"`` as the file reads it; the driven model is assembled again (its
    velocities follow the new speed)."""
    base = mbody.loads(driven_text(), "driven.yaml")
    fresh = mbody.loads(driven_text().replace("speed: 100}", 'speed: "100 rpm"}'), "driven.yaml")
    got = base.with_values({"drivers.motor.speed": "100 rpm"})
    same_model(got, fresh)
    assert got.initial.omega[0, 2] == pytest.approx(100 * 2 * math.pi / 60, rel=1e-12)
    assert got.file_state is not None


def test_values_compose_and_leave_the_model_alone():
    base = mbody.load(SLIDER)
    one = base.with_values({"bodies.rod.mass": 2.0}).with_values({"bodies.crank.mass": 0.7})
    both = base.with_values({"bodies.rod.mass": 2.0, "bodies.crank.mass": 0.7})
    same_model(one, both)
    assert one.source.values == (("bodies.rod.mass", 2.0), ("bodies.crank.mass", 0.7))
    assert base.mass.tolist() == [0.4, 0.6, 0.5]
    # the later value wins
    assert one.with_values({"bodies.rod.mass": 3.0}).mass[1] == 3.0
    # numpy numbers are plain numbers to the file
    assert base.with_values({"bodies.rod.mass": np.float32(2.5)}).mass[1] == 2.5


def line_of(text: str, needle: str) -> int:
    return next(i for i, s in enumerate(text.splitlines(), 1) if needle in s)


@pytest.mark.parametrize(("values", "key", "pattern", "needle"), [
    ({"bodies.rdo.mass": 1}, "bodies.rdo.mass", r"no body named 'rdo' \(did you mean 'rod'\?\)",
     "bodies:"),
    ({"bodies.rod.mas": 1}, "bodies.rod.mas", r"no key 'mas' \(did you mean 'mass'\?\)",
     "- name: rod"),
    ({"bodeis.rod.mass": 1}, "bodeis.rod.mass", r"did you mean 'bodies'", None),
    ({"bodies.rod.position.2": 1}, "bodies.rod.position.2", r"has 2 components",
     "[0.113377771730964"),
    ({"bodies.rod.mass.0": 1}, "bodies.rod.mass.0", r"single value \(0.6\)", "mass: 0.6"),
    ({"joints.Z.at": [0, 0]}, "joints.Z.at", r"no joint named 'Z'", "joints:"),
    ({"loads.gass.force.0": 1}, "loads.gass.force.0", r"did you mean 'gas'", "loads:"),
    ({"bodies.rod.name": "bar"}, "bodies.rod.name", r"a name cannot be set", "name: rod"),
])
def test_a_bad_path_is_located_with_a_did_you_mean(values, key, pattern, needle):
    text = SLIDER.read_text()
    with pytest.raises(ModelError) as err:
        mbody.load(SLIDER).with_values(values)
    issue = err.value.issues[0]
    assert issue.key == key
    assert re.search(pattern, str(issue)), str(issue)
    assert issue.file == str(SLIDER)
    if needle is not None:
        assert issue.line == line_of(text, needle)


@pytest.mark.parametrize(("values", "pattern"), [
    ({"bodies.rod.mass": -1}, r"expected a number > 0, got -1"),
    ({"bodies.rod.mass": "2 kg"}, r"expected a number"),
    ({"bodies.rod.mass": float("nan")}, r"finite"),
    ({"joints.P.axis": [0, 0]}, r"the axis is the zero vector"),
    ({"loads.gas.force.0": "-50*sin(t"}, r"missing '\)'"),
])
def test_a_bad_value_is_refused_by_the_files_own_rules(values, pattern):
    """Refused where the file would be, at the line of the value the file gives, under
    the path that was set."""
    text = SLIDER.read_text()
    (path, value), = values.items()
    with pytest.raises(ModelError) as err:
        mbody.load(SLIDER).with_values(values)
    issue = err.value.issues[0]
    assert issue.key.startswith(path) and re.search(pattern, issue.message), str(issue)
    assert f"set by {path}=" in issue.hint
    file_line = int(re.search(r"on line (\d+)", issue.hint).group(1))
    assert issue.line == file_line
    name = path.split(".")[1]
    assert issue.line > line_of(text, f"name: {name}") if path.startswith("bodies") else True


def test_an_imported_model_takes_paths_of_its_yaml_form():
    """MJCF: the bodies are the links by their names in the YAML form mbody convert writes;
    a value is checked by the file's rules and located at the XML's line."""
    arm = mbody.load(ARM)
    first = arm.body_names[1]
    changed = arm.with_values({f"bodies.{first}.mass": 9.0})
    assert changed.mass[1] == 9.0 and np.array_equal(changed.mass[[0, 2]], arm.mass[[0, 2]])
    with pytest.raises(ModelError) as err:
        arm.with_values({f"bodies.{first}.mass": 0})
    issue = err.value.issues[0]
    assert issue.file == str(ARM) and issue.line > 0 and issue.key == f"bodies.{first}.mass"


def test_a_dictionary_models_values():
    spec = {"dimension": 2, "bodies": [{"name": "a", "mass": 1, "inertia": 1}]}
    model = mbody.load(spec)
    assert model.with_values({"bodies.a.mass": 4, "gravity": [0, -9.81]}).mass[0] == 4
    assert spec["bodies"][0]["mass"] == 1  # the caller's dictionary is not touched
    with pytest.raises(ModelError, match=r"gives no 'gravity' here"):
        model.with_values({"gravity.1": 3})


def test_a_large_file_is_read_again_and_must_not_have_changed(tmp_path, monkeypatch):
    monkeypatch.setattr(source_module, "KEEP_TEXT", 100)
    path = tmp_path / "m.yaml"
    path.write_text(SLIDER.read_text())
    model = mbody.load(path)
    assert model.source.text is None and model.source.digest
    assert model.with_values({"bodies.rod.mass": 2.0}).mass[1] == 2.0
    path.write_text(SLIDER.read_text().replace("mass: 0.6", "mass: 0.7"))
    with pytest.raises(MbodyError, match="changed since the model was read"):
        model.with_values({"bodies.rod.mass": 2.0})


def test_a_model_built_from_a_spec_has_no_document():
    from mbody.model.loader import load_text
    from mbody.model.validate import validate

    model = mbody.Model.from_spec(validate(load_text(SLIDER.read_text(), "x.yaml")))
    with pytest.raises(MbodyError, match="no document to set values in"):
        model.with_values({"bodies.rod.mass": 2.0})


def test_a_source_pickles_and_rebuilds_the_same_model():
    model = mbody.loads(driven_text(), "driven.yaml")
    again = pickle.loads(pickle.dumps(model.source))
    assert again.finish is model.source.finish and again.text == model.source.text


def run(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mbody", *argv], capture_output=True,
                          text=True, cwd=ROOT, timeout=120)


def test_set_on_the_command_line():
    """``--set`` on solve gives what with_values gives; a bad path or value exits 2 with
    the located message; the value is read as the file reads it (units, lists)."""
    p = run("solve", str(SLIDER), "--json", "--set", "bodies.rod.mass=2",
            "--set", "gravity=[0, -1.62]")
    assert p.returncode == 0, p.stderr
    import json

    got = json.loads(p.stdout)
    want = mbody.assemble(mbody.load(SLIDER).with_values(
        {"bodies.rod.mass": 2, "gravity": [0, -1.62]})).solve()
    assert got["coordinates"] == want.coordinates
    assert got["accelerations"] == want.accelerations.tolist()
    p = run("check", str(SLIDER), "--set", "bodies.rod.mas=2")
    assert p.returncode == 2 and "did you mean 'mass'" in p.stderr
    assert "Traceback" not in p.stderr
    p = run("check", str(SLIDER), "--set", "bodies.rod.mass=-2")
    assert p.returncode == 2 and f"{SLIDER}:" in p.stderr and "bodies.rod.mass" in p.stderr
    p = run("check", str(SLIDER), "--set", "bodies.rod.mass")
    assert p.returncode == 2 and "PATH=VALUE" in p.stderr
    p = run("check", str(SLIDER), "--set", "bodies.rod.mass=1:20")
    assert p.returncode == 2 and "base-60" in p.stderr


def test_convert_writes_the_model_with_the_values_set(tmp_path):
    """convert --set: the YAML written is the document with the value in place (read
    back, the same model as with_values gives); an MJCF import's YAML form too."""
    out = tmp_path / "p.yaml"
    p = run("convert", str(SLIDER), "-o", str(out), "--set", "bodies.rod.mass=2")
    assert p.returncode == 0, p.stderr
    same_model(mbody.load(out), mbody.load(SLIDER).with_values({"bodies.rod.mass": 2}))
    arm = mbody.load(ARM)
    name = arm.body_names[1]
    out = tmp_path / "arm.yaml"
    p = run("convert", str(ARM), "-o", str(out), "--set", f"bodies.{name}.mass=7")
    assert p.returncode == 0, p.stderr
    assert mbody.load(out).mass[1] == 7.0
    p = run("convert", str(SLIDER), "-o", str(tmp_path / "q.yaml"), "--set",
            "bodies.rod.mas=2")
    assert p.returncode == 2 and "did you mean 'mass'" in p.stderr
    assert not (tmp_path / "q.yaml").exists()


@pytest.mark.parametrize("file", sorted((ROOT / "models").glob("*.yaml")), ids=lambda p: p.stem)
def test_every_settable_path_resolves_and_every_entry_key_is_listed(file):
    """`settable_paths` (what an ``--allow-set`` pattern is matched against) lists only
    paths `resolve` accepts, and every body's and joint's keys."""
    from mbody.model.values import entry_names, resolve, settable_paths

    model = mbody.load(file)
    doc, names = model.source.read(), entry_names(model)
    paths = settable_paths(doc, names)
    assert len(paths) == len(set(paths))
    for p in paths:
        resolve(doc, p, names)  # raises on a path that names nothing
    for body in model.body_names:
        assert f"bodies.{body}.mass" in paths and f"bodies.{body}.color" in paths
    assert "gravity" in paths
    assert ("gravity.0" in paths) == ("gravity" in doc.data)  # components of what it gives

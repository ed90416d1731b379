"""A model written to MJCF and read back keeps the model file's order of bodies and
joints, so the rows and columns of its equations (and of every export) come in the same
order. MJCF's nesting alone does not keep it (a body comes after its parent, joints in
the tree's order, the joints MJCF does not hold last): the ``mbody:order`` entry of
``<custom>`` does."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import main
from mbody.errors import ModelError
from mbody.io.interop.mjcf import read_mjcf
from mbody.io.interop.mjcf_write import to_mjcf

MODELS = Path(__file__).resolve().parent.parent / "models"
ALL = sorted(p.stem for p in MODELS.glob("*.yaml"))


def _dense(x) -> np.ndarray:
    return x.toarray() if hasattr(x, "toarray") else np.asarray(x, dtype=float)


def _names(data: dict) -> tuple[list[str], list[str]]:
    return ([b["name"] for b in data["bodies"]], [j["name"] for j in data.get("joints", [])])


@pytest.mark.parametrize("name", ALL)
def test_bodies_and_joints_come_back_in_the_files_order(name):
    """Every shipped model: the document read back lists the bodies and joints as the
    YAML file does, so the equations' coordinates and reactions come in the same order
    (G's columns and M's rows at once, not up to a permutation)."""
    model = mbody.load(MODELS / f"{name}.yaml")
    xml = to_mjcf(model)
    data = read_mjcf(xml).data
    assert _names(data) == (list(model.body_names), [j.name for j in model.joints])
    back = mbody.load(data)
    A, B = mbody.assemble(model), mbody.assemble(back)
    assert B.coordinates == A.coordinates and B.reactions == A.reactions
    G, H = _dense(A.G), _dense(B.G)
    assert np.abs(G - H).max(initial=0.0) <= 1e-12 * max(1.0, float(np.abs(G).max(
        initial=0.0)))


def test_the_scotch_yoke_round_trips_in_order(tmp_path):
    """The case a user met: crank, yoke and O, P, S came back as yoke, crank and P, S, O
    through ``mbody convert`` YAML -> MJCF -> YAML."""
    xml, yml = tmp_path / "sy.xml", tmp_path / "sy.yaml"
    assert main(["convert", str(MODELS / "scotch_yoke.yaml"), "-o", str(xml)]) == 0
    assert main(["convert", str(xml), "-o", str(yml)]) == 0
    text = yml.read_text()
    bodies = re.findall(r"^  - name: (\w+)", text, re.M)
    joints = re.findall(r"^  - \{name: (\w+), type:", text, re.M)
    assert bodies == ["crank", "yoke"] and joints == ["O", "P", "S"]


def test_without_the_entry_the_tree_order_is_kept():
    """A file without ``mbody:order`` (plain MJCF, or written before it) reads in MJCF's
    order, as it always did: the parent first."""
    xml = to_mjcf(mbody.load(MODELS / "scotch_yoke.yaml"))
    line = next(ln for ln in xml.splitlines() if 'name="mbody:order"' in ln)
    data = read_mjcf(xml.replace(line + "\n", "")).data
    assert _names(data) == (["yoke", "crank"], ["P", "S", "O"])


def test_a_body_added_by_hand_follows_the_listed_ones():
    """The entry orders what it names; a body added to the file later (here first, fixed
    to the world) comes after them, in the file's order."""
    xml = to_mjcf(mbody.load(MODELS / "double_pendulum.yaml"))
    extra = ('<worldbody>\n<body name="base" pos="0 0.5 0"><inertial pos="0 0 0" mass="1" '
             'diaginertia="1 1 1"/></body>')
    data = read_mjcf(xml.replace("<worldbody>", extra, 1)).data
    assert _names(data)[0] == ["upper", "lower", "base"]


@pytest.mark.parametrize("data, message", [
    ('{"bodies": ["upper", "lowr"]}', "mbody:order: no body 'lowr' in the file (did you "
                                      "mean 'lower'?)"),
    ('{"joints": ["O", "Q"]}', "mbody:order: no joint 'Q' in the file"),
    ('{"bodys": ["upper"]}', "mbody:order: unknown key 'bodys' (did you mean 'bodies'?)"),
    ('{"bodies": "upper"}', "mbody:order: bodies must be a list of names"),
    ('{"bodies": ["upper", "upper"]}', "mbody:order: bodies names 'upper' twice"),
])
def test_a_wrong_order_entry_is_an_error_at_its_line(data, message):
    xml = to_mjcf(mbody.load(MODELS / "double_pendulum.yaml"))
    lines = xml.splitlines()
    k = next(i for i, ln in enumerate(lines) if 'name="mbody:order"' in ln)
    lines[k] = f"    <text name=\"mbody:order\" data='{data}'/>"
    with pytest.raises(ModelError) as err:
        read_mjcf("\n".join(lines), file="dp.xml")
    text = str(err.value)
    assert message in text, text
    assert f"dp.xml:{k + 1}:" in text

"""Hints for words mbody names otherwise (review R4, F10): a textbook's or another
program's word gets "mbody calls it '...'" (as a joint type's alias always did), and a
spelling suggestion that is far off is not offered ('frame' is not 'name')."""

from __future__ import annotations

from pathlib import Path

import pytest

import mbody
from mbody.errors import ModelError, closest, did_you_mean

BODY = "{name: rod, mass: 1, inertia: 0.1, position: [0, 0]"


def issues(tmp_path: Path, text: str) -> list:
    path = tmp_path / "m.yaml"
    path.write_text("dimension: 2\n" + text)
    with pytest.raises(ModelError) as err:
        mbody.load(path)
    return err.value.issues


@pytest.mark.parametrize(("text", "key", "message", "hint"), [
    (f"bodies: [{BODY}, omega: 1}}]\n", "bodies[0].omega", "unknown key 'omega'",
     "mbody calls it 'angular_velocity'"),
    (f"bodies: [{BODY}, theta: 0.3}}]\n", "bodies[0].theta", "unknown key 'theta'",
     "mbody calls it 'angle'"),
    (f"bodies: [{BODY}}}]\nloads: [{{name: f, type: force, body: rod, force: [1, 0], "
     "point: [0, 0.1]}]\n", "loads[0].point", "unknown key 'point'", "mbody calls it 'at'"),
    (f"bodies: [{BODY}}}]\nloads: [{{name: f, type: force, body: rod, force: [1, 0], "
     "position: [0, 0.1]}]\n", "loads[0].position", "unknown key 'position'",
     "mbody calls it 'at'"),
    (f"bodies: [{BODY}}}]\nloads: [{{name: c, type: moment, body: rod, torque: 2}}]\n",
     "loads[0].type", "unknown load type 'moment'",
     "mbody calls it 'torque': a couple, a pure moment"),
    (f"bodies: [{BODY}}}]\nloads: [{{name: c, type: couple, body: rod, torque: 2}}]\n",
     "loads[0].type", "unknown load type 'couple'",
     "mbody calls it 'torque': a couple, a pure moment"),
    (f"bodies: [{BODY}}}]\nloads: [{{name: s, type: spring, bodies: [ground, rod], "
     "at: [[0, 1], [0, 0]], k: 100, rest_length: 0.5}]\n", "loads[0].k", "unknown key 'k'",
     "mbody calls it 'stiffness'"),
])
def test_a_synonym_is_named(tmp_path, text, key, message, hint):
    found = issues(tmp_path, text)
    assert [(i.key, i.message, i.hint) for i in found] == [(key, message, hint)]


def test_a_models_name_written_name_is_named_model(tmp_path):
    """Review R7-14: `name:` at the top (a body's key, a natural guess for the model's)."""
    found = issues(tmp_path, f"name: arm\nbodies: [{BODY}}}]\n")
    assert [(i.key, i.hint) for i in found] == [("name", "mbody calls it 'model': the "
                                                 "model's name")]


def test_inertia_written_I_is_one_problem(tmp_path):
    """`I: 0.1` for `inertia`: the hint names the key, so its absence is not reported
    as well (as for a misspelt key)."""
    found = issues(tmp_path, "bodies: [{name: rod, mass: 1, I: 0.1, position: [0, 0]}]\n")
    assert [(i.key, i.hint) for i in found] == [("bodies[0].I", "mbody calls it 'inertia'")]


def test_a_far_off_spelling_is_not_suggested(tmp_path):
    """`frame` on a body was 'did you mean name?' (difflib finds them 0.67 alike: two
    edits in five letters); now the keys are listed."""
    found = issues(tmp_path, f"bodies: [{BODY}, frame: world}}]\n")
    assert len(found) == 1 and found[0].message == "unknown key 'frame'"
    assert found[0].hint.startswith("expected one of: name, mass, inertia")


def test_the_cli_prints_the_hints(tmp_path, capsys):
    from mbody.cli.app import main

    path = tmp_path / "m.yaml"
    path.write_text("dimension: 2\nbodies: [{name: rod, mass: 1, I: 0.1, omega: 2}]\n")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}:2:31: bodies[0].I: unknown key 'I' (mbody calls it 'inertia')" in err
    assert "bodies[0].omega: unknown key 'omega' (mbody calls it 'angular_velocity')" in err


@pytest.mark.parametrize(("word", "choices", "meant"), [
    ("intertia", ["inertia", "mass"], "inertia"),        # one letter added
    ("rest_lenght", ["rest_length"], "rest_length"),     # two swapped
    ("angular_velocty", ["angular_velocity"], "angular_velocity"),
    ("mas", ["mass", "name"], "mass"),
    ("DOP853", ["dop853", "rk45"], "dop853"),           # case only
    ("frame", ["name", "mass"], None),   # 2 edits in 5 letters, another first letter
    ("revolve", ["revolute", "prismatic"], "revolute"),  # 2 edits in 8 letters
    ("sped", ["speed", "angle"], "speed"),
    ("bodys", ["bodies", "joints"], "bodies"),           # 2 edits, the first letter kept
    ("damp", ["damping", "stiffness"], "damping"),       # cut short
    ("ngle", ["angle", "mass"], "angle"),                # the first letter lost: 1 edit
])
def test_closest_takes_spellings_a_few_edits_away(word, choices, meant):
    assert closest(word, choices) == meant


def test_a_synonym_is_offered_only_where_mbody_has_it():
    """`position` is the body's key; on a load (no `position`) it means `at`. A word whose
    synonym is not among the choices falls back to the spelling."""
    assert did_you_mean("position", ["at", "force"]) == "mbody calls it 'at'"
    assert did_you_mean("omega", ["mass", "inertia"]) == ""
    assert did_you_mean("pin", ["revolute", "fixed"], {"pin": "revolute"}) == \
        "mbody calls it 'revolute'"

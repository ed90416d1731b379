"""Looking a result or a record up by a wrong key, as a notebook user does: every lookup
says what the key should be (the closest label, or the ones there are), and a label of the
other kind says where it is read."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import mbody
from mbody.errors import MbodyTypeError

MODELS = Path(__file__).resolve().parent.parent / "models"


@pytest.fixture(scope="module")
def dp():
    return mbody.load(MODELS / "double_pendulum.yaml")


def message(err: pytest.ExceptionInfo) -> str:
    """A KeyError's text (str() of a KeyError quotes it)."""
    return err.value.args[0]


def test_a_reaction_label_read_as_an_acceleration_points_to_reactions(dp):
    """Before: KeyError "no coordinate 'A.Fx'; " (a dangling "; ", no way on)."""
    sol = mbody.assemble(dp).solve()
    with pytest.raises(KeyError) as err:
        sol["A.Fx"]
    assert message(err) == "no coordinate 'A.Fx': it is a reaction component, read as " \
                           "sol.reactions['A.Fx']"
    assert sol.reactions["A.Fx"] == sol.reactions.array[list(sol.reactions).index("A.Fx")]
    with pytest.raises(KeyError) as err:
        sol["A.fx"]       # closest to a reaction component, not to a coordinate
    assert message(err).endswith("did you mean the reaction component sol.reactions['A.Fx']?")
    with pytest.raises(KeyError) as err:
        sol["upper.thta"]
    assert message(err) == "no coordinate 'upper.thta'; did you mean 'upper.theta'?"
    with pytest.raises(KeyError) as err:
        sol["zzz"]
    assert message(err).startswith("no coordinate 'zzz' (the coordinates: upper.x, upper.y")
    assert not message(err).endswith("; ")


def test_a_misspelt_reaction_component_gets_a_did_you_mean(dp):
    reactions = mbody.assemble(dp).solve().reactions
    with pytest.raises(KeyError) as err:
        reactions["A.fx"]
    assert message(err) == "no reaction component 'A.fx'; did you mean 'A.Fx'?"
    assert "A.fx" not in reactions and "A.Fx" in reactions
    assert reactions.get("A.fx", 7.0) == 7.0 and reactions.get("A.Fx") == reactions["A.Fx"]


def test_a_misspelt_constraint_row_gets_a_did_you_mean(dp):
    """Before: ValueError "'A.fx' is not in list"."""
    jac = mbody.assemble(dp).jacobian()
    with pytest.raises(KeyError) as err:
        jac.row("A.fx")
    assert message(err) == "no constraint row 'A.fx'; did you mean 'A.Fx'?"
    with pytest.raises(KeyError) as err:
        jac.row("upper.x")
    # worded by the one lookup error since review R3 (Y5; was "(a row per reaction
    # component, .rows: ...)")
    assert message(err) == ("no constraint row 'upper.x' (the rows, one per reaction "
                            "component: O.Fx, O.Fy, A.Fx, A.Fy)")
    # the pin O holds the upper rod's end on the ground: its x row is the rod's v_x, less
    # omega times the end's height above the mass centre (0.25 cos 30 deg). The model file
    # gives the mass centre to 15 digits (a relative 2e-15 here): 1e-12 is rounding only
    height = 0.25 * math.cos(math.radians(30))
    assert jac.row("O.Fx") == pytest.approx({"upper.x": 1.0, "upper.theta": -height},
                                            rel=1e-12)


def test_bodies_and_joints_are_found_by_name_and_by_index(dp):
    """Before: model.bodies[0] a KeyError, model.joints['A'] a TypeError, and
    model.bodies['uper'] a bare KeyError; repr(model.joints) '<2 records; made so far: 2>'."""
    assert dp.bodies[0] is dp.bodies["upper"] and dp.bodies[-1] is dp.bodies["lower"]
    assert dp.joints["A"] is dp.joints[1] and dp.joints["A"].child == "lower"
    assert "A" in dp.joints and dp.joints[0] in dp.joints and "C" not in dp.joints
    assert list(dp.bodies) == ["upper", "lower"]          # still a mapping by name
    assert [j.name for j in dp.joints] == ["O", "A"]      # still a sequence of joints
    assert repr(dp.joints) == "<2 joints: O, A>"
    assert repr(dp.bodies) == "<2 bodies: upper, lower>"
    with pytest.raises(KeyError) as err:
        dp.bodies["uper"]
    assert message(err) == "no body named 'uper'; did you mean 'upper'?"
    with pytest.raises(KeyError) as err:
        dp.joints["a"]
    assert message(err) == "no joint named 'a'; did you mean 'A'?"
    with pytest.raises(KeyError) as err:
        dp.joints["pivot"]
    assert message(err) == "no joint named 'pivot' (the joints: O, A)"
    with pytest.raises(IndexError, match=r"body index 2 out of range \(2 bodies: upper, lower\)"):
        dp.bodies[2]
    with pytest.raises(IndexError, match=r"joint index -3 out of range \(2 joints: O, A\)"):
        dp.joints[-3]
    # an MbodyTypeError (was a plain TypeError "joints are found by name or by index"):
    # one wrong-type error across the API (review R3, B6)
    with pytest.raises(MbodyTypeError) as err:
        dp.joints[0.0]
    assert message(err) == ("joints[key] must be a name (str) or an index (int), got "
                            "float 0.0")


def test_bodies_get_is_by_name_as_the_mapping_keys_are():
    """`model.bodies` is a mapping of names: `get` agrees with `in` (an index is for
    ``bodies[0]``, not a key), and returns the default for anything not a name there."""
    dp = mbody.load(MODELS / "double_pendulum.yaml")
    assert 0 not in dp.bodies and dp.bodies.get(0) is None
    assert dp.bodies.get(5, "none") == "none" and dp.bodies.get(1.5, "none") == "none"
    assert dp.bodies.get("upper") is dp.bodies["upper"] is dp.bodies[0]
    assert dp.bodies.get("uper", "none") == "none"


@pytest.mark.parametrize("path", ["located", "fast"])
def test_loads_are_found_by_name_on_both_reading_paths(path, monkeypatch):
    """The located reader and the bulk one (`mbody.model.fast`, here for a small file
    too) make the same records, found the same ways."""
    import yaml

    from mbody.model import fast

    monkeypatch.setattr(fast, "MIN_BYTES", 0)
    doc = {"dimension": 2, "bodies": [{"name": "a", "mass": 1, "inertia": 1}],
           "loads": [{"name": "push", "type": "force", "body": "a", "force": [1, 0]},
                     {"name": "turn", "type": "torque", "body": "a", "torque": 2}]}
    text = yaml.safe_dump(doc, sort_keys=False, default_flow_style=None)
    if path == "located":
        text += "# \u00e9\n"   # not ASCII: the bulk reader leaves it to the located one
    assert (fast.fast_spec(text, "m.yaml") is not None) == (path == "fast")
    model = mbody.loads(text)
    assert model.loads["turn"] is model.loads[1] and model.loads["turn"].type == "torque"
    assert repr(model.loads) == "<2 loads: push, turn>"
    with pytest.raises(KeyError) as err:
        model.loads["psh"]
    assert message(err) == "no load named 'psh'; did you mean 'push'?"
    joints = model.joints
    assert repr(joints) == "<no joints>"
    with pytest.raises(KeyError) as err:
        joints["A"]
    assert message(err) == "no joint named 'A' (this model has no joints)"


def test_generalized_known_gets_the_did_you_mean_solve_gives(dp):
    asm = mbody.assemble(dp)
    with pytest.raises(mbody.MbodyError) as err:
        asm.generalized(known={"A.fx": 1.0})
    assert str(err.value) == "no reaction component 'A.fx' in this model; did you mean 'A.Fx'?"
    with pytest.raises(mbody.MbodyError) as solved:
        asm.solve(known={"A.fx": 1.0})
    assert str(solved.value) == str(err.value)


def test_every_lookup_by_name_says_the_same_way_what_is_there():
    """One KeyError for every lookup by name (`mbody.errors.not_found`): a did-you-mean,
    else the names there are; never a dangling '; ' (review R3, Y5)."""
    dp = mbody.load(MODELS / "double_pendulum.yaml")
    asm = mbody.assemble(dp)
    sol = asm.solve()
    cases = [
        (lambda: asm.bodies["uppr"], "no body named 'uppr'; did you mean 'upper'?"),
        (lambda: asm.bodies["zz"], "no body named 'zz' (the bodies: upper, lower)"),
        (lambda: sol.reactions["o.fx"], "no reaction component 'o.fx'; did you mean 'O.Fx'?"),
        (lambda: sol.reactions["zz"], "no reaction component 'zz' (the components: O.Fx, "
                                      "O.Fy, A.Fx, A.Fy)"),
        (lambda: mbody.solve_many(dp, [dp.initial]).reaction("zz"),
         "no reaction 'zz' (the reactions: O.Fx, O.Fy, A.Fx, A.Fy)"),
    ]
    for call, expected in cases:
        with pytest.raises(KeyError) as err:
            call()
        assert message(err) == expected


def test_the_closest_name_is_difflibs_among_a_thousand():
    # closest() skips the names whose lengths alone rule out difflib's cutoff (its first
    # test, in its own arithmetic) before difflib looks at the rest: the same answer as
    # difflib's over all of them, ties and near-misses included (then the same test of a
    # misspelling: the first letter, or a few edits)
    import difflib
    import random

    from mbody.errors import _EDITS_PER_LETTER, CLOSE_CUTOFF, _edits, closest

    def reference(word: str, names: list[str]) -> str | None:
        same = [c for c in names if c.casefold() == word.casefold()]
        if same:
            return same[0]
        close = difflib.get_close_matches(word, names, n=1, cutoff=CLOSE_CUTOFF)
        if not close:
            return None
        meant = close[0]
        if word[:1].casefold() == meant[:1].casefold() or _edits(word, meant) <= max(
                1, max(len(word), len(meant)) // _EDITS_PER_LETTER):
            return meant
        return None

    rng = random.Random(7)
    names = ["".join(rng.choice("jl_.012angle") for _ in range(rng.randint(1, 16)))
             for _ in range(1000)]
    words = [w[:-1] for w in names[:40]] + [w + "x" for w in names[40:80]] + \
        ["", "m", "a_x", "j12.angle_dd", "ANGLE", "q" * 30]
    found = 0
    for word in words:
        expected = reference(word, names)
        assert closest(word, names) == expected, word
        found += expected is not None
    assert found >= 60

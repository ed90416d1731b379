"""`mbody.verify`: every diagnosis on shipped models, planar and spatial.

The student equations below are written by hand from the course's worked examples and
from the shipped models' free bodies (their numbers are in the model files' comments
and in `mbody assemble`). Each right equation is also written in other orders, scaled,
with the vocabulary's symbols and with rounded numbers, and must stay `correct`; each
wrong one must get its diagnosis, never `correct`.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

import mbody
from mbody.answers import DIAGNOSES, AnswersError, verify
from mbody.answers.compare import CONST, Row, fit
from mbody.answers.parse import EquationError, parse_equation

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
_CACHE: dict[str, mbody.Model] = {}


def model(name: str) -> mbody.Model:
    if name not in _CACHE:
        _CACHE[name] = mbody.load(MODELS / f"{name}.yaml")
    return _CACHE[name]


def check(name: str, body: str, eq: str, **kw):
    """The single check of one equation."""
    v = verify(model(name), [{"body": body, "eq": eq}], **kw)
    assert len(v.checks) == 1
    return v.checks[0]


def diagnosis(name: str, body: str, eq: str) -> str:
    return check(name, body, eq).diagnosis


# == correct, however it is written ===================================================

CORRECT = [
    # worked example 1: m = 10, I_G = 0.5, 50 N along x, 20 N m about G
    ("seed_example_1", "plate", "10*a_x = 50", "plate.x"),
    ("seed_example_1", "plate", "a_x = 5", "plate.x"),
    ("seed_example_1", "plate", "50 - m*a_x = 0", "plate.x"),
    ("seed_example_1", "plate", "m*a_x = F_push_x", "plate.x"),
    ("seed_example_1", "plate", "m*a_y = 0", "plate.y"),
    ("seed_example_1", "plate", "I_G*alpha = 50*0.4", "plate.theta"),
    ("seed_example_1", "plate", "alpha = 20/I_G", "plate.theta"),
    ("seed_example_1", "plate", "-2*alpha = -80", "plate.theta"),
    # worked example 2: I = (2, 3, 4), w = (1, 2, 3): alpha = (-3, 2, -0.5)
    ("seed_example_2", "body", "I_1*alpha_1 = (I_2 - I_3)*w_2*w_3", "body.w1"),
    ("seed_example_2", "body", "(I_3 - I_2)*w_2*w_3 + I_1*alpha_1 = 0", "body.w1"),
    ("seed_example_2", "body", "alpha_1 = -3", "body.w1"),
    ("seed_example_2", "body", "2.000*alpha_1 + 6.000 = 0", "body.w1"),
    ("seed_example_2", "body", "alpha_2 = (I_3 - I_1)*w_3*w_1/I_2", "body.w2"),
    ("seed_example_2", "body", "4*alpha_3 = -2", "body.w3"),
    ("seed_example_2", "body", "α_3 = (I_1 - I_2)*ω_1*ω_2/I_3", "body.w3"),
    ("seed_example_2", "body", "m*a_z = 0", "body.z"),
    # the physical pendulum: m = 2, I_G = 0.167083, G 0.5 m below the pin at 30 deg
    ("pendulum", "rod", "2*a_y = O.Fy - 19.62", "rod.y"),
    ("pendulum", "rod", "O.Fy - m*g - m*a_y = 0", "rod.y"),
    ("pendulum", "rod", "a_y = (O.Fy - 19.62)/2", "rod.y"),
    ("pendulum", "rod", "-4*a_y = -2*O.Fy + 39.24", "rod.y"),
    ("pendulum", "rod", "m*a_x = O.Fx", "rod.x"),
    ("pendulum", "rod", "0.1671*alpha = -0.433*O.Fx - 0.25*O.Fy", "rod.theta"),
    ("pendulum", "rod", "I_G*alpha = -0.5*cos(theta)*O.Fx - 0.5*sin(theta)*O.Fy",
     "rod.theta"),
    # moments about the pin with the transport term, and with the pin's inertia
    ("pendulum", "rod", "I_G*alpha + 0.433013*m*a_x + 0.25*m*a_y = -m*g*0.25", "rod.theta"),
    ("pendulum", "rod", "(I_G + m*0.5^2)*alpha = -m*g*0.5*sin(theta)", "rod.theta"),
    # spatial with reactions and a full tensor
    ("heavy_top", "top", "m*a_z = pivot.Fz - m*g", "top.z"),
    ("heavy_top", "top", "0.0008*alpha_1 + 0.0632608 = 0.0469846*pivot.Fy "
     "+ 0.017101*pivot.Fz", "top.w1"),
    ("heavy_top", "top", "I_1*alpha_1 + (I_3 - I_2)*w_2*w_3 = 0.0469846*pivot.Fy "
     "+ 0.017101*pivot.Fz", "top.w1"),
    ("rotated_full_inertia", "bracket",
     "I_11*alpha_1 + I_12*alpha_2 + I_13*alpha_3 + 0.232 = 0.743015 + 0.5", "bracket.w1"),
    ("rotated_full_inertia", "bracket", "3*a_z = 15 - 29.43", "bracket.z"),
    ("rotor_offset_load", "rotor", "I_2*alpha_2 = (I_3 - I_1)*w_3*w_1", "rotor.w2"),
    ("double_pendulum", "upper", "m*a_x = O.Fx - A.Fx", "upper.x"),
    ("double_pendulum", "lower", "a_y = A.Fy - g", "lower.y"),
    ("spring_mass_damper", "block", "2*a_y = 38.4 - 19.62", "block.y"),
]


@pytest.mark.parametrize("name, body, eq, row", CORRECT)
def test_a_right_equation_written_any_way_is_correct(name, body, eq, row):
    c = check(name, body, eq)
    assert c.diagnosis == "correct", c.explanation
    assert c.row == row


def test_the_heavy_tops_euler_equation_about_its_fixed_pivot_is_correct():
    # I_P = I_G + m d^2 = 0.0008 + 0.05^2 = 0.0033 about axis 1; the gyroscopic term with
    # I_P: (I_3 - 0.0033) w_2 w_3; gravity's moment about the pivot m g 0.017101
    c = check("heavy_top", "top", "0.0033*alpha_1 + (I_3 - 0.0033)*w_2*w_3 = m*g*0.017101")
    assert c.diagnosis == "correct" and c.details["form"] == "fixed_pivot"


# == each mistake of the course's table ===============================================

def test_missing_gyroscopic_term_spatial():
    c = check("seed_example_2", "body", "I_3*alpha_3 = 0")
    assert c.diagnosis == "missing_gyroscopic_term"
    assert c.row == "body.w3" and c.expected == "4 alpha_3 + 2 = 0"
    assert "(I_2 − I_1) w_1 w_2" in c.explanation and "= 2 N m" in c.explanation
    assert c.details["value"] == pytest.approx(2.0)
    assert diagnosis("seed_example_2", "body", "alpha_1 = 0") == "missing_gyroscopic_term"
    # with reactions and a full tensor
    assert diagnosis("heavy_top", "top", "0.0008*alpha_1 = 0.0469846*pivot.Fy + "
                     "0.017101*pivot.Fz") == "missing_gyroscopic_term"
    assert diagnosis("rotated_full_inertia", "bracket", "0.08*alpha_1 - 0.012*alpha_2 + "
                     "0.004*alpha_3 = 1.24302") == "missing_gyroscopic_term"
    # about the fixed pivot: I_P alpha = M_P without w x I_P w
    c = check("heavy_top", "top", "0.0033*alpha_1 = m*g*0.0171010")
    assert c.diagnosis == "missing_gyroscopic_term" and c.details["point"] == "joint pivot"


def test_single_inertia_in_space():
    # rotor: principal moments (0.2625, 0.2625, 0.225); the side load's moment -5 N m
    c = check("rotor_offset_load", "rotor", "I_3*alpha_1 = -5")
    assert c.diagnosis == "single_inertia_in_space"
    assert c.details["inertia_used"] == pytest.approx(0.225)
    assert "0.2625 alpha_1" in c.explanation
    # the mean of the principal moments, written as a number
    assert diagnosis("rotor_offset_load", "rotor", "0.25*alpha_1 = -5") == \
        "single_inertia_in_space"
    # a full tensor: its I_11 alone, no products of inertia, no gyroscopic term
    c = check("rotated_full_inertia", "bracket", "0.08*alpha_1 = 0.743015 + 0.5")
    assert c.diagnosis == "single_inertia_in_space" and c.row == "bracket.w1"
    # an inertia that is none of the body's is not "single inertia": the moment is wrong
    assert diagnosis("rotor_offset_load", "rotor", "I_1*alpha_1 = -7") == \
        "not_an_equation_of_this_body"


def test_wrong_moment_point():
    # pendulum: moments about the pin, m g (L/2) sin 30 = 4.905 N m, with I_G kept
    c = check("pendulum", "rod", "I_G*alpha = -m*g*0.25")
    assert c.diagnosis == "wrong_moment_point" and c.details["point"] == "joint O"
    assert c.expected == "0.167083 alpha = -0.433013 O.Fx - 0.25 O.Fy"
    assert "0.866025 a_x + 0.5 a_y" in c.details["transport_term"]
    # the lower rod of the double pendulum about its pin A (which moves)
    c = check("double_pendulum", "lower", "I_G*alpha = -m*g*0.176777")
    assert c.diagnosis == "wrong_moment_point" and c.details["point"] == "joint A"
    # I_A alpha = M_A about the moving pin A: only about a fixed point
    c = check("double_pendulum", "lower", "(I_G + m*0.25^2)*alpha = -m*g*0.176777")
    assert c.diagnosis == "wrong_moment_point" and c.details["form"] == "moving_pivot"
    # spatial: the heavy top about its pivot, gravity's moment m g 0.017101 with I_G
    c = check("heavy_top", "top", "0.0008*alpha_1 + 0.0632608 = m*g*0.0171010")
    assert c.diagnosis == "wrong_moment_point" and c.row == "top.w1"


def test_reaction_treated_as_known():
    # the pin force's solved value 15.9435 N (pendulum.yaml) put in as a number
    c = check("pendulum", "rod", "2*a_y = 15.9435 - 19.62")
    assert c.diagnosis == "reaction_treated_as_known"
    assert c.details["reactions"] == ["O.Fy"]
    assert c.details["value_used"] == pytest.approx(15.9435, rel=1e-6)
    assert c.details["value_solved"] == pytest.approx(15.9435, abs=1e-4)
    # the static guess O.Fy = m g
    c = check("pendulum", "rod", "2*a_y = 0")
    assert c.diagnosis == "reaction_treated_as_known"
    assert c.details["value_used"] == pytest.approx(19.62)
    # spatial: the top's pivot force taken as its weight
    c = check("heavy_top", "top", "0.0008*alpha_1 + 0.0632608 = 0.0469846*pivot.Fy "
              "+ 0.017101*9.81")
    assert c.diagnosis == "reaction_treated_as_known"
    assert c.details["reactions"] == ["pivot.Fz"]
    assert c.details["value_used"] == pytest.approx(9.81, rel=1e-5)


def test_missing_reaction():
    c = check("pendulum", "rod", "2*a_y = -19.62")
    assert c.diagnosis == "missing_reaction" and c.details["reactions"] == ["O.Fy"]
    # the upper rod of the double pendulum: the lower rod's pull at A forgotten
    c = check("double_pendulum", "upper", "m*a_x = O.Fx")
    assert c.diagnosis == "missing_reaction" and c.details["reactions"] == ["A.Fx"]
    assert c.details["term"] == "-A.Fx"
    # spatial
    c = check("heavy_top", "top", "0.0008*alpha_1 + 0.0632608 = 0.0469846*pivot.Fy")
    assert c.diagnosis == "missing_reaction" and c.details["reactions"] == ["pivot.Fz"]


def test_reaction_sign():
    # upper is the parent of A: it feels -A.Fx (Newton's third law)
    c = check("double_pendulum", "upper", "m*a_x = O.Fx + A.Fx")
    assert c.diagnosis == "reaction_sign" and c.details["reactions"] == ["A.Fx"]
    assert "parent of joint A" in c.explanation
    c = check("pendulum", "rod", "2*a_y = -O.Fy - 19.62")
    assert c.diagnosis == "reaction_sign" and "child of joint O" in c.explanation
    # spatial: both pivot components of the Euler row reversed: on the child, the
    # moment's sign is r × F's (lever_arm_sign), not the third law's
    c = check("heavy_top", "top", "0.0008*alpha_1 + 0.0632608 = -0.0469846*pivot.Fy "
              "- 0.017101*pivot.Fz")
    assert c.diagnosis == "lever_arm_sign"
    assert c.details["reactions"] == ["pivot.Fy", "pivot.Fz"]


def test_missing_applied_load():
    c = check("seed_example_1", "plate", "0.5*alpha = 0")
    assert c.diagnosis == "missing_applied_load" and c.details["loads"] == ["push"]
    assert c.expected == "0.5 alpha = 20"
    c = check("pendulum", "rod", "2*a_y = O.Fy")
    assert c.diagnosis == "missing_applied_load" and c.details["loads"] == ["gravity"]
    c = check("spring_mass_damper", "block", "2*a_y = -19.62")
    assert c.diagnosis == "missing_applied_load" and c.details["loads"] == ["suspension"]
    # spatial: gravity, a force, a couple
    assert check("rotated_full_inertia", "bracket", "3*a_z = 15").details["loads"] == \
        ["gravity"]
    assert check("rotor_offset_load", "rotor", "m*a_y = 0").details["loads"] == ["side_load"]
    c = check("rotated_full_inertia", "bracket",
              "0.08*alpha_1 - 0.012*alpha_2 + 0.004*alpha_3 + 0.232 = 0.743015")
    assert c.diagnosis == "missing_applied_load" and c.details["loads"] == ["motor"]


def test_not_an_equation_of_this_body():
    c = check("pendulum", "rod", "2*a_y = 3*O.Fy - 19.62")
    assert c.diagnosis == "not_an_equation_of_this_body" and c.row == "rod.y"
    assert "O.Fy has -3 where -1 is expected" in c.explanation
    # a reaction of a joint the body does not touch
    c = check("double_pendulum", "lower", "m*a_x = O.Fx + A.Fx")
    assert c.diagnosis == "not_an_equation_of_this_body" and c.details["foreign"] == ["O.Fx"]
    # not linear in the unknowns
    c = check("pendulum", "rod", "alpha*O.Fx = 1")
    assert c.diagnosis == "not_an_equation_of_this_body" and "product" in c.explanation
    # no unknown at all
    assert diagnosis("pendulum", "rod", "m*g = 19.62") == "not_an_equation_of_this_body"
    # the gyroscopic term with the wrong sign: a diagnosis of its own
    c = check("seed_example_2", "body", "I_1*alpha_1 = (I_3 - I_2)*w_2*w_3")
    assert c.diagnosis == "gyroscopic_term_sign" and c.row == "body.w1"
    # a true equation mixing two rows is not one row
    c = check("seed_example_1", "plate", "10*a_x + 10*a_y = 50")
    assert c.diagnosis == "not_an_equation_of_this_body"
    assert "combines the rows plate.x, plate.y" in c.explanation
    # moments about the pin with a transport term twice too large
    c = check("pendulum", "rod", "I_G*alpha + 0.866025*m*a_x + 0.5*m*a_y = -m*g*0.25")
    assert c.diagnosis == "not_an_equation_of_this_body"
    assert "a_x has 1.73205 where 0.866025 is expected" in c.explanation


WRONG = [
    ("pendulum", "rod", "2*a_y = O.Fy - 19.82"),           # 1 % off
    ("pendulum", "rod", "2.02*a_y = O.Fy - 19.62"),
    ("pendulum", "rod", "0.1671*alpha = -0.4330*O.Fx - 0.26*O.Fy"),
    ("pendulum", "rod", "I_G*alpha = -0.433013*O.Fx"),
    ("pendulum", "rod", "I_G*alpha = -0.433013*O.Fx - 0.25*O.Fy + 0.001"),
    ("seed_example_1", "plate", "0.5*alpha = 19.9"),
    ("seed_example_1", "plate", "10*a_x = 50 + 0.0001*a_y"),
    ("seed_example_2", "body", "2*alpha_1 + 6.03 = 0"),       # 0.5 % off
    ("seed_example_2", "body", "I_1*alpha_1 = 0"),
    ("heavy_top", "top", "a_x = pivot.Fx + pivot.Fy"),
    ("rotated_full_inertia", "bracket", "0.08*alpha_1 - 0.012*alpha_2 + 0.232 = 1.24302"),
]


@pytest.mark.parametrize("name, body, eq", WRONG)
def test_a_wrong_equation_is_never_called_correct(name, body, eq):
    c = check(name, body, eq)
    assert c.diagnosis != "correct" and c.diagnosis in DIAGNOSES


def test_tolerance_decides_how_rounded_a_number_may_be():
    eq = "0.167*alpha = -0.433*O.Fx - 0.25*O.Fy"  # I_G 0.167083: 5e-4 off
    assert check("pendulum", "rod", eq).diagnosis == "correct"
    assert check("pendulum", "rod", eq, tol=1e-4).diagnosis != "correct"
    assert check("pendulum", "rod", "0.17*alpha = -0.43*O.Fx - 0.25*O.Fy",
                 tol=2e-2).diagnosis == "correct"


def test_rounding_where_terms_cancel_is_judged_by_the_terms():
    # 50 - 49.9 is 0.1 N from two rounded numbers, so the net may be off by 0.1 %
    # of 99.9, far more than 0.1 % of 0.1
    v = verify(model("seed_example_1"), [{"body": "plate", "eq": "10*a_x = 50.04 - 0.04"}])
    assert v.checks[0].diagnosis == "correct"


# == the whole answers, files, errors =================================================

def test_seed_example_answer_files_end_to_end():
    v = mbody.verify(MODELS / "seed_example_1.yaml", MODELS / "answers/seed_example_1.yaml")
    assert [c.diagnosis for c in v.checks] == [
        "correct", "correct", "correct", "correct", "missing_applied_load",
        "not_an_equation_of_this_body"]
    assert v.student == "worked example 1" and not v.ok and v.correct == 4
    assert v.uncovered == () and v.rows == 3
    v = mbody.verify(str(MODELS / "seed_example_2.yaml"),
                     str(MODELS / "answers/seed_example_2.yaml"))
    assert [c.diagnosis for c in v.checks] == [
        "correct", "correct", "missing_gyroscopic_term", "correct", "correct"]
    assert [u.row for u in v.uncovered] == ["body.y", "body.z", "body.w3"]
    assert v.checks[2].line == 7
    d = v.to_dict()
    assert [e["index"] for e in d["equations"]] == [1, 2, 3, 4, 5]
    # equation 4 (alpha_1 = -3) gives body.w1 again, as equation 1 did
    assert d["summary"] == {"equations": 5, "correct": 4, "rows": 6, "uncovered": 3,
                            "duplicates": 1, "required": "answered"}
    assert "body.w3" in str(v) and "missing_gyroscopic_term" in str(v)


def test_every_answer_file_shipped_verifies():
    for path in sorted((MODELS / "answers").glob("*.yaml")):
        target = MODELS / path.name
        v = verify(mbody.load(target), path)
        assert v.checks and all(c.diagnosis in DIAGNOSES for c in v.checks), path


def errors(name: str, text: str, tmp_path) -> list[str]:
    f = tmp_path / "answers.yaml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(AnswersError) as exc:
        verify(model(name), f)
    return [str(i) for i in exc.value.issues]


def test_bad_answers_are_reported_with_file_line_column_and_did_you_mean(tmp_path):
    text = ("equations:\n"
            "  - {body: rdo, eq: \"2*a_y = O.Fy\"}\n"
            "  - {body: rod, eq: \"2*a_y = O.Fy - m*gg\"}\n"
            "  - {body: rod, eq: \"2*a_y = = O.Fy\"}\n"
            "  - body: rod\n"
            "    eq: 2*a_y = O.Fz\n"
            "  - {body: rod, eqn: \"a_x = 0\"}\n")
    out = errors("pendulum", text, tmp_path)
    f = str(tmp_path / "answers.yaml")
    # every problem at once, in the file's order: an entry's unknown key does not hide
    # the other equations' problems (review R4, F5)
    assert [o.split(": ")[0] for o in out] == [f"{f}:{at}" for at in (
        "2:12", "3:39", "4:30", "6:17", "7:5", "7:17")]
    assert out[4].startswith(f"{f}:7:5: equations[4]: missing eq")
    assert out[5].startswith(f"{f}:7:17: equations[4].eqn: unknown key 'eqn'")
    assert "did you mean 'eq'?" in out[5]
    out = errors("pendulum", text.replace("eqn", "eq"), tmp_path)
    assert out[0].startswith(f"{f}:2:12: equations[0].body: no body named 'rdo'")
    assert "did you mean 'rod'?" in out[0]
    # columns point at the character: "2*a_y = O.Fy - m*gg" starts at column 22
    assert out[1].startswith(f"{f}:3:39: equations[1].eq: unknown name 'gg'")
    assert "did you mean 'g'?" in out[1]
    assert out[2].startswith(f"{f}:4:30: equations[2].eq: nothing on the left of '='") or \
        out[2].startswith(f"{f}:4:30: equations[2].eq: unexpected '='")
    assert out[3].startswith(f"{f}:6:17: equations[3].eq: no reaction component 'O.Fz'")
    assert "did you mean 'O.Fx'?" in out[3] or "did you mean 'O.Fy'?" in out[3]


def test_names_of_the_other_kind_of_body_are_explained(tmp_path):
    out = errors("seed_example_2", "equations:\n  - {body: body, eq: 'I_G*alpha = 0'}\n",
                 tmp_path)
    assert "inertia tensor, not one inertia" in out[0]
    out = errors("seed_example_1", "equations:\n  - {body: plate, eq: 'I_1*alpha_1 = 0'}\n",
                 tmp_path)
    assert "one moment of inertia: I_G" in out[0]
    out = errors("seed_example_1", "equations:\n  - {body: plate, eq: 'm*a_y = -m*g'}\n",
                 tmp_path)
    assert "no gravity" in out[0]
    out = errors("rotated_full_inertia",
                 "equations:\n  - {body: bracket, eq: 'I_1*alpha_1 = 0'}\n", tmp_path)
    assert "not diagonal" in out[0] and "I_11" in out[0]


def test_empty_or_malformed_answer_files(tmp_path):
    assert "empty" in errors("pendulum", "", tmp_path)[0]
    assert "no 'equations:' list" in errors("pendulum", "student: x\n", tmp_path)[0]
    assert "empty" in errors("pendulum", "equations: []\n", tmp_path)[0]
    assert "missing eq" in errors("pendulum", "equations:\n  - {body: rod}\n", tmp_path)[0]
    assert "YAML syntax error" in errors("pendulum", "equations: [\n", tmp_path)[0]
    with pytest.raises(AnswersError, match="no such file"):
        verify(model("pendulum"), tmp_path / "missing.yaml")


def test_parser_is_safe_and_points_at_its_errors():
    with pytest.raises(EquationError) as exc:
        parse_equation("2a_x = 0")
    assert exc.value.position == 1 and "'*'" in exc.value.hint
    for text in ("__import__('os') = 0", "a_x = [0]", "a_x < 0",
                 "a_x = 0 = 0", "a_x", "= 3", "sin a_x = 0", "(a_x = 0"):
        with pytest.raises(EquationError):
            parse_equation(text)
    # '==', a comparison's spelling (review R7-14): said as such, at the first '='
    with pytest.raises(EquationError) as exc:
        parse_equation("m*a_x == O.Fx")
    assert exc.value.position == 6 and "'=='" in str(exc.value) and "one '='" in \
        exc.value.hint
    # a dotted name is only ever looked up in the vocabulary
    with pytest.raises(AnswersError, match="no reaction component 'a_x.__class__'"):
        verify(model("pendulum"), [("rod", "a_x.__class__ = 0")])
    eq = parse_equation("pin-1.Fx * 2 − 3 · a_x = 0", labels=["pin-1.Fx"])
    assert eq.lhs[0] == "-" and eq.lhs[1][1][1] == "pin-1.Fx"


def test_fit_compares_up_to_scale_with_exact_zeros():
    t = Row.of({"a_y": 2.0, "O.Fy": -1.0, CONST: 19.62})
    s = Row({"a_y": -1.0, "O.Fy": 0.5, CONST: -9.81}, {})
    f = fit(s, t)
    assert f.k == pytest.approx(-0.5) and f.error == 0.0
    s = Row({"a_y": 2.0, CONST: 19.62}, {"a_y": 2.0, CONST: 19.62})  # O.Fy left out
    assert fit(s, t).errors["O.Fy"] >= 0.99
    assert fit(Row({}, {}), t) is None


def test_verify_needs_no_sympy_and_import_mbody_stays_light():
    import subprocess

    code = ("import sys, mbody; assert 'mbody.answers' not in sys.modules; "
            "v = mbody.verify('models/seed_example_2.yaml', "
            "'models/answers/seed_example_2.yaml'); "
            "print('sympy' in sys.modules, v.correct)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "4"]


def test_report_shows_the_answers_beside_the_expected_rows():
    from mbody.present.report import report_html

    m = model("pendulum")
    v = verify(m, [{"body": "rod", "eq": "I_G*alpha = -m*g*0.25"},
                   {"body": "rod", "eq": "m*a_x = O.Fx"}])
    page = report_html(m, answers=v)
    assert '<section id="answers">' in page and 'href="#answers"' in page
    assert "<code>I_G*alpha = -m*g*0.25</code>" in page
    assert "wrong_moment_point" in page
    assert "<code>0.167083 alpha = -0.433013 O.Fx - 0.25 O.Fy</code>" in page
    assert "Rows no correct equation gave" in page and "rod.y" in page
    assert 'id="answers"' not in report_html(m)
    assert not math.isnan(v.tol)


def _written(row: Row, fmt: str, k: float = 1.0, drop: str = "") -> str:
    """A row written as a student would: every term, numbers in format `fmt`, = 0."""
    parts = [f"({format(k * v, fmt)})" + ("" if key == CONST else f"*{key}")
             for key, v in row.coef.items() if v != 0.0 and key != drop]
    return " + ".join(parts or ["0"]) + " = 0"


def test_every_row_of_every_shipped_model_is_correct_and_none_with_a_term_left_out():
    from mbody.answers.rows import body_rows

    for path in sorted(MODELS.glob("*.yaml")):
        m = mbody.load(path)
        asm = mbody.assemble(m)
        answers, expect = [], []
        for b in m.body_names:
            for r in body_rows(asm, b).rows:
                if not r.row.unknowns:
                    continue
                for fmt, k in (("", 1.0), (".5g", 1.0), (".6g", -3.7)):
                    answers.append((b, _written(r.row, fmt, k)))
                    expect.append((True, r.label))
                for key in sorted(r.row.keys):
                    answers.append((b, _written(r.row, ".6g", 2.0, drop=key)))
                    expect.append((False, f"{r.label} without {key}"))
        if not answers:
            continue
        v = verify(m, answers, asm=asm)
        for c, (ok, what) in zip(v.checks, expect, strict=True):
            if ok:
                assert c.correct and c.row == what, (path.name, what, c.explanation)
            elif c.correct:
                # only a different, true equation may pass: about a fixed pivot, a row
                # that says alpha_2 = 0 is the same as I_P alpha_2 = 0 (the heavy top);
                # or an acceleration the joints hold at 0 left out (bricard's rod1.x
                # without a_x)
                # or an acceleration the joints hold at 0 left out (bricard's rod1.x
                # without a_x); or moments about a joint's point with the kinematics put
                # in, which then hold at the solved state
                assert c.details.get("form") == "fixed_pivot" or _held_at_zero(
                    c, what.rpartition(" without ")[2]) or (
                    c.details.get("form") == "transport" and "kinematics" in c.details
                    and _holds(asm, c)), (path.name, what, c.eq)


def _held_at_zero(c, term: str) -> bool:
    """Whether `c` is correct because the joints hold acceleration `term` at 0 at this
    state (its relation reads ``term = 0``), so that its coefficient is any number."""
    return f"{term} = 0" in c.details.get("kinematics", [])


_COORDINATE = {"a_x": "x", "a_y": "y", "a_z": "z", "alpha": "theta", "alpha_1": "w1",
               "alpha_2": "w2", "alpha_3": "w3"}


def _holds(asm, c) -> bool:
    """Whether the equation of check `c` holds at the assembly's solution (accelerations
    and reactions from `Assembly.solve`, not from the checker): the residual small
    against its terms' magnitudes."""
    from mbody.answers.linear import linear_row
    from mbody.answers.vocabulary import vocabulary

    sol = asm.solve()
    row = linear_row(parse_equation(c.eq, asm.model.reactions),
                     vocabulary(asm.model, asm.state, c.body))
    terms = [v * (1.0 if k == CONST else sol.reactions[k] if "." in k else
                  sol[f"{c.body}.{_COORDINATE[k]}"]) for k, v in row.coef.items()]
    return abs(sum(terms)) <= 1e-9 * max(1.0, sum(map(abs, terms)))


def test_particles_known_reactions_and_loads_that_vary_in_time():
    # a particle: translation rows only; its link tension O.T
    assert diagnosis("point_pendulum", "bob", "m*a_y = 0.866025*O.T - m*g") == "correct"
    assert check("point_pendulum", "bob", "m*a_y = 0.866025*O.T").details["loads"] == \
        ["gravity"]
    with pytest.raises(AnswersError, match="particle"):
        verify(model("point_pendulum"), [("bob", "I_G*alpha = 0")])
    # a reaction the file gives (fork.Mt = 16 N m) by its label or by its value
    assert diagnosis("rotor_gyroscopic_bearings", "flywheel",
                     "0.204167*alpha_1 + 7.83333 = fork.Mt") == "correct"
    assert diagnosis("rotor_gyroscopic_bearings", "flywheel",
                     "0.204167*alpha_1 + 7.83333 = 16") == "correct"
    assert diagnosis("rotor_gyroscopic_bearings", "flywheel",
                     "0.204167*alpha_1 = 16") == "missing_gyroscopic_term"
    # a thrust 300 exp(-t/4) N at t = 0, by its name or its law
    assert diagnosis("satellite_thruster", "satellite", "m*a_z = F_main_engine_3") == \
        "correct"
    assert diagnosis("satellite_thruster", "satellite", "m*a_z = 300*exp(-0/4)") == \
        "correct"
    with pytest.raises(AnswersError, match="unknown function 'ln'"):
        verify(model("satellite_thruster"), [("satellite", "m*a_z = ln(2)")])


# == found in review: what a student tries next =========================================
def test_time_t_is_a_name_so_a_load_copied_from_symbolic_reads():
    # `mbody assemble --symbolic` writes M_load = -60*exp(-90*t): copy it as it stands
    eq = ("I_G*alpha = -60*exp(-90*t) + 0.0176777*O.Fx - 0.0176777*O.Fy "
          "+ 0.0176777*A.Fx - 0.0176777*A.Fy")
    assert diagnosis("slider_crank", "crank", eq) == "correct"
    assert diagnosis("slider_crank", "piston", "m*a_x = -4000*exp(-200*t) + B.Fx") == \
        "correct"


def test_the_closest_row_is_about_the_acceleration_written():
    # a moment equation with wrong lever arms is compared with the moment row, not with
    # the Newton row that happens to share two reactions with it
    c = check("slider_crank", "crank", "I_G*alpha = -60 - 0.025*O.Fy + 0.025*A.Fy")
    assert c.diagnosis == "not_an_equation_of_this_body" and c.row == "crank.theta"
    assert "alpha does not belong" not in c.explanation


def test_a_moment_of_the_wrong_sign_on_the_child_is_not_blamed_on_the_third_law():
    c = check("pendulum", "rod", "I_G*alpha = 0.433013*O.Fx + 0.25*O.Fy")
    assert c.diagnosis == "lever_arm_sign" and c.details["reactions"] == ["O.Fx", "O.Fy"]
    assert "r × F" in c.explanation and "so it feels +O.Fx" not in c.explanation
    assert "third law" not in c.explanation and "r × F" in c.meaning
    # on the parent, the third law is the reason, and r × (−R) is said
    c = check("slider_crank", "crank", "I_G*alpha = -60 + 0.0176777*O.Fx - 0.0176777*O.Fy "
              "- 0.0176777*A.Fx + 0.0176777*A.Fy")
    assert c.diagnosis == "reaction_sign" and "parent of joint A" in c.explanation
    assert "r × (−R)" in c.explanation


@pytest.mark.parametrize("name, body, eq, what, row", [
    ("pendulum", "rod", "m*a_y = O.Fy + m*g", "gravity", "rod.y"),
    ("slider_crank", "piston", "m*a_x = B.Fx + 4000", "gas", "piston.x"),
    ("slider_crank", "piston", "m*a_x = B.Fx - F_gas_x", "gas", "piston.x"),
    ("seed_example_2", "body", "I_1*alpha_1 = (I_3 - I_2)*w_2*w_3", "omega x (I omega)",
     "body.w1"),
    ("seed_example_2", "body", "alpha_1 = 3", "omega x (I omega)", "body.w1"),
    ("heavy_top", "top", "I_1*alpha_1 = (I_3 - I_2)*w_2*w_3 + 0.0469846*pivot.Fy "
     "+ 0.017101*pivot.Fz", "omega x (I omega)", "top.w1"),
])
def test_a_load_or_the_gyroscopic_term_of_the_wrong_sign_is_named(name, body, eq, what, row):
    c = check(name, body, eq)
    # a load of the wrong sign is applied_load_sign (it was named within
    # not_an_equation_of_this_body, so the class summary lost it); the gyroscopic term's
    # sign is a diagnosis of its own
    assert c.diagnosis == ("gyroscopic_term_sign" if what == "omega x (I omega)" else
                           "applied_load_sign") and c.row == row
    assert c.details["wrong_sign"] == what and "of the wrong sign" in c.explanation


def test_textbook_spellings_read_and_unknown_names_get_a_useful_hint(tmp_path):
    # subscript digits pasted from the course (I₁ω̇₁ = (I₂ − I₃)ω₂ω₃), and ω̇ as omega1_dot
    assert diagnosis("seed_example_2", "body", "I₁*α₁ = (I₂ − I₃)*ω₂*ω₃") == "correct"
    assert diagnosis("seed_example_2", "body",
                     "I_1*omega1_dot = (I_2 - I_3)*omega2*omega3") == "correct"
    assert diagnosis("seed_example_1", "plate", "I_G*omega_dot = 20") == "correct"

    def error(name, body, eq):
        return errors(name, f"equations:\n  - {{body: {body}, eq: '{eq}'}}\n", tmp_path)[0]

    # a letter axis on a spatial body's angular quantity: its axes are numbered (w_x
    # was "did you mean 'w_3'?")
    for eq in ("I_x*alpha_1 = 0", "I_xx*alpha_1 = 0", "w_x*I_1*alpha_1 = 0",
               "alpha_x = 0"):
        out = error("seed_example_2", "body", eq)
        assert "numbered" in out and "did you mean" not in out, out
    # a product without '*' ("mg" was "did you mean 'm'?")
    assert "write m*g" in error("pendulum", "rod", "m*a_y = O.Fy - mg")
    # the inertia about a pin has no name: I_G + m d² ("I_O" was "did you mean 'I_G'?")
    assert "I_G + m*d^2" in error("pendulum", "rod", "I_O*alpha = -m*g*0.25")
    # degrees
    assert "radians" in error("pendulum", "rod", "I_G*alpha = -0.5*O.Fy*sin(30°)")
    # suggestions are canonical names, never an alias ("a" was "did you mean 'az'?")
    out = error("seed_example_2", "body", "a = 0")
    assert "did you mean 'a_" in out and "'az'" not in out


def test_a_reaction_is_said_replaced_by_a_number_only_where_a_number_was_written():
    # no number at all: the static guess, said as such (not "replaced by the number")
    for name, body, eq in (("pendulum", "rod", "m*a_y = 0"),
                           ("heavy_top", "top", "I_1*alpha_1 = 0")):
        c = check(name, body, eq)
        assert c.diagnosis == "reaction_treated_as_known"
        assert "static guess" in c.explanation and "replaced by" not in c.explanation
    # a number, even one written with names that cancel, is a number
    c = check("heavy_top", "top", "m*a_z = -m*g + m*g")
    assert c.diagnosis == "reaction_treated_as_known"
    assert c.details["value_used"] == pytest.approx(9.81)
    assert "replaced by the number 9.81 N" in c.explanation
    c = check("pendulum", "rod", "m*a_y = 19.62 - m*g")
    assert "replaced by the number 19.62 N" in c.explanation


def test_no_row_of_a_shipped_model_with_one_term_reversed_or_1_percent_off_is_correct():
    """Every term of every row of every shipped model, reversed in sign or 1 % off
    (a row of one term excepted: that is only a scale), is never `correct`, except as
    the same law about a fixed pivot."""
    from mbody.answers.rows import body_rows

    for path in sorted(MODELS.glob("*.yaml")):
        m = mbody.load(path)
        asm = mbody.assemble(m)
        answers, what = [], []
        for b in m.body_names:
            for r in body_rows(asm, b).rows:
                if len(r.row.keys) < 2:
                    continue
                for key in sorted(r.row.keys):
                    for factor in (-1.0, 1.01):
                        row = r.row.with_term(key, r.row.get(key) * factor)
                        answers.append((b, _written(row, ".6g", 1.0)))
                        what.append(f"{r.label}: {key} times {factor}")
        if not answers:
            continue
        v = verify(m, answers, asm=asm)
        for c, w in zip(v.checks, what, strict=True):
            assert not c.correct or c.details.get("form") == "fixed_pivot", (path.name, w)


DP_SPRING = (Path(__file__).parent / "dp_spring.yaml").read_text()


@pytest.fixture(scope="module")
def dp_spring(tmp_path_factory) -> mbody.Model:
    path = tmp_path_factory.mktemp("dp") / "dp_spring.yaml"
    path.write_text(DP_SPRING)
    return mbody.load(path)


def test_reactions_are_treated_as_known_only_when_the_number_is_their_share(dp_spring):
    def one(eq: str, body: str = "upper"):
        return verify(dp_spring, [{"body": body, "eq": eq}]).checks[0]

    # upper's Euler row: 0.0602667 alpha = 1.5 - 0.259808 O.Fx - 0.15 O.Fy
    # - 0.259808 A.Fx - 0.15 A.Fy; solved, the four reactions add -2.65334 N m
    for eq in ("I_G*alpha = 777", "I_G*alpha = 1.5 + 2.943", "I_G*alpha = 1.5 + 2.6533"):
        c = one(eq)
        assert c.diagnosis == "not_an_equation_of_this_body", (eq, c.explanation)
        assert "Closest is" in c.explanation and "replaced by" not in c.explanation
    # their solved share, rounded as a student would, and the static guess stay
    for eq in ("I_G*alpha = 1.5 - 2.6533", "I_G*alpha = -1.1533", "I_G*alpha = 0"):
        c = one(eq)
        assert c.diagnosis == "reaction_treated_as_known", (eq, c.explanation)
    # one reaction: a number that is neither its solved value nor its static guess
    # (pendulum: O.Fy solved 15.9435 N, static m g = 19.62 N) is not that mistake
    c = check("pendulum", "rod", "2*a_y = 7 - 19.62")
    assert c.diagnosis == "not_an_equation_of_this_body", c.explanation
    assert "replaced by" not in c.explanation


def test_the_names_offered_for_a_body_are_its_own_reactions(tmp_path):
    def error(body, eq):
        return errors("double_pendulum", f"equations:\n  - {{body: {body}, eq: '{eq}'}}\n",
                      tmp_path)[0]

    # lower hangs from A only: O.Fx, O.Fy are not on its free body (they were listed)
    out = error("lower", "m*a_y = A.Fy - m*gg")
    names = out.split("(the names: ")[1]
    assert "A.Fx, A.Fy" in names and "O.F" not in names, out
    out = error("upper", "m*a_y = O.Fy - m*gg")
    assert "O.Fx, O.Fy, A.Fx, A.Fy" in out.split("(the names: ")[1], out
    # a misspelt component of another body's joint: said so, never suggested
    out = error("lower", "m*a_x = A.Fx + O.Fz")
    assert "joint O does not act on lower" in out and "did you mean" not in out, out
    # another body's reaction, spelt right, is a mistake of the free body, not of the
    # file: a diagnosis that names it as not acting on this body
    c = check("double_pendulum", "lower", "m*a_x = A.Fx + O.Fx")
    assert c.diagnosis == "not_an_equation_of_this_body"
    assert c.details["foreign"] == ["O.Fx"]
    assert "O.Fx is a reaction of a joint that does not touch lower" in c.explanation


def test_a_tolerance_that_is_not_a_number_is_refused_by_name():
    """Before: "'>' not supported between instances of 'str' and 'float'"."""
    eqs = [{"body": "rod", "eq": "2*a_x = O.Fx"}]
    with pytest.raises(TypeError) as err:
        verify(MODELS / "pendulum.yaml", eqs, tol="1e-3")
    msg = str(err.value)
    assert msg.startswith("tol must be a relative tolerance") and "got str '1e-3'" in msg
    assert isinstance(err.value, mbody.MbodyError)
    with pytest.raises(TypeError, match="^tol must be "):
        verify(MODELS / "pendulum.yaml", eqs, tol=None)
    assert verify(MODELS / "pendulum.yaml", eqs, tol=1e-3).tol == 1e-3


def test_an_assembly_of_another_model_is_refused():
    """`asm` is where the true rows come from: another model's (before: "no body named
    'rod'"), or this model's with another mass (before: checked against it in silence),
    is refused; the same model read again is accepted and gives the same checks."""
    model = mbody.load(MODELS / "pendulum.yaml")
    eqs = [{"body": "rod", "eq": "2*a_x = O.Fx"}]
    other = mbody.assemble(mbody.load(MODELS / "double_pendulum.yaml"))
    with pytest.raises(mbody.MbodyError) as err:
        verify(model, eqs, asm=other)
    msg = str(err.value)
    assert msg.startswith("asm: an assembly of model 'double-pendulum'")
    assert f"not of {model.name!r}" in msg and "leave asm out" in msg
    heavier = mbody.assemble(model.with_values({"bodies.rod.mass": 3.0}))
    with pytest.raises(mbody.MbodyError, match=r"with other values \(masses"):
        verify(model, eqs, asm=heavier)
    with pytest.raises(TypeError, match=r"^asm must be an Assembly of the model"):
        verify(model, eqs, asm=model)
    again = verify(model, eqs, asm=mbody.assemble(mbody.load(MODELS / "pendulum.yaml")))
    assert [c.diagnosis for c in again.checks] == [c.diagnosis for c in verify(model, eqs).checks]

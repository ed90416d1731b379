"""The diagnosis labels a wrong equation gets (review R4, F3 and F16): a load of the wrong
sign, a reaction's moment of the wrong sign on the child, a number rounded too coarsely.
The label is what the class summary keeps, so each mistake that the explanation names
has a label of its own, and its headline says the same as the explanation.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import mbody
from mbody.answers import DIAGNOSES, verify
from mbody.answers.verify import MEANINGS

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"


def check(name: str, body: str, eq: str, **kw):
    return verify(MODELS / f"{name}.yaml", [{"body": body, "eq": eq}], **kw).checks[0]


def test_the_new_labels_are_listed_with_their_meaning_in_the_order_tried():
    order = list(DIAGNOSES)
    assert order.index("missing_applied_load") < order.index("applied_load_sign") \
        < order.index("not_an_equation_of_this_body")
    assert order.index("reaction_sign") < order.index("lever_arm_sign")
    assert order[-2:] == ["rounded_too_coarsely", "not_an_equation_of_this_body"]
    for label in ("applied_load_sign", "lever_arm_sign", "rounded_too_coarsely"):
        assert MEANINGS[label] == DIAGNOSES[label]


# == F3: a load of the wrong sign ==========================================================

@pytest.mark.parametrize("name, body, eq, load, row", [
    ("pendulum", "rod", "m*a_y = O.Fy + m*g", "gravity", "rod.y"),
    ("seed_example_1", "plate", "m*a_x = -50", "push", "plate.x"),
    ("seed_example_1", "plate", "I_G*alpha = -50*0.4", "push", "plate.theta"),
    ("slider_crank", "piston", "m*a_x = B.Fx + 4000", "gas", "piston.x"),
])
def test_a_load_of_the_wrong_sign_is_applied_load_sign(name, body, eq, load, row):
    c = check(name, body, eq)
    assert (c.diagnosis, c.row) == ("applied_load_sign", row), c.explanation
    assert c.details["wrong_sign"] == load and c.details["loads"] == [load]
    assert "of the wrong sign" in c.explanation and c.meaning == MEANINGS["applied_load_sign"]


def test_a_load_left_out_or_right_is_not_a_sign():
    assert check("pendulum", "rod", "m*a_y = O.Fy").diagnosis == "missing_applied_load"
    assert check("pendulum", "rod", "m*a_y = O.Fy - m*g").diagnosis == "correct"
    # twice the load is neither its sign nor the row
    assert check("pendulum", "rod", "m*a_y = O.Fy - 2*m*g").diagnosis == \
        "not_an_equation_of_this_body"


def test_the_class_summary_keeps_the_load_sign(tmp_path):
    from mbody.answers.summary import grade

    f = tmp_path / "ana.yaml"
    f.write_text('equations:\n  - {body: rod, eq: "m*a_x = O.Fx"}\n'
                 '  - {body: rod, eq: "m*a_y = O.Fy + m*g"}\n')
    s = grade(mbody.load(MODELS / "pendulum.yaml"), [f])
    assert [(m.diagnosis, m.row) for m in s.mistakes] == [("applied_load_sign", "rod.y")]
    assert MEANINGS["applied_load_sign"] in s.csv()


# == F16: the moment of a reaction of the wrong sign, and rounding ==========================

def test_a_moment_arm_of_the_wrong_sign_on_the_child_is_lever_arm_sign():
    # the review's equation: both moment arms reversed on the rod, the child of O
    c = check("pendulum", "rod", "I_G*alpha = 0.433*O.Fx + 0.25*O.Fy")
    assert c.diagnosis == "lever_arm_sign" and c.details["reactions"] == ["O.Fx", "O.Fy"]
    assert "third law" not in c.meaning + c.explanation
    assert "r × F" in c.meaning and "r × F" in c.explanation
    # the same reversal in a Newton row is the third law's
    c = check("pendulum", "rod", "m*a_x = -O.Fx")
    assert c.diagnosis == "reaction_sign" and "third law" in c.meaning
    # and on the parent of a joint, a moment of the wrong sign is the third law's: the
    # parent feels −R, whose moment is r × (−R)
    c = check("slider_crank", "crank", "I_G*alpha = -60 + 0.0176777*O.Fx - 0.0176777*O.Fy "
              "- 0.0176777*A.Fx + 0.0176777*A.Fy")
    assert c.diagnosis == "reaction_sign" and c.details["reactions"] == ["A.Fx", "A.Fy"]


@pytest.mark.parametrize("eq, key, have, want, percent", [
    # the review's: 0.43 for 0.433013 (0.7 %)
    ("I_G*alpha = -0.43*O.Fx - 0.25*O.Fy", "O.Fx", "0.43", "0.433013", "0.7 %"),
    ("0.17*alpha = -0.433013*O.Fx - 0.25*O.Fy", "alpha", "0.17", "0.167083", "1.7 %"),
    ("2*a_y = O.Fy - 19.8", "the constant", "19.8", "19.62", "0.92 %"),
])
def test_a_number_rounded_too_coarsely_is_said_with_by_how_much(eq, key, have, want,
                                                                 percent):
    c = check("pendulum", "rod", eq)
    assert c.diagnosis == "rounded_too_coarsely", c.explanation
    text = " ".join(c.explanation.split())
    assert f"{key} has {have} where {want} is expected ({percent} off)" in text
    assert "must match to 0.1 %" in text
    # the same numbers within the tolerance are right
    assert check("pendulum", "rod", eq, tol=0.05).diagnosis == "correct"


@pytest.mark.parametrize("eq", [
    "I_G*alpha = -0.4*O.Fx - 0.25*O.Fy",      # 8 % off: not rounding
    "I_G*alpha = -0.43*O.Fx",                  # a term left out: not rounding
    "I_G*alpha = -0.43*O.Fx - 0.25*O.Fy + 1",  # a term too many
    "I_G*alpha = 0.43*O.Fx - 0.25*O.Fy",       # a sign
])
def test_rounding_is_said_only_of_a_row_with_every_term_in_place(eq):
    c = check("pendulum", "rod", eq)
    assert c.diagnosis not in ("rounded_too_coarsely", "correct"), (eq, c.explanation)


def test_numbers_to_four_figures_stay_correct():
    assert check("pendulum", "rod", "I_G*alpha = -0.4330*O.Fx - 0.2500*O.Fy").correct
    assert check("pendulum", "rod", "m*a_y = O.Fy - m*9.81").correct


# == R5-10: the moving pivot's I_P has the label's meaning ================================

def test_moments_about_a_moving_pin_with_its_inertia_say_so_in_the_meaning():
    # the lower rod of the double pendulum about its pin A, which moves with the upper
    # rod: I_A alpha = M_A does not hold there (no transport term r x m a_G)
    c = check("double_pendulum", "lower", "(I_G + m*0.25^2)*alpha = -m*g*0.176777")
    assert (c.diagnosis, c.details["form"]) == ("wrong_moment_point", "moving_pivot")
    assert "A moves" in c.explanation and "I_P" in c.explanation
    # the headline the class summary keeps says the same as the explanation
    assert c.meaning == MEANINGS["wrong_moment_point"]
    assert "I_P" in c.meaning and "moves" in c.meaning and "transport term" in c.meaning
    # and about it with I_G, the other case the meaning covers
    c = check("double_pendulum", "lower", "I_G*alpha = -m*g*0.176777")
    assert c.diagnosis == "wrong_moment_point" and "I_G α alone" in c.explanation
    assert "with I_G" in c.meaning


def test_the_solved_value_label_is_listed_before_the_last_two():
    order = list(DIAGNOSES)
    assert order.index("reaction_treated_as_known") < \
        order.index("solved_value_not_an_equation") < order.index("rounded_too_coarsely")
    assert MEANINGS["solved_value_not_an_equation"] == \
        DIAGNOSES["solved_value_not_an_equation"]

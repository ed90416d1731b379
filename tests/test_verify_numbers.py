"""Numbers in a student's equations that a double cannot carry, and rows written at any
scale: an overflow, a nan or a product lost below the smallest double is refused at its
operator (file, line, column; exit 2), never a traceback (exit 70) or a verdict drawn
from inf or nan; a row written at 1e-170 or 1e170 is judged as the same row at 1."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import mbody
from mbody.answers.diagnose import diagnose
from mbody.answers.linear import linear_row
from mbody.answers.load import read_answers
from mbody.answers.parse import parse_equation
from mbody.answers.rows import body_rows
from mbody.answers.verify import verify
from mbody.answers.vocabulary import vocabulary
from mbody.cli.app import main

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
SEED_1 = MODELS / "seed_example_1.yaml"  # m = 10, I_G = 0.5, 50 N along x: a_x = 5
EQ_COLUMN = 24  # where the equation starts in `answers`' line
OVERFLOW = "the numbers in {} go beyond ±1.8e308, the largest double (divide both sides " \
           "by a power of ten)"


def answers(tmp_path: Path, *eqs: str) -> Path:
    path = tmp_path / "a.yaml"
    path.write_text("equations:\n" + "".join(f'  - {{body: plate, eq: "{e}"}}\n' for e in eqs),
                    encoding="utf-8")
    return path


def run(capsys, tmp_path: Path, eq: str, *options: str) -> tuple[int, str, str]:
    code = main(["verify", str(SEED_1), str(answers(tmp_path, eq)), *options])
    out = capsys.readouterr()
    return code, out.out, out.err


def nth(text: str, token: str, n: int) -> int:
    """0-based position of the n-th (1-based) `token` in `text`."""
    at = -1
    for _ in range(n):
        at = text.index(token, at + 1)
    return at


@pytest.mark.parametrize("eq, token, n, message", [
    # from the fuzzer: ValueError, OverflowError, nan taken for a missing load
    ("sin(1e100*1e100*1e100*1e100)*a_x = 1", "*", 3, OVERFLOW.format("this product")),
    ("(1e100*1e100+2-1e100*1e100)^2*a_x = 1", "^", 1, OVERFLOW.format("this power")),
    ("m*a_x = 50 + 0*(1e100*1e100*1e100*1e100)", "*", 5, OVERFLOW.format("this product")),
    ("m*a_x = 50 + 0*(1e100^4)", "^", 1, "1e+100^4 is beyond ±1.8e308, the largest double"),
    ("a_x = 1e100*1e100*1e100*1e100", "*", 3, OVERFLOW.format("this product")),
    ("a_x = 1e100*1e100*1e100/1e-100", "/", 1, OVERFLOW.format("this quotient")),
    # each side fits (3e307, with a rounding scale of 1.2e308), their difference does not
    ("a_x + 1e100*1e100*1e100*3e7 = -1e100*1e100*1e100*3e7", "=", 1,
     OVERFLOW.format("the two sides")),
    ("a_x = exp(1000)", "exp", 1, "exp(1000) is too large"),
    ("a_x = 1e-200*1e-200", "*", 1, "this product is too small to compute: below 2.2e-308, "
     "the smallest double (nonzero numbers would become 0) (multiply both sides by a power "
     "of ten)"),
    ("1e-200*1e-200*a_x = 1", "*", 1, "this product is too small to compute"),
    # one term lost is enough, whatever the others
    ("(2*a_x + 1e-200)*1e-200 = 0", "*", 2, "this product is too small to compute"),
    ("(0 + a_x*1e-200)/1e100/1e100 = 1", "/", 2, "this quotient is too small to compute"),
    ("a_x = 0.5^2000", "^", 1, "this power is too small to compute"),
    ("a_x = 0^(-1)", "^", 1, "0^-1 cannot be computed (a negative number to a fractional "
     "power, or 0 to a negative one)"),
    ("a_x = (-8)^(1/3)", "^", 1, "(-8)^0.333333 cannot be computed"),
])
def test_numbers_a_double_cannot_carry_are_refused_at_their_operator(capsys, tmp_path, eq,
                                                                     token, n, message):
    code, out, err = run(capsys, tmp_path, eq)
    assert code == 2, out
    assert f"a.yaml:2:{EQ_COLUMN + nth(eq, token, n)}: equations[0].eq: {message}" in err, err
    assert "internal error" not in err
    code, out, err = run(capsys, tmp_path, eq, "--json")
    assert code == 2 and out == "" and message in err


def test_every_equation_refused_for_its_numbers_is_reported_at_once(capsys, tmp_path):
    path = answers(tmp_path, "a_x = 1e100*1e100*1e100*1e100", "m*a_x = 50",
                   "a_y = 1e-200*1e-200")
    assert main(["verify", str(SEED_1), str(path)]) == 2
    err = capsys.readouterr().err
    assert "2 problems in the answers" in err
    assert "a.yaml:2:" in err and "a.yaml:4:" in err and "a.yaml:3:" not in err


def test_a_tiny_but_valid_row_is_compared_at_its_own_scale(capsys, tmp_path):
    # 1e-170 a_x = 1e-170 says a_x = 1 (the true row: a_x = 5); the squares of 1e-170
    # vanished in the fit (ZeroDivisionError)
    code, out, err = run(capsys, tmp_path, "1e-170*a_x = 1e-170")
    assert code == 1, err
    assert "not_an_equation_of_this_body" in out
    assert "the constant has -1e-170 where -5e-170 is expected" in " ".join(out.split())
    code, out, err = run(capsys, tmp_path, "1e-170*a_x = 1e-170", "--json")
    doc = json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in --json"))
    differs = doc["equations"][0]["details"]["differs"]
    assert differs["1"]["have"] == -1e-170
    assert differs["1"]["expected"] == pytest.approx(-5e-170, rel=1e-12)
    for eq in ("1e-170*a_x = 5e-170", "1e-170*m*a_x = 1e-170*50", "a_x*1e-300 = 5e-300",
               "1e100*1e100*1e100*a_x = 5*1e100*1e100*1e100", "a_x/1e100/1e100/1e100 = 5e-300"):
        code, out, err = run(capsys, tmp_path, eq)
        assert code == 0 and "    correct\n" in out, (eq, out, err)
    code, out, err = run(capsys, tmp_path, "1e-170*a_y = 1e-170")
    assert code == 1
    assert "the constant does not belong here (you have -1e-170)" in " ".join(out.split())


def test_no_unknowns_at_a_tiny_scale_says_by_how_much():
    v = verify(SEED_1, [("plate", "1e-170*m = 2e-170")])
    assert "a number equal to another (they differ by 8e-170)" in v.checks[0].explanation


@pytest.mark.parametrize("scale", [2.0 ** -600, 2.0 ** -60, 2.0 ** 60, 2.0 ** 600])
def test_every_shipped_answer_has_the_same_diagnosis_at_any_scale(scale):
    """Each equation of every shipped answers file, its row multiplied by a power of two
    (exactly, 2^-600 is about 2.4e-181), gets the same diagnosis, row and details.

    But two, by design, equations of one unknown that fix no scale of their own: a Newton
    row with a reaction written as a number (pendulum: m*a_y = 19.62 - m*g) is called
    `reaction_treated_as_known` only when written at the row's scale; and the moment
    about a fixed pivot (I_P alpha = M_P) is `correct` only as written or divided by m
    (any other multiple says no more than alpha's value: review R6-1)."""
    for path in sorted((MODELS / "answers").glob("*.yaml")):
        model = mbody.load(MODELS / path.name)
        asm = mbody.assemble(model)
        sheet = read_answers(path)
        for a in sheet.equations:
            vocab = vocabulary(model, asm.state, a.body)
            try:
                row = linear_row(parse_equation(a.eq, model.reactions), vocab)
            except Exception:  # noqa: BLE001 -- not linear: no row to scale
                continue
            rows = body_rows(asm, a.body)
            plain, scaled = diagnose(row, rows, 1e-3), diagnose(row.scaled(scale), rows, 1e-3)
            if plain.diagnosis == "reaction_treated_as_known" and len(row.unknowns) == 1:
                assert scaled.diagnosis == "not_an_equation_of_this_body"
                continue
            if plain.details.get("form") == "fixed_pivot" and len(row.unknowns) == 1:
                assert plain.diagnosis == "correct" != scaled.diagnosis, (path.name, a.eq)
                continue
            assert (scaled.diagnosis, scaled.row, scaled.expected) == \
                (plain.diagnosis, plain.row, plain.expected), (path.name, a.eq)
            if "scale" in plain.details:
                assert scaled.details["scale"] == pytest.approx(plain.details["scale"] * scale,
                                                                rel=1e-12)

"""Long and deeply nested expressions (loads of time, a student's equations): a flat sum of
any length is read and evaluated in a loop; nesting (parentheses, functions, signs,
powers, which nest to the right) is bounded and refused where it begins, with the
file, line and column. Nothing ends in RecursionError (exit 70)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mbody.answers.verify import verify
from mbody.cli.app import main
from mbody.model.expressions import MAX_DEPTH, ExpressionError, compile_expression
from mbody.model.model import load

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
STACK = 120
"""Frames left for the call in `with_little_stack`: a flat sum needs a handful."""


def with_little_stack(fn: Callable[[], Any]) -> Any:
    """fn() called with only about `STACK` frames left before Python's recursion limit."""
    def descend(n: int) -> Any:
        return fn() if n <= 0 else descend(n - 1)
    frame, used = sys._getframe(), 0
    while frame is not None:
        used, frame = used + 1, frame.f_back
    return descend(sys.getrecursionlimit() - used - STACK)


@pytest.mark.parametrize("op, n, at2", [("+", 499, 998.0), ("-", 499, -994.0),
                                        ("*", 30, 2.0 ** 30), ("/", 30, 2.0 ** -28)])
def test_a_long_chain_of_one_operator_is_evaluated_in_a_loop(op, n, at2):
    text = op.join(["t"] * n)
    assert len(text) <= 1000
    e = with_little_stack(lambda: compile_expression(text))
    assert not e.constant
    assert with_little_stack(lambda: e(2.0)) == at2          # numpy, scalar
    assert with_little_stack(lambda: e.at(2.0)) == at2       # the closures of a simulation
    np.testing.assert_array_equal(with_little_stack(lambda: e(np.array([2.0, 2.0]))),
                                  [at2, at2])
    codes, numbers = e.program                               # the compiled path's postfix
    assert len(codes) == 2 * n - 1 and len(numbers) == len(codes)


def test_a_long_constant_sum_folds_to_its_value():
    e = with_little_stack(lambda: compile_expression("+".join(["1"] * 499) + "+t"))
    assert e.tree == ("+", ("num", 499.0), ("t",))


def test_a_mixed_chain_keeps_precedence_and_left_association():
    text = "t*2 + 3 - t/4*8 + 1 - 2*t^2 - 6/3/2"
    e = compile_expression(text)
    t = 1.5
    assert e(t) == pytest.approx(t * 2 + 3 - t / 4 * 8 + 1 - 2 * t**2 - 6 / 3 / 2, abs=1e-14)
    assert e.at(t) == e(t)


@pytest.mark.parametrize("text", ["^".join(["2"] * (MAX_DEPTH + 2)),
                                  "^".join(["t"] * 400),
                                  "-" * (MAX_DEPTH + 2) + "t",
                                  "sin(" * (MAX_DEPTH + 1) + "t" + ")" * (MAX_DEPTH + 1)])
def test_nesting_deeper_than_the_bound_is_refused_where_it_begins(text):
    with pytest.raises(ExpressionError, match=f"nesting deeper than {MAX_DEPTH} levels"):
        compile_expression(text)


def test_a_power_tower_within_the_bound_is_read():
    assert compile_expression("2^2^2^2").value == 65536.0  # right-associative
    e = compile_expression("^".join(["t"] * MAX_DEPTH))
    assert e(1.0) == 1.0


def test_a_power_tower_in_a_load_is_refused_at_its_line(capsys, tmp_path):
    text = (MODELS / "planar_time_varying_force.yaml").read_text(encoding="utf-8")
    tower = "^".join(["t"] * 400)
    path = tmp_path / "m.yaml"
    path.write_text(text.replace('"50*sin(2*t)"', f'"{tower}"'), encoding="utf-8")
    line = next(i for i, row in enumerate(path.read_text().split("\n"), 1) if tower in row)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"m.yaml:{line}:52: loads[0].force[0]: invalid expression: nesting deeper than " \
           f"{MAX_DEPTH} levels at character {2 * MAX_DEPTH + 2}" in err
    assert "RecursionError" not in err


def test_a_long_sum_in_a_load_is_simulated(tmp_path):
    text = (MODELS / "planar_time_varying_force.yaml").read_text(encoding="utf-8")
    path = tmp_path / "m.yaml"
    path.write_text(text.replace('"50*sin(2*t)"', '"' + "+".join(["t"] * 490) + '"'),
                    encoding="utf-8")
    model = load(path)
    assert model.loads[0].expressions[0](2.0) == 980.0


def answers(tmp_path: Path, eq: str) -> Path:
    path = tmp_path / "a.yaml"
    path.write_text(f'equations:\n  - {{body: plate, eq: "{eq}"}}\n', encoding="utf-8")
    return path


def test_a_sum_of_997_ones_in_an_answer_is_checked(tmp_path, capsys):
    eq = "a_x = " + "+".join(["1"] * 997)
    assert len(eq) < 2000
    v = with_little_stack(lambda: verify(MODELS / "seed_example_1.yaml",
                                         answers(tmp_path, eq)))
    c = v.checks[0]
    assert c.diagnosis == "not_an_equation_of_this_body"
    assert "the constant has -997 where -5 is expected" in c.explanation
    code = main(["verify", str(MODELS / "seed_example_1.yaml"), str(answers(tmp_path, eq))])
    assert code == 1 and "RecursionError" not in capsys.readouterr().err


def test_a_sum_of_490_unknowns_in_an_answer_is_checked(tmp_path):
    eq = "+".join(["a_x"] * 490) + " = 2450"
    assert len(eq) < 2000
    v = with_little_stack(lambda: verify(MODELS / "seed_example_1.yaml",
                                         answers(tmp_path, eq)))
    assert v.checks[0].diagnosis == "correct"  # 490 a_x = 2450: a_x = 5


def test_a_power_tower_in_an_answer_is_refused_at_its_column(tmp_path, capsys):
    eq = "a_x = " + "^".join(["2"] * 300)
    code = main(["verify", str(MODELS / "seed_example_1.yaml"), str(answers(tmp_path, eq))])
    err = capsys.readouterr().err
    assert code == 2
    # the '^' that opens level MAX_DEPTH + 1 is character 6 + 2 (MAX_DEPTH + 1) of the
    # equation, whose first character is in column 24
    assert (f"a.yaml:2:{23 + 6 + 2 * (MAX_DEPTH + 1)}: equations[0].eq: nesting deeper than "
            f"{MAX_DEPTH} levels") in err

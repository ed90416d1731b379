"""The safe expression parser: values, precedence, vectorisation, errors with positions."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbody
from mbody.model.expressions import ExpressionError, ExpressionTable, compile_expression

T = np.linspace(-2.0, 3.0, 11)


@pytest.mark.parametrize("text, f", [
    ("50*sin(2*t)", lambda t: 50 * np.sin(2 * t)),
    ("1 + 2*3", lambda t: 7.0),
    ("(1 + 2)*3", lambda t: 9.0),
    ("2^3^2", lambda t: 512.0),              # right-associative
    ("2**3", lambda t: 8.0),
    ("-2^2", lambda t: -4.0),                # power binds tighter than unary minus
    ("2^-1", lambda t: 0.5),
    ("-t", lambda t: -t),
    ("--t", lambda t: t),
    ("8/2/2", lambda t: 2.0),                # left-associative
    ("10 - 4 - 3", lambda t: 3.0),
    ("t*t - 3*t + 1.5e-1", lambda t: t * t - 3 * t + 0.15),
    ("exp(-t/3)*cos(pi*t)", lambda t: np.exp(-t / 3) * np.cos(np.pi * t)),
    ("sqrt(abs(t)) + log(t^2 + 1) + tan(t/4)",
     lambda t: np.sqrt(np.abs(t)) + np.log(t**2 + 1) + np.tan(t / 4)),
    (".5*t", lambda t: 0.5 * t),
])
def test_values_scalar_and_vectorised(text, f):
    e = compile_expression(text)
    expected = np.broadcast_to(f(T), T.shape)
    np.testing.assert_allclose(e(T), expected, rtol=1e-15, atol=1e-15)
    assert e(T).shape == T.shape
    assert isinstance(e(1.25), float) and e(1.25) == pytest.approx(float(f(1.25)), abs=1e-15)


def test_constant_folding():
    assert compile_expression("2*pi").constant
    assert compile_expression("2*pi").value == 2 * math.pi
    assert compile_expression("3 + 0*t").constant is False  # t stays a variable
    assert compile_expression("sin(2*t)").tree == ("call", "sin", ("*", ("num", 2.0), ("t",)))


@pytest.mark.parametrize("text, position, fragment", [
    ("50*sin(2*t", 10, "missing ')'"),
    ("2t", 1, "write '*'"),
    ("t sin(t)", 2, "write '*'"),
    ("sin t", 4, "must be followed by '('"),
    ("x + 1", 0, "unknown name 'x'"),
    ("foo(t)", 0, "unknown name 'foo'"),
    ("t)", 1, "unmatched ')'"),
    ("", 0, "empty"),
    ("3*", 2, "ends too early"),
    ("t == 1", 2, "comparisons"),
    ("max(t, 1)", 0, "unknown name 'max'"),
    ("__import__('os').system('true')", 0, "unknown name '__import__'"),
    ("t + 'a'", 4, "unexpected character"),
    ("t.real", 1, "attribute"),
    ("[t]", 0, "grouping"),
])
def test_errors_name_the_character(text, position, fragment):
    with pytest.raises(ExpressionError) as exc:
        compile_expression(text)
    assert exc.value.position == position
    assert fragment in str(exc.value)
    assert f"at character {position + 1}" in str(exc.value)
    assert exc.value.caret().splitlines()[1] == " " * position + "^"


def test_refuses_without_running_anything(monkeypatch):
    """Parsing never reaches eval/exec: make them explode and parse hostile text."""
    import builtins

    def boom(*a, **k):
        raise AssertionError("eval/exec called")

    monkeypatch.setattr(builtins, "eval", boom)
    monkeypatch.setattr(builtins, "exec", boom)
    assert compile_expression("1+t")(2.0) == 3.0
    for text in ("().__class__", "lambda: 1", "open('x')", "t if t else 1", "a=1"):
        with pytest.raises(ExpressionError):
            compile_expression(text)


def test_deep_nesting_and_length_are_bounded():
    with pytest.raises(ExpressionError, match="nesting"):
        compile_expression("(" * 200 + "t" + ")" * 200)
    with pytest.raises(ExpressionError, match="longer than"):
        compile_expression("t+" * 600 + "t")
    assert compile_expression("(" * 50 + "t" + ")" * 50)(2.0) == 2.0


def test_out_of_domain_gives_non_finite_not_warnings():
    e = compile_expression("log(t)")
    v = e(np.array([-1.0, 0.0, 1.0]))
    assert np.isnan(v[0]) and v[1] == -np.inf and v[2] == 0.0


def test_table_evaluates_each_distinct_expression_once():
    a = compile_expression("3*t")
    b = compile_expression("3 * t")   # same tree, different text
    c = compile_expression("t^2")
    table = ExpressionTable.build([(0, 0, a), (1, 2, b), (2, 1, c)])
    assert len(table.exprs) == 2
    base = np.ones((3, 3))
    out = table.apply(base, 2.0)
    np.testing.assert_array_equal(out, [[6, 1, 1], [1, 1, 6], [1, 4, 1]])
    many = table.apply(base, np.array([0.0, 1.0, 2.0]))
    assert many.shape == (3, 3, 3)
    np.testing.assert_array_equal(many[2], out)
    assert ExpressionTable.build([]) is None


def _write(tmp_path, loads: str, dimension: int = 2):
    body = "[{name: p, mass: 2, inertia: 0.5}]" if dimension == 2 else \
        "[{name: p, mass: 2, inertia: [1, 2, 3]}]"
    f = tmp_path / "m.yaml"
    f.write_text(f"dimension: {dimension}\nbodies: {body}\nloads:\n{loads}")
    return f


def test_model_loads_vary_in_time(tmp_path):
    f = _write(tmp_path, '  - {name: push, type: force, body: p, force: ["50*sin(2*t)", 3]}\n'
                         '  - {name: twist, type: torque, body: p, torque: "cos(t)"}\n'
                         '  - {name: k, type: torque, body: p, torque: "2*pi"}\n')
    model = mbody.load(f)
    ft = model.forces
    np.testing.assert_allclose(ft.vector_at(0.0), [[0, 3, 0], [0, 0, 1], [0, 0, 2 * np.pi]])
    np.testing.assert_allclose(ft.vector_at(1.0), [[50 * np.sin(2), 3, 0], [0, 0, np.cos(1)],
                                                   [0, 0, 2 * np.pi]])
    assert ft.vector_at(np.array([0.0, 1.0])).shape == (2, 3, 3)
    assert model.loads[2].expressions == {}  # a constant expression is just a number
    # The assembly at a state's time uses the loads at that time.
    sol = mbody.assemble(model, model.initial.replace(t=1.0)).solve()
    np.testing.assert_allclose(sol.accelerations, [25 * np.sin(2), 1.5,
                                                   (np.cos(1) + 2 * np.pi) / 0.5])


def test_model_expression_errors_name_file_line_column_and_character(tmp_path):
    f = _write(tmp_path, '  - {name: push, type: force, body: p, force: ["50*sin(2*t", 2t]}\n'
                         '  - {name: tw, type: torque, body: p, torque: "log(t)"}\n')
    with pytest.raises(mbody.ModelError) as exc:
        mbody.load(f)
    issues = exc.value.issues
    assert len(issues) == 3
    a, b, c = issues
    line4 = f.read_text().splitlines()[3]
    assert (a.file, a.line, a.key) == (str(f), 4, "loads[0].force[0]")
    assert a.column == line4.index('"50*') + 1  # the value's own column
    assert "missing ')' at character 11" in a.message and '"50*sin(2*t|"' in a.message
    assert (b.line, b.column, b.key) == (4, line4.index("2t") + 1, "loads[0].force[1]")
    assert "at character 2" in b.message and '"2|t"' in b.message
    assert "write '*'" in b.hint
    assert (c.line, c.key) == (5, "loads[1].torque") and "-inf at t = 0" in c.message


def test_cli_check_reports_expression_error(tmp_path, capsys):
    from mbody.cli import main

    f = _write(tmp_path, '  - {type: force, body: p, force: [0, 0, "sin(t"]}\n', dimension=3)
    assert main(["check", str(f)]) == 2
    err = capsys.readouterr().err
    assert f"{f}:4:" in err and "at character 6" in err and "Traceback" not in err

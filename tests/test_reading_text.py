"""Inputs whose reading time grew with the square of their size, read in linear time now
(measured by tools/bench_reading_text.py; here only what they answer is checked): long
runs of digits in a model's numbers, and answers files of many equations."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from mbody.answers.load import MAX_EQUATIONS, read_answers
from mbody.cli.app import main
from mbody.model import loader

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = (MODELS / "pendulum.yaml").read_text(encoding="utf-8")
MASS_LINE = next(i for i, line in enumerate(PENDULUM.split("\n"), 1) if "mass: 2.0" in line)


def check(capsys, tmp_path: Path, mass: str) -> tuple[int, str]:
    path = tmp_path / "m.yaml"
    path.write_text(PENDULUM.replace("mass: 2.0", f"mass: {mass}"), encoding="utf-8")
    code = main(["check", str(path)])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("mass, message", [
    # the fuzzer's hang: a plain scalar of digits with an underscore, then not a number
    ("1" + "0" * 80_000 + "_x", "expected a number, got the text '1000000"),
    ('"1' + "0" * 80_000 + '}"', "expected a number, got the text '1000000"),
    ('"1' + "0" * 80_000 + ' kg!"', "expected a number, got the text '1000000"),
    ("1_" + "0" * 80_000, "has underscores: YAML 1.1 reads it as the number 1000000"),
    ("1_5", "'1_5' has underscores: YAML 1.1 reads it as the number 15, YAML 1.2 as text"),
])
def test_long_runs_of_digits_are_refused_at_their_line(capsys, tmp_path, mass, message):
    code, err = check(capsys, tmp_path, mass)
    assert code == 2
    assert f"m.yaml:{MASS_LINE}:11: bodies[0].mass: " in err
    assert message in err
    assert len(err) < 1000  # the value is cut short in the message


def test_the_linear_underscore_pattern_reads_what_the_old_one_read():
    """The number check's pattern was rewritten to stay linear: the same language."""
    old = re.compile(r"[-+]?[0-9_]*[0-9][0-9_]*(\.[0-9_]*)?([eE][-+]?[0-9]+)?")
    samples = ["1_000", "_1", "1_", "__", "_", "_._", "1_.5", "_.5_", "-_1", "+1__2",
               "1_000e5", "_e5", "1_e", "1__.__e-3", "1_0x", "0_", "._1", "1._", "_1_._e1"]
    for s in samples:
        assert bool(loader._UNDERSCORED.fullmatch(s)) == bool(old.fullmatch(s)), s


def answers_text(n: int, eq: str) -> str:
    return "student: many\nequations:\n" + "".join(
        f'  - {{body: rod, eq: "{eq.format(k=k)}"}}\n' for k in range(n))


def test_an_answers_file_of_16000_equations_is_read_with_every_mark(tmp_path):
    """Each entry's column was found by splitting the whole text again (31 s for 16 000)."""
    path = tmp_path / "a.yaml"
    path.write_text(answers_text(16_000, "m*a_x = O.Fx + {k}"), encoding="utf-8")
    answers = read_answers(path)
    assert len(answers.equations) == 16_000
    last = answers.equations[-1]
    assert (last.index, last.line, last.column, last.eq) == (16_000, 16_002, 22,
                                                              "m*a_x = O.Fx + 15999")


def test_an_answers_file_of_16000_equations_is_checked(capsys, tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text(answers_text(16_000, "m*a_x = O.Fx"), encoding="utf-8")
    code = main(["verify", str(MODELS / "pendulum.yaml"), str(path)])
    out = capsys.readouterr().out
    assert code == 0
    assert out.rstrip().endswith("16000 of 16000 equations correct; 1 of 3 rows covered.")
    assert "[16000] rod: m*a_x = O.Fx  (line 16002)" in out


def test_too_many_equations_are_refused(capsys, tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text(answers_text(MAX_EQUATIONS + 1, "m*a_x = O.Fx"), encoding="utf-8")
    code = main(["verify", str(MODELS / "pendulum.yaml"), str(path)])
    err = capsys.readouterr().err
    assert code == 2
    assert (f"a.yaml:3:3: equations: {MAX_EQUATIONS + 1} equations; at most {MAX_EQUATIONS} "
            "are checked at once (split the answers into several files)") in err


def test_labels_the_name_token_would_split_are_read_whole(tmp_path):
    """A chain whose joints are named pin-0, pin-1 ...: its reaction labels (pin-3.Fx) are
    looked up per position by length (was: every label at every character, a quarter of
    a second an equation with 1000 labels); the longest one wins (pin-10.Fx, not
    pin-1.Fx followed by '0')."""
    import mbody

    n = 60
    bodies = "\n".join(f"  - {{name: b{k}, mass: 1, inertia: 0.1, position: [{k + 0.5}, 0]}}"
                       for k in range(n))
    joints = "\n".join(f"  - {{name: pin-{k}, type: revolute, parent: "
                       f"{'ground' if k == 0 else f'b{k - 1}'}, child: b{k}, at: [{k}, 0]}}"
                       for k in range(n))
    model = mbody.loads(f"dimension: 2\ngravity: [0, -9.81]\nbodies:\n{bodies}\n"
                        f"joints:\n{joints}\n")
    v = mbody.verify(model, [("b10", "m*a_x = pin-10.Fx - pin-11.Fx"),
                             ("b10", "m*a_x = pin-10.Fx + pin-11.Fx"),
                             ("b1", "m*a_y = pin-1.Fy-pin-2.Fy - m*g")])
    assert [c.diagnosis for c in v.checks] == ["correct", "reaction_sign", "correct"]
    assert v.checks[1].details["reactions"] == ["pin-11.Fx"]

"""Grading a class fairly (review R4, F4, F5 and F8): a file is all correct only when it
gives every row asked for; an entry that cannot be read is that entry's problem, reported
with every other problem; each file may carry its own values of the model (``set:``); the
answer key (``assemble --answers-key``) is a file the checker finds all correct.

The numbers are the physical pendulum's closed forms (models/pendulum.yaml): a 1 m rod
with a 50 mm box section, pinned at its top end at 30 deg, so m g = 9.81 m, I_G = m (0.05^2
+ 1^2)/12, and the pin's lever arms about G are L/2 cos 30 and L/2 sin 30.
"""

from __future__ import annotations

import csv
import io
import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import mbody
from mbody.answers import AnswersError, verify
from mbody.answers import summary as summary_module
from mbody.answers.coverage import requirement
from mbody.answers.key import answer_key, row_equation
from mbody.answers.load import read_answers
from mbody.answers.summary import grade
from mbody.errors import MbodyError
from mbody.model.loader import load_text
from mbody.present.summary import class_summary_html
from tests.test_cli_options import run

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"
DOUBLE = MODELS / "double_pendulum.yaml"
G = 9.81
C30, S30 = 0.5 * math.cos(math.radians(30)), 0.5 * math.sin(math.radians(30))


def i_g(m: float) -> float:
    """The pendulum rod's I_G (kg m^2) for mass m: the 0.05 x 1 m box."""
    return m * (0.05**2 + 1.0**2) / 12


def pendulum_rows(m: float) -> list[str]:
    """The pendulum's three rows for mass m, written from the closed forms."""
    return [f"{m}*a_x = O.Fx", f"{m}*a_y = O.Fy - {m * G!r}",
            f"{i_g(m)!r}*alpha = -{C30!r}*O.Fx - {S30!r}*O.Fy"]


def write(path: Path, eqs: list[str], head: str = "", body: str = "rod") -> Path:
    path.write_text(head + "equations:\n" + "".join(f'  - {{body: {body}, eq: "{e}"}}\n'
                                                    for e in eqs), encoding="utf-8")
    return path


def table(text: str) -> list[dict[str, str]]:
    rows = list(csv.reader(io.StringIO(text)))
    files = rows[:rows.index([])]
    return [dict(zip(files[0], r, strict=False)) for r in files[1:]]


# --- F4: coverage ---------------------------------------------------------------------

def test_one_row_written_three_times_is_not_all_correct(tmp_path, capsys):
    ana = write(tmp_path / "ana.yaml", pendulum_rows(2.0), "student: Ana\n")
    ben = write(tmp_path / "ben.yaml", ["m*a_x = O.Fx", "m*a_x = O.Fx", "2*a_x = O.Fx"],
                "student: Ben\n")
    summary = grade(mbody.load(PENDULUM), [ana, ben])
    rows = table(summary.csv())
    assert [r["student"] for r in rows] == ["Ana", "Ben"]
    pick = ("equations", "correct", "rows covered", "rows asked", "duplicates")
    assert [rows[0][k] for k in pick] == ["3", "3", "3", "3", "0"]
    assert [rows[1][k] for k in pick] == ["3", "3", "1", "3", "2"]
    a, b = summary.graded
    assert a.all_correct and not b.all_correct and b.incomplete
    assert summary.text().startswith("2 answers files for model 'physical-pendulum': "
                                     "1 all correct, 1 incomplete")
    assert "rows asked for: every row of the model; 4 of 6 given" in summary.text()
    # the command line: Ben keeps the class from exit 0; Ana alone is all correct
    code, out, err = run(capsys, "verify", PENDULUM, ana, ben, "--summary", tmp_path / "c.csv")
    assert code == 1, err
    assert run(capsys, "verify", PENDULUM, ana, "--summary", tmp_path / "a.csv")[0] == 0
    # one file: its repeats named; exit 0 (every equation right) unless rows are required
    code, out, _ = run(capsys, "verify", PENDULUM, ben)
    assert code == 0
    assert ("equations that repeat a row an earlier correct equation gave:\n"
            "    [2] rod.x (as [1])\n    [3] rod.x (as [1])\n") in out
    assert out.rstrip().endswith("3 of 3 equations correct; 1 of 3 rows covered.")
    code, out, _ = run(capsys, "verify", PENDULUM, ben, "--require", "all")
    assert code == 1 and "rows no correct equation gave (every row of the model):" in out
    # asked for rod.x alone, Ben's file is all correct (his repeats still counted)
    code, out, _ = run(capsys, "verify", PENDULUM, ben, "--require", "rod.x",
                       "--summary", tmp_path / "x.csv")
    assert code == 0, out
    assert table((tmp_path / "x.csv").read_text())[0]["duplicates"] == "2"


def test_what_is_asked_for(tmp_path):
    model = mbody.load(DOUBLE)
    lower = ["m*a_x = A.Fx", "m*a_y = A.Fy - m*g"]
    f = write(tmp_path / "lower.yaml", lower, body="lower")
    asked = {w: verify(model, f, require=w) for w in
             ("all", "answered", "lower", "upper.theta,lower.x", ["lower.x", "lower.y"])
             if isinstance(w, str)}
    asked["list"] = verify(model, f, require=["lower.x", "lower.y"])
    # (rows asked, rows covered): the model has 3 rows a planar body, two bodies
    got = {w: (v.rows, v.covered) for w, v in asked.items()}
    assert got == {"all": (6, 2), "answered": (3, 2), "lower": (3, 2),
                   "upper.theta,lower.x": (2, 1), "list": (2, 2)}
    assert [u.row for u in asked["all"].uncovered] == ["upper.x", "upper.y", "upper.theta",
                                                       "lower.theta"]
    assert asked["list"].all_correct and not asked["lower"].all_correct
    # one file's default: the bodies it answers, as before
    assert verify(model, f).rows == 3 and verify(model, f).required == ""
    for bad, hint in (("lowr", "did you mean 'lower'?"), ("upper.thta", "upper.theta"),
                      ("al", "all")):
        with pytest.raises(MbodyError, match=f"'{bad}' is no body or row") as exc:
            requirement(model, bad)
        assert hint in str(exc.value)
    with pytest.raises(MbodyError, match="no rows named"):
        requirement(model, " , ")


def test_a_class_in_lagrange_equations_is_asked_for_them(tmp_path, capsys):
    # a file without a body answers in generalized coordinates: every Lagrange equation
    # (one here: I_O theta'' = -m g L/2 sin theta, I_O = I_G + m (L/2)^2) is a whole answer
    eq = "(I_rod + m_rod*0.5^2)*O.angle_ddot = -m_rod*g*0.5*sin(O.angle)"
    f = tmp_path / "lg.yaml"
    f.write_text(f'equations:\n  - {{eq: "{eq}"}}\n', encoding="utf-8")
    summary = grade(mbody.load(PENDULUM), [f])
    row = table(summary.csv())[0]
    assert (row["correct"], row["rows covered"], row["rows asked"]) == ("1", "1", "1")
    assert summary.graded[0].all_correct
    # asked for the Newton-Euler rows of rod instead, the same file is incomplete
    v = verify(mbody.load(PENDULUM), f, require="rod")
    assert (v.rows, v.covered, v.ok, v.all_correct) == (3, 0, True, False)
    code, _, err = run(capsys, "verify", PENDULUM, f, "--require", "lagrange",
                       "--summary", tmp_path / "l.csv")
    assert code == 0, err


# --- F5: every problem at once; an entry's problem is that entry's ----------------------

def test_a_stray_key_does_not_hide_the_equations_problems(tmp_path, capsys):
    # review R4's file: two equations without '*' and one entry with a key too many
    f = tmp_path / "g.yaml"
    f.write_text('equations:\n  - {body: rod, eq: "m a_x = O.Fx"}\n'
                 '  - {body: rod, eq: "2a_y = O.Fy - m*g"}\n'
                 '  - {body: rod, eq: "m*a_y = O.Fy - m*g", remark: x}\n', encoding="utf-8")
    code, out, err = run(capsys, "verify", PENDULUM, f)
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert lines[0] == "mbody: error: 3 problems in the answers:"
    assert lines[1].startswith(f"{f}:2:24: equations[0].eq: unexpected name 'a_x' "
                               "(write '*' for multiplication")
    assert lines[2].startswith(f"{f}:3:23: equations[1].eq: unexpected name 'a_y'")
    assert lines[3].startswith(f"{f}:4:43: equations[2].remark: unknown key 'remark'")
    # a note or a comment is free text, on an entry or on the file
    f.write_text('comment: sheet 3\nequations:\n'
                 '  - {body: rod, eq: "m*a_x = O.Fx", comment: "about G"}\n'
                 '  - {body: rod, eq: "m*a_y = O.Fy - m*g", note: 2}\n', encoding="utf-8")
    code, out, err = run(capsys, "verify", PENDULUM, f)
    assert code == 0, err
    f.write_text('note: [a, b]\nequations:\n  - {body: rod, eq: "m*a_x = O.Fx", '
                 'note: {x: 1}}\n', encoding="utf-8")
    code, _, err = run(capsys, "verify", PENDULUM, f)
    assert code == 2
    assert f"{f}:1:7: note: expected free text, got a list" in err
    assert f"{f}:3:43: equations[0].note: expected free text, got a mapping" in err


def test_in_a_class_the_readable_entries_are_graded(tmp_path, capsys):
    # Fay: one equation without '*', one with a stray key, one right
    fay = tmp_path / "fay.yaml"
    fay.write_text('student: Fay\nequations:\n  - {body: rod, eq: "m a_x = O.Fx"}\n'
                   '  - {body: rod, eq: "m*a_y = O.Fy - 19.62", remark: x}\n'
                   '  - {body: rod, eq: "I_G*alpha = -0.433*O.Fx - 0.25*O.Fy"}\n'
                   '  - {body: rdo}\n', encoding="utf-8")
    summary = grade(mbody.load(PENDULUM), [fay])
    (g,) = summary.graded
    v = g.verification
    assert v is not None and g.error == ""
    # entries 2 (its key reported, its equation checked) and 3 are right; 1 and 4 not read
    assert [c.index for c in v.checks] == [2, 3] and v.correct == 2
    assert (v.equations, v.covered, v.rows) == (4, 2, 3)
    assert [i.key for i in v.errors] == ["equations[0].eq", "equations[1].remark",
                                         "equations[3]"]
    assert not g.all_correct and not g.incomplete
    row = table(summary.csv())[0]
    assert (row["equations"], row["correct"]) == ("4", "2")
    assert row["error"].startswith(f"{fay}:3:24: equations[0].eq: unexpected name 'a_x'")
    assert row["error"].count(f"{fay}:") == 3
    assert "1 with entries that could not be read" in summary.text()
    # without --summary: each file's report lists the problems after the verdicts
    code, out, _ = run(capsys, "verify", PENDULUM, fay, fay)
    assert code == 1
    assert "problems in the answers (2 equations not checked):\n" in out
    assert "2 of 4 equations correct; 2 of 3 rows covered." in out
    # --json: the entries' problems as data
    code, out, _ = run(capsys, "verify", PENDULUM, fay, fay, "--json")
    doc = json.loads(out)
    assert [e["key"] for e in doc[0]["errors"]] == [i.key for i in v.errors]
    assert doc[0]["summary"]["equations"] == 4
    # the page shows every problem, escaped
    page = class_summary_html(summary)
    text = "".join(ET.fromstring(page.split("\n", 1)[1]).itertext())
    assert "unknown key 'remark'" in text and "rows asked" in text
    # a file that is no answers file at all is still a row of its own
    bad = tmp_path / "bad.yaml"
    bad.write_text("student: x\n", encoding="utf-8")
    g = grade(mbody.load(PENDULUM), [bad]).graded[0]
    assert g.verification is None and "no 'equations:' list" in g.error


def test_partial_reading_in_python(tmp_path):
    f = tmp_path / "a.yaml"
    f.write_text('studnt: x\nequations:\n  - {body: rod, eq: "m*a_x = O.Fx"}\n  - 3\n',
                 encoding="utf-8")
    with pytest.raises(AnswersError) as exc:
        read_answers(f)
    assert [i.key for i in exc.value.issues] == ["studnt", "equations[1]"]
    sheet = read_answers(f, partial=True)
    assert [a.eq for a in sheet.equations] == ["m*a_x = O.Fx"] and sheet.given == 2
    assert "did you mean 'student'?" in str(sheet.problems[0])
    v = verify(mbody.load(PENDULUM), f, partial=True)
    assert v.correct == 1 and not v.ok and len(v.errors) == 2
    # a bad Lagrange entry beside a good one: the good one is checked
    f.write_text('equations:\n  - {eq: "(I_rod + m_rod*0.25)*O.angle_ddot = '
                 '-m_rod*g*0.5*sin(O.angle)"}\n  - {eq: "O.angle_ddot = q"}\n',
                 encoding="utf-8")
    v = verify(mbody.load(PENDULUM), f, partial=True)
    assert [c.correct for c in v.checks] == [True]
    assert [i.key for i in v.errors] == ["equations[1].eq"]


# --- F8b: each file's own values --------------------------------------------------------

def test_a_file_with_its_own_values_is_checked_against_them(tmp_path, capsys):
    eqs = pendulum_rows(3.0)
    f = write(tmp_path / "vi.yaml", eqs, "student: Vi\nset: {bodies.rod.mass: 3}\n")
    model = mbody.load(PENDULUM)
    v = verify(model, f, require="all")
    assert v.all_correct and v.values == (("bodies.rod.mass", 3),)
    # the same as the model with those values and the file without them
    plain = write(tmp_path / "plain.yaml", eqs)
    same = verify(model.with_values({"bodies.rod.mass": 3}), plain, require="all")
    assert [c.diagnosis for c in same.checks] == [c.diagnosis for c in v.checks]
    # ...and not what the class's model gives (m = 2: every row differs)
    assert verify(model, plain).correct == 0
    code, out, _ = run(capsys, "verify", PENDULUM, f)
    assert code == 0 and out.startswith(f"model 'physical-pendulum' ({PENDULUM}) with "
                                        "bodies.rod.mass=3; answers")
    # a lever arm set too: the rod at 40 deg, G moved with it (L/2 from the pin)
    th = math.radians(40)
    c, s = 0.5 * math.cos(th), 0.5 * math.sin(th)
    f40 = write(tmp_path / "v40.yaml", [f"{i_g(2.0)!r}*alpha = -{c!r}*O.Fx - {s!r}*O.Fy"],
                f"set:\n  bodies.rod.angle: 40 deg\n  bodies.rod.position: [{s!r}, {-c!r}]\n")
    assert verify(model, f40).ok
    assert not verify(model, write(tmp_path / "p40.yaml", [
        f"{i_g(2.0)!r}*alpha = -{c!r}*O.Fx - {s!r}*O.Fy"])).ok


def test_a_class_of_variants_is_assembled_once_per_variant(tmp_path, monkeypatch, capsys):
    files = [write(tmp_path / f"s{k}.yaml", pendulum_rows(m), f"set: {{bodies.rod.mass: {m}}}\n")
             for k, m in enumerate((3.0, 2.5, 3.0, 2.5, 3.0))]
    files.append(write(tmp_path / "base.yaml", pendulum_rows(2.0)))
    made = []
    real = summary_module.assemble
    monkeypatch.setattr(summary_module, "assemble", lambda m: made.append(m) or real(m))
    summary = grade(mbody.load(PENDULUM), files)
    assert len(made) == 3  # masses 3, 2.5 and the class's own 2
    assert all(g.all_correct for g in summary.graded)
    rows = table(summary.csv())
    assert [r["set"] for r in rows] == ["bodies.rod.mass=3.0", "bodies.rod.mass=2.5",
                                        "bodies.rod.mass=3.0", "bodies.rod.mass=2.5",
                                        "bodies.rod.mass=3.0", ""]
    # the command line's --set is the class's; a file's own value is set on top of it
    code, _, err = run(capsys, "verify", PENDULUM, *files[:2], "--set", "bodies.rod.mass=7",
                       "--summary", tmp_path / "c.csv")
    assert code == 0, err
    code, _, _ = run(capsys, "verify", PENDULUM, files[-1], "--set", "bodies.rod.mass=7",
                     "--summary", tmp_path / "c.csv")
    assert code == 1  # the file without set: is checked at the class's mass, 7


def test_bad_values_are_located_in_the_answers_file(tmp_path, capsys):
    f = tmp_path / "v.yaml"
    f.write_text('set:\n  bodies.rod.mas: 3\n  bodies.rod.mass: -1\n  gravity: [0, -9.81, 0]\n'
                 'equations:\n  - {body: rod, eq: "m*a_x = O.Fx"}\n'
                 '  - {body: rod, eq: "m*a_y = O.Fy - m*gg"}\n', encoding="utf-8")
    code, out, err = run(capsys, "verify", PENDULUM, f)
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert lines[0] == "mbody: error: 4 problems in the answers:"
    assert lines[1] == (f"{f}:2:3: set.bodies.rod.mas: body 'rod' has no key 'mas' "
                        "(did you mean 'mass'?)")
    assert lines[2].startswith(f"{f}:3:20: set.bodies.rod.mass: expected a number > 0, "
                               "got -1")
    assert lines[3].startswith(f"{f}:4:12: set.gravity: expected 2 components, got 3")
    assert f"the model's own value is on line 15 of {PENDULUM}" in lines[3]
    assert lines[4].startswith(f"{f}:7:39: equations[1].eq: unknown name 'gg'")
    for text, want in (("set: 3\n", "1:6: set: expected a mapping of model paths"),
                       ("set: {bodies.rod.mass: }\n", "1:7: set.bodies.rod.mass: no value")):
        f.write_text(text + 'equations:\n  - {body: rod, eq: "m*a_x = O.Fx"}\n',
                     encoding="utf-8")
        code, _, err = run(capsys, "verify", PENDULUM, f)
        assert code == 2 and f"{f}:{want}" in err, err
    # in a class, a file whose values cannot be set is not checked: its row says why
    g = grade(mbody.load(PENDULUM), [f]).graded[0]
    assert g.verification is None and "set.bodies.rod.mass: no value" in g.error


# --- F8a: the answer key ----------------------------------------------------------------

def test_the_answer_key_is_the_closed_forms_and_all_correct(tmp_path):
    text = answer_key(mbody.load(PENDULUM))
    doc = load_text(text, "key").data
    assert doc["student"] == "answer key" and "set" not in doc
    assert [e["note"] for e in doc["equations"]] == ["rod.x", "rod.y", "rod.theta"]
    assert [e["eq"] for e in doc["equations"]] == [
        "2*a_x = O.Fx", "2*a_y = -19.62 + O.Fy",
        f"{i_g(2.0):.12g}*alpha = -{C30:.12g}*O.Fx - {S30:.12g}*O.Fy"]
    assert row_equation({"a_x": 1.0, "O.Fx": 1.0, "1": 0.0}) == "a_x = -O.Fx"
    assert row_equation({"alpha": 0.0, "1": 0.0}) == "0 = 0"


@pytest.mark.parametrize("name", sorted(p.name for p in MODELS.glob("*.yaml")))
def test_the_key_of_every_shipped_model_is_all_correct(name, tmp_path):
    model = mbody.load(MODELS / name)
    key = tmp_path / "key.yaml"
    key.write_text(answer_key(model), encoding="utf-8")
    for tol in (1e-3, 1e-9):
        v = verify(model, key, require="all", tol=tol)
        assert v.all_correct and v.duplicates == 0, [c for c in v.checks if not c.correct]
        assert v.rows == len(model.coordinates)


def test_the_key_of_a_variant_carries_its_values(tmp_path, capsys):
    key = tmp_path / "key.yaml"
    code, out, err = run(capsys, "assemble", DOUBLE, "--set", "bodies.upper.mass=3",
                         "--set", "gravity=[0, -9.7]", "--answers-key", key)
    assert code == 0 and out == f"wrote {key}  (6 equations)\n", err
    doc = load_text(key.read_text(), "key").data
    assert doc["set"] == {"bodies.upper.mass": 3, "gravity": [0, -9.7]}
    assert "3*a_y = -29.1 + O.Fy - A.Fy" in [e["eq"] for e in doc["equations"]]
    # the grader applies them: the key is all correct against the class's model
    code, _, err = run(capsys, "verify", DOUBLE, key, "--summary", tmp_path / "c.csv")
    assert code == 0, err
    # without them it is not (the upper rod's mass and the weights differ)
    key.write_text("\n".join(ln for ln in key.read_text().splitlines()
                             if not ln.startswith(("set:", "  \""))) + "\n")
    assert "set" not in load_text(key.read_text(), "key").data
    assert run(capsys, "verify", DOUBLE, key, "--summary", tmp_path / "c.csv")[0] == 1


def test_the_key_on_the_command_line(tmp_path, capsys):
    code, out, _ = run(capsys, "assemble", DOUBLE, "--answers-key", "-", "--body", "lower")
    assert code == 0
    doc = load_text(out, "key").data
    assert {e["body"] for e in doc["equations"]} == {"lower"} and len(doc["equations"]) == 3
    # a key of one body is all correct when that body is what is asked for
    key = tmp_path / "lower.yaml"
    key.write_text(out, encoding="utf-8")
    assert run(capsys, "verify", DOUBLE, key, "--require", "lower", "--summary",
               tmp_path / "c.csv")[0] == 0
    assert run(capsys, "verify", DOUBLE, key, "--summary", tmp_path / "c.csv")[0] == 1
    # never onto an input, a name of another format refused, a bad body named
    model = tmp_path / "m.yaml"
    model.write_text(DOUBLE.read_text())
    before = model.read_text()
    code, _, err = run(capsys, "assemble", model, "--answers-key", model)
    assert code == 2 and "is the model itself" in err and model.read_text() == before
    code, _, err = run(capsys, "assemble", DOUBLE, "--answers-key", tmp_path / "k.json")
    assert code == 2 and "did you mean" in err and not (tmp_path / "k.json").exists()
    code, _, err = run(capsys, "assemble", DOUBLE, "--answers-key", tmp_path / "k.yaml",
                       "--body", "lowr")
    assert code == 2 and "did you mean 'lower'?" in err
    code, _, err = run(capsys, "assemble", DOUBLE, "--answers-key", tmp_path / "k.yaml",
                       "--latex")
    assert code == 2 and "without --latex" in err

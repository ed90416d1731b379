"""A class graded at once (``mbody verify MODEL answers/*.yaml --summary class.csv``):
each row is what `verify` says of that file alone; the class's mistakes are counted as
the rows show them; a file that cannot be read is a row with its problem."""

from __future__ import annotations

import csv
import io
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import pytest

import mbody
from mbody.answers.lagrange import LAGRANGE_DIAGNOSES, POTENTIAL_GRADIENT_SIGN
from mbody.answers.summary import grade
from mbody.present.summary import class_summary_html

ROOT = Path(__file__).resolve().parent.parent
MODEL = ROOT / "models" / "double_pendulum.yaml"
RIGHT = ["m*a_x = A.Fx", "m*a_y = A.Fy - m*g", "m*a_x = O.Fx - A.Fx",
         "m*a_y = O.Fy - A.Fy - m*g"]
BODIES = ["lower", "lower", "upper", "upper"]
WRONG = {0: ("m*a_x = -A.Fx", "reaction_sign"), 1: ("m*a_y = A.Fy", "missing_applied_load"),
         2: ("m*a_x = O.Fx + A.Fx", "reaction_sign"), 3: ("m*a_y = O.Fy - m*g",
                                                         "missing_reaction")}
CLASS = {  # student -> the equations they got wrong
    "ana": [], "ben": [2], "chloe": [2, 3], "dev": [0, 1, 2, 3], "eli": [1], "fay": [2]}


@pytest.fixture
def answers(tmp_path) -> list[Path]:
    files = []
    for i, (name, wrong) in enumerate(CLASS.items()):
        eqs = [WRONG[k][0] if k in wrong else RIGHT[k] for k in range(4)]
        head = [f"student: {name.title()} Example"] if i % 2 == 0 else []
        lines = head + ["equations:"] + [f'  - {{body: {b}, eq: "{e}"}}'
                                         for b, e in zip(BODIES, eqs, strict=True)]
        path = tmp_path / f"{name}.yaml"
        path.write_text("\n".join(lines) + "\n")
        files.append(path)
    bad = tmp_path / "zed.yaml"
    bad.write_text('equations:\n  - {body: lowr, eq: "m*a_x = A.Fx"}\n')
    return [*files, bad]


def tables(text: str) -> tuple[list[list[str]], list[list[str]]]:
    rows = list(csv.reader(io.StringIO(text)))
    blank = rows.index([])
    return rows[:blank], rows[blank + 1:]


def test_each_row_is_what_verify_says_of_that_file(answers):
    model = mbody.load(MODEL)
    summary = grade(model, answers)
    files, mistakes = tables(summary.csv())
    assert files[0][:4] == ["file", "student", "equations", "correct"]
    assert files[0][-5:] == ["rows covered", "rows asked", "duplicates", "set", "error"]
    assert files[0][4:-5] == [f"mistake {k}" for k in (1, 2, 3, 4)]
    for row, path in zip(files[1:], answers, strict=True):
        assert row[0] == str(path)
        if path.stem == "zed":  # its one entry names no body of the model: read, not checked
            assert row[1] == "zed" and row[2:4] == ["1", "0"]
            assert row[-5:-1] == ["0", "6", "0", ""]
            assert "no body named 'lowr'" in row[-1] and "did you mean 'lower'" in row[-1]
            assert row[-1].startswith(f"{path}:2:12: equations[0].body: ")
            continue
        alone = mbody.verify(model, path, require="all")
        wrong = CLASS[path.stem]
        assert row[1] == (alone.student or path.stem)
        assert row[2:4] == [str(len(alone.checks)), str(4 - len(wrong))]
        # the model asks for six rows (x, y, theta of each rod); these files write the
        # x and y rows, so each correct equation covers one row and repeats none
        assert row[-5:-1] == [str(4 - len(wrong)), "6", "0", ""]
        assert row[-5:-3] == [str(alone.covered), str(alone.rows)]
        cells = [c for c in row[4:-5] if c]
        assert cells == [f"{c.diagnosis} (equation {c.index}, {c.row})"
                         for c in alone.checks if not c.correct]
        assert [c.split(" (")[0] for c in cells] == [WRONG[k][1] for k in wrong]
    # the students named in their files keep their names; the others their file's stem
    assert files[1][1] == "Ana Example" and files[2][1] == "ben"
    # the class's mistakes: counted from the rows, the most frequent first
    want = Counter()
    for wrong in CLASS.values():
        for k in wrong:
            want[(WRONG[k][1], ["lower.x", "lower.y", "upper.x", "upper.y"][k])] += 1
    assert mistakes[0] == ["mistake", "row", "equations", "students", "meaning"]
    got = {(m[0], m[1]): int(m[2]) for m in mistakes[1:]}
    assert got == dict(want)
    counts = [int(m[2]) for m in mistakes[1:]]
    assert counts == sorted(counts, reverse=True) and counts[0] == 4  # upper.x's sign


def test_the_html_summary_is_one_escaped_page(answers):
    summary = grade(mbody.load(MODEL), answers)
    page = class_summary_html(summary)
    assert page.startswith("<!DOCTYPE html>")
    root = ET.fromstring(page.split("\n", 1)[1])  # well-formed: escaped everywhere
    text = "".join(root.itertext())
    assert "Ana Example" in text and "reaction_sign" in text and "lowr" in text
    assert "The class's most frequent mistakes" in text


def run(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mbody", *argv], capture_output=True,
                          text=True, cwd=ROOT, timeout=300)


def test_the_command_line(answers, tmp_path):
    out = tmp_path / "class.csv"
    p = run("verify", str(MODEL), *map(str, answers), "--summary", str(out))
    assert p.returncode == 1, p.stderr  # some equations are wrong
    assert f"wrote {out}" in p.stdout and "7 answers files" in p.stdout
    assert out.read_text() == grade(mbody.load(MODEL), answers).csv()
    p = run("verify", str(MODEL), str(answers[0]), "--summary", str(tmp_path / "x.txt"))
    assert p.returncode == 2 and ".csv or .html" in p.stderr
    # one file and no summary: the report as before, exit 0 when all is correct
    p = run("verify", str(MODEL), str(answers[0]))
    assert p.returncode == 0 and "4 of 4 equations correct" in p.stdout
    # several files without a summary: each report in turn
    p = run("verify", str(MODEL), str(answers[0]), str(answers[1]))
    assert p.returncode == 1 and p.stdout.count("== ") == 2
    # the output may not be an input (an answers file whose name ends in .csv)
    odd = tmp_path / "odd.csv"
    odd.write_text(answers[0].read_text())
    p = run("verify", str(MODEL), str(odd), "--summary", str(odd))
    assert p.returncode == 2 and "is the answers file itself" in p.stderr
    assert odd.read_text() == answers[0].read_text()


def test_no_text_cell_of_the_csv_is_a_spreadsheet_formula(tmp_path, monkeypatch):
    # a student's name, a file's name and the error text that repeats it are free text
    # that a spreadsheet would run when they start with = + - @ (OWASP's CSV injection);
    # each gets a ' in front, and the count columns stay numbers
    eqs = "\n".join(f'  - {{body: {b}, eq: "{e}"}}' for b, e in zip(BODIES, RIGHT,
                                                                  strict=True))
    names = {"eve": '=HYPERLINK(""http://example.com"",""click"")', "fred": "+1",
             "gil": "@SUM(A1:A9)", "hal": "-2", "ida": "Ida;=1+2", "jo": "Jo"}
    files = []
    for stem, student in names.items():
        f = tmp_path / f"{stem}.yaml"
        f.write_text(f'student: "{student}"\nequations:\n{eqs}\n'.replace('""', '\\"'))
        files.append(f)
    bad = tmp_path / "=cmd.yaml"
    bad.write_text('equations:\n  - {body: lowr, eq: "m*a_x = A.Fx"}\n')
    monkeypatch.chdir(tmp_path)
    text = grade(mbody.load(MODEL), [*files, "=cmd.yaml"]).csv()
    rows, _ = tables(text)
    by_stem = {Path(r[0].lstrip("'")).stem: r for r in rows[1:]}
    assert by_stem["eve"][1] == "'=HYPERLINK(\"http://example.com\",\"click\")"
    assert by_stem["fred"][1] == "'+1" and by_stem["gil"][1] == "'@SUM(A1:A9)"
    assert by_stem["hal"][1] == "'-2"  # a name, not a number: the student column is text
    assert by_stem["ida"][1] == "Ida;'=1+2"  # where a ';' spreadsheet would start a cell
    assert by_stem["jo"][1] == "Jo"  # nothing else is changed
    for r in rows[1:-1]:
        assert r[2:4] == ["4", "4"], r  # the counts: numbers, never quoted
    # a file named =cmd.yaml given as such: its file cell and its error text
    last = rows[-1]
    assert last[0] == "'=cmd.yaml" and last[1] == "'=cmd"
    assert last[-1].startswith("'=cmd.yaml") and "no body named 'lowr'" in last[-1]
    assert not any(c.startswith(("=", "+", "-", "@", "\t", "\r")) for r in rows for c in r)


def test_a_lagrange_mistake_is_a_mistake_of_the_class(tmp_path):
    # an entry without a body is a Lagrange equation; its diagnoses are Lagrange's own
    # (the pendulum: 0.667083 O.angle_ddot = -4.905 with I_O = I_rod + m_rod 0.5^2 and
    # the weight's moment m_rod g 0.5 sin(30 deg); here of the wrong sign)
    pendulum = ROOT / "models" / "pendulum.yaml"
    f = tmp_path / "lg.yaml"
    f.write_text('equations:\n  - {eq: "(I_rod + m_rod*0.5^2)*O.angle_ddot = '
                 'm_rod*g*0.5*sin(O.angle)"}\n')
    summary = grade(mbody.load(pendulum), [f])
    assert summary.graded[0].wrong[0].diagnosis == POTENTIAL_GRADIENT_SIGN
    _, mistakes = tables(summary.csv())
    assert mistakes[1][0] == POTENTIAL_GRADIENT_SIGN
    assert mistakes[1][-1] == LAGRANGE_DIAGNOSES[POTENTIAL_GRADIENT_SIGN]
    page = class_summary_html(summary)
    text = "".join(ET.fromstring(page.split("\n", 1)[1]).itertext())
    assert LAGRANGE_DIAGNOSES[POTENTIAL_GRADIENT_SIGN] in text
    for out in ("class.csv", "class.html"):
        p = run("verify", str(pendulum), str(f), "--summary", str(tmp_path / out))
        assert p.returncode == 1, p.stderr  # one wrong equation: not an internal error


def test_a_folder_a_device_or_a_pipe_among_the_files_is_a_row(answers, tmp_path):
    # each is one student's problem, as a missing file is: a row with its error, and
    # the class goes on (exit 1, the summary written)
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    odd = [folder, Path(os.devnull), tmp_path / "missing.yaml"]
    if hasattr(os, "mkfifo"):  # no writer: nothing comes through it in the wait
        os.mkfifo(tmp_path / "pipe.yaml")
        odd.append(tmp_path / "pipe.yaml")
    out = tmp_path / "class.csv"
    p = run("verify", str(MODEL), str(answers[0]), *map(str, odd), "--summary", str(out))
    assert p.returncode == 1, p.stderr
    assert f"{1 + len(odd)} answers files" in p.stdout and f"wrote {out}" in p.stdout
    rows, _ = tables(out.read_text())
    assert rows[1][:4] == [str(answers[0]), "Ana Example", "4", "4"]
    errors = {Path(r[0]).name: r[-1] for r in rows[2:]}
    assert all(r[2:4] == ["0", "0"] for r in rows[2:])
    assert errors["folder.yaml"] == f"{folder}: this is a directory; expected a YAML answers file"
    assert errors[Path(os.devnull).name].startswith(f"{os.devnull}: this is a character device")
    assert errors[Path(os.devnull).name].endswith("not a file; expected a YAML answers file")
    assert errors["missing.yaml"] == f"{tmp_path / 'missing.yaml'}: no such file"
    if hasattr(os, "mkfifo"):
        assert errors["pipe.yaml"].startswith(f"{tmp_path / 'pipe.yaml'}: nothing came "
                                              "through this pipe")
    # one file alone is the command's input: refused as before (exit 2)
    p = run("verify", str(MODEL), str(folder))
    assert p.returncode == 2 and "this is a directory" in p.stderr

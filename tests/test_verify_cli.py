"""`mbody verify` and `mbody report --answers`, run as a user runs them."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from mbody.answers import DIAGNOSES

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"


def mbody(*args: str | Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    p = subprocess.run([sys.executable, "-m", "mbody", *map(str, args)], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=120)
    assert "Traceback" not in p.stderr and "Traceback" not in p.stdout, p.stderr
    return p


def test_verify_explains_each_equation_and_exits_1_when_one_is_wrong():
    p = mbody("verify", MODELS / "seed_example_2.yaml", MODELS / "answers/seed_example_2.yaml")
    assert p.returncode == 1, p.stderr
    out = p.stdout
    assert "[3] body: I_3*alpha_3 = 0  (line 7)\n    missing_gyroscopic_term: " in out
    assert "    expected (body.w3): 4 alpha_3 + 2 = 0\n" in out
    assert "rows no correct equation gave:\n    body.y: a_y = 0\n" in out
    assert out.rstrip().endswith("4 of 5 equations correct; 3 of 6 rows covered.")


def test_verify_json_has_one_entry_per_equation_in_file_order(tmp_path):
    answers = tmp_path / "a.yaml"
    answers.write_text("equations:\n"
                       "  - {body: rod, eq: 'I_G*alpha = -m*g*0.25'}\n"
                       "  - {body: rod, eq: '2*a_y = O.Fy - 19.62'}\n"
                       "  - {body: rod, eq: '2*a_y = 15.9435 - 19.62'}\n", encoding="utf-8")
    p = mbody("verify", MODELS / "pendulum.yaml", answers, "--json")
    assert p.returncode == 1, p.stderr
    d = json.loads(p.stdout)
    assert [e["diagnosis"] for e in d["equations"]] == [
        "wrong_moment_point", "correct", "reaction_treated_as_known"]
    assert [e["line"] for e in d["equations"]] == [2, 3, 4]
    assert all(set(e) >= {"diagnosis", "expected", "explanation"} for e in d["equations"])
    assert all(e["diagnosis"] in DIAGNOSES for e in d["equations"])
    assert d["equations"][0]["expected"] == "0.167083 alpha = -0.433013 O.Fx - 0.25 O.Fy"
    assert [u["row"] for u in d["uncovered"]] == ["rod.x", "rod.theta"]
    assert d["summary"] == {"equations": 3, "correct": 1, "rows": 3, "uncovered": 2,
                            "duplicates": 0, "required": "answered"}


def test_verify_exits_0_when_every_equation_is_correct_and_tol_applies(tmp_path):
    answers = tmp_path / "a.yaml"
    answers.write_text("equations:\n  - {body: plate, eq: '0.5*alpha = 20.02'}\n",
                       encoding="utf-8")
    p = mbody("verify", MODELS / "seed_example_1.yaml", answers)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "1 of 1 equation correct" in p.stdout
    assert mbody("verify", MODELS / "seed_example_1.yaml", answers, "--tol",
                 "1e-4").returncode == 1
    p = mbody("verify", MODELS / "seed_example_1.yaml", answers, "--tol", "2")
    assert p.returncode == 2 and "between 0 and 1" in p.stderr


def test_a_bad_answers_file_is_exit_2_with_file_line_column(tmp_path):
    answers = tmp_path / "a.yaml"
    answers.write_text("equations:\n  - {body: rod, eq: '2*a_y = O.Fy - m*gg'}\n"
                       "  - {body: rdo, eq: 'a_x = 0'}\n", encoding="utf-8")
    p = mbody("verify", MODELS / "pendulum.yaml", answers)
    assert p.returncode == 2
    assert p.stderr.startswith("mbody: error: 2 problems in the answers:\n")
    assert f"{answers}:2:39: equations[0].eq: unknown name 'gg'" in p.stderr
    assert f"{answers}:3:12: equations[1].body: no body named 'rdo'" in p.stderr
    assert "did you mean 'rod'?" in p.stderr
    p = mbody("verify", MODELS / "pendulum.yaml", tmp_path / "none.yaml")
    assert p.returncode == 2 and "no such file" in p.stderr


def test_report_shows_the_answers(tmp_path):
    page = tmp_path / "r.html"
    p = mbody("report", MODELS / "seed_example_2.yaml", "-o", page, "--answers",
              MODELS / "answers/seed_example_2.yaml")
    assert p.returncode == 0, p.stderr
    html = page.read_text(encoding="utf-8")
    assert '<section id="answers">' in html and "missing_gyroscopic_term" in html
    assert "<code>I_3*alpha_3 = 0</code>" in html


def test_an_equation_not_linear_in_the_unknowns_is_said_so_with_its_term(tmp_path):
    # no mistake of the table can explain a_x^2 (the rows are linear in a_x and the
    # reactions): the verdict's line says what is wrong with it, not "none of the above"
    answers = tmp_path / "a.yaml"
    answers.write_text('equations:\n  - {body: rod, eq: "a_x^2 = O.Fx"}\n'
                       '  - {body: rod, eq: "alpha*O.Fx = 1"}\n'
                       '  - {body: rod, eq: "(a_x + O.Fy)^3 = 1"}\n'
                       '  - {eq: "O.angle_ddot^0.5 = 1"}\n', encoding="utf-8")
    p = mbody("verify", MODELS / "pendulum.yaml", answers)
    assert p.returncode == 1, p.stderr
    lines = p.stdout.splitlines()
    verdicts = [lines[k + 1] for k, line in enumerate(lines) if line.startswith("[")]
    head = "    not_an_equation_of_this_body: not linear in the unknowns"
    # an entry without a body (a Lagrange equation) has the model's label, not a body's
    lagrange = "    not_an_equation_of_this_model: not linear in the unknowns"
    assert verdicts == [f"{head} (a_x squared)", f"{head} (a product of unknowns (alpha "
                        "times O.Fx))", f"{head} (a sum of unknowns (O.Fy, a_x) cubed)",
                        f"{lagrange} (O.angle_ddot to the power 0.5)"]
    assert "it has a_x squared" in " ".join(p.stdout.split())
    doc = json.loads(mbody("verify", MODELS / "pendulum.yaml", answers, "--json").stdout)
    first = doc["equations"][0]
    assert first["diagnosis"] == "not_an_equation_of_this_body"  # the contract's name
    assert first["details"]["not_linear"] == "a_x squared"


def test_an_entry_without_body_in_newton_euler_names_asks_for_its_body(tmp_path):
    # an entry without body: is a Lagrange equation (documented); written with a body's
    # Newton-Euler names, the error asks for the body: the one whose free body has the
    # reactions it names, else every body whose equations have its names
    def error(model: str, *eqs: str) -> list[str]:
        answers = tmp_path / "a.yaml"
        answers.write_text("equations:\n" + "".join(f'  - {{eq: "{e}"}}\n' for e in eqs),
                           encoding="utf-8")
        p = mbody("verify", MODELS / model, answers)
        assert p.returncode == 2, p.stdout
        return [line for line in p.stderr.splitlines() if "equations[" in line]

    why = "an entry without body: is an equation in generalized coordinates"
    (out,) = error("pendulum.yaml", "m*a_x = O.Fx")
    assert out.endswith(f"unknown name 'm' in a Lagrange equation (the names: "
                        f"O.angle_ddot, t, g, m_rod, I_rod) (did you forget body: rod? {why})")
    out = error("double_pendulum.yaml", "m*a_y = O.Fy - A.Fy - m*g", "m*a_x = A.Fx",
                "alpha = 0")
    assert out[0].endswith(f"(did you forget body: upper? {why})")  # O: upper's alone
    assert out[1].endswith("(did you forget body: NAME? m, a_x, A.Fx are names of the "
                           f"Newton-Euler equations of upper, lower; {why})")
    assert out[2].endswith("(did you forget body: NAME? alpha is a name of the "
                           f"Newton-Euler equations of upper, lower; {why})")
    # names that are no body's: the error as it was, without the hint
    for eq in ("O.angle_dd = 0", "I_1*alpha_1 = 0", "m*a_x = B.Fx"):
        (out,) = error("double_pendulum.yaml", eq)
        assert "forget" not in out, out


def test_report_draws_the_model_the_answers_set_values_on(tmp_path):
    """With answers that `set:` values, the verdicts are the student's model's; the page
    drew the class's (the file's mass, angle and solution) beside them."""
    answers = tmp_path / "a.yaml"
    answers.write_text("set: {bodies.rod.mass: 5, bodies.rod.angle: 40 deg}\n"
                       "equations:\n  - {body: rod, eq: 'm*a_x = O.Fx'}\n", encoding="utf-8")
    pages = {}
    for name, args in {"answers": ["--answers", answers],
                       "set": ["--set", "bodies.rod.mass=5", "--set", "bodies.rod.angle=40 deg"],
                       "class": []}.items():
        pages[name] = tmp_path / f"{name}.html"
        p = mbody("report", MODELS / "pendulum.yaml", "-o", pages[name], *args)
        assert p.returncode == 0, p.stderr

    def drawn(page: Path) -> str:
        """The page from the model summary on, without the answers' section."""
        text = page.read_text(encoding="utf-8")
        text = text[text.index('<section id="summary">'):]
        if '<section id="answers">' in text:
            start = text.index('<section id="answers">')
            end = text.index("</section>", start) + len("</section>\n")
            text = text[:start] + text[end:]
        return text

    assert drawn(pages["answers"]) == drawn(pages["set"]) != drawn(pages["class"])
    head = pages["answers"].read_text(encoding="utf-8")
    assert ("with the answers' values <code>bodies.rod.mass=5</code>, "
            "<code>bodies.rod.angle=40 deg</code>") in head
    assert "(m = 5 kg," in head and "(m = 2 kg," in pages["class"].read_text(encoding="utf-8")

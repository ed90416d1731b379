"""LaTeX: the equations written out are the course's (exact strings on the worked examples),
names are escaped, and the document compiles with pdflatex (when installed; CI installs
Debian's texlive-latex-base) and always passes a structural parse."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from randmodels import planar_model, spatial_model
from test_export import ODD_NAMES

import mbody
from mbody.present.latex import (
    body_latex,
    document,
    equation_latex,
    escape,
    number,
    reaction_symbol,
    stacked_latex,
)

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"


def _asm(source) -> mbody.Assembly:
    return mbody.assemble(mbody.load(MODELS / source if isinstance(source, str) else source))


# -- what is written --------------------------------------------------------------------------
def test_planar_worked_example_reads_as_the_course_writes_it():
    """m = 10, I_G = 0.5, 50 N whose moment about G is 20 N·m: 10 a_x = 50, 0.5 α = 20."""
    eq = _asm("seed_example_1.yaml").bodies["plate"]
    text = body_latex(eq)
    assert text.startswith(r"\begin{aligned}") and text.endswith(r"\end{aligned}")
    assert [equation_latex(e) for e in eq.equations] == [
        r"10\,a_{x} &= 50", r"10\,a_{y} &= 0", r"0.5\,\alpha &= 20"]


def test_euler_equations_carry_the_gyroscopic_term():
    """I = (2, 3, 4), ω = (1, 2, 3): ω × Jω = (6, −6, 2) sits on the left of each row."""
    eq = _asm("seed_example_2.yaml").bodies["body"]
    assert [equation_latex(e) for e in eq.euler] == [
        r"2\,\dot{\omega}_{1} + 6 &= 0", r"3\,\dot{\omega}_{2} - 6 &= 0",
        r"4\,\dot{\omega}_{3} + 2 &= 0"]


def test_pendulum_reactions_are_named_unknowns():
    """θ = 30°, pin 0.5 m above G along the rod: I_G α = −½cos θ F_x − ½ sin θ F_y."""
    eq = _asm("pendulum.yaml").bodies["rod"]
    assert [equation_latex(e) for e in eq.equations] == [
        r"2\,a_{x} &= F^{\text{O}}_{x}",
        r"2\,a_{y} &= -19.62 + F^{\text{O}}_{y}",
        r"0.167083\,\alpha &= -0.433013\,F^{\text{O}}_{x} - 0.25\,F^{\text{O}}_{y}"]


def test_stacked_system_small_is_written_in_full():
    text = stacked_latex(_asm("pendulum.yaml"))
    assert text == (
        r"\begin{bmatrix}2 & 0 & 0 \\ 0 & 2 & 0 \\ 0 & 0 & 0.167083\end{bmatrix}"
        r"\begin{bmatrix}a_{x}^{\text{rod}} \\ a_{y}^{\text{rod}} \\ \alpha^{\text{rod}}"
        r"\end{bmatrix}" "\n"
        r"= \begin{bmatrix}0 \\ -19.62 \\ 0\end{bmatrix} + \begin{bmatrix}1 & 0 \\ 0 & 1 \\ "
        r"-0.433013 & -0.25\end{bmatrix}\begin{bmatrix}F^{\text{O}}_{x} \\ "
        r"F^{\text{O}}_{y}\end{bmatrix}")


def test_stacked_system_large_is_shown_as_blocks():
    asm = mbody.assemble(mbody.load(planar_model(1, n=8, n_joints=6)))
    text = stacked_latex(asm)
    assert r"\text{24 rows, 14 reaction unknowns}" in text
    assert r"M = \operatorname{diag}(M_{\text{p0}}, M_{\text{p1}}, \dots)" in text
    # One row per body, one column per joint; x where the joint touches the body.
    rows = re.findall(r"\\text\{(p\d)\} & ([^\\]*(?:\\(?:times|cdot)[^\\]*)+)", text)
    assert len(rows) == 8
    pattern = {b: [c == "times" for c in re.findall(r"\\(times|cdot)", cells)]
               for b, cells in rows}
    rt = asm.model.reaction_table
    for c in range(len(rt.labels)):
        for b in (rt.child[c], rt.parent[c]):
            if b >= 0:
                assert pattern[f"p{b}"][rt.joint[c]]
    assert sum(map(sum, pattern.values())) == len(
        {(int(b), int(j)) for b, j in zip([*rt.child, *rt.parent], [*rt.joint, *rt.joint],
                                          strict=True) if b >= 0})


def test_long_right_hand_sides_continue_on_aligned_lines():
    asm = mbody.assemble(mbody.load(spatial_model(2, n=6, n_joints=12)))
    eq = max((e for b in asm.bodies.values() for e in b.euler), key=lambda e: len(e.reactions))
    assert len(eq.reactions) > 4
    lines = equation_latex(eq).split("\\\\\n")
    assert len(lines) == -(-(len(eq.reactions) + (eq.rhs != 0)) // 4)
    assert all(line.startswith(r"&\quad ") for line in lines[1:])


def test_names_are_escaped():
    assert escape("link_1") == r"link\_1"
    assert escape("a&b%c$d#e{f}g~h^i\\j") == (
        r"a\&b\%c\$d\#e\{f\}g\textasciitilde{}h\textasciicircum{}i\textbackslash{}j")
    assert escape("Zoë") == "Zoë" and escape("θ") == "[U+03B8]"
    assert reaction_symbol("pin_A.Fx") == r"F^{\text{pin\_A}}_{x}"
    assert reaction_symbol("u.Mt") == r"M^{\text{u}}_{t}"


@pytest.mark.parametrize("x, want", [(0.0, "0"), (-1e-15, "0"), (2.5, "2.5"), (-19.62, "-19.62"),
                                     (1.5e-7, r"1.5\times10^{-7}"), (3e12, r"3\times10^{12}"),
                                     (1 / 3, "0.333333")])
def test_numbers(x, want):
    assert number(x) == want


# -- it is a valid document ----------------------------------------------------------------------
DOC_CASES = {
    "pendulum": lambda: _asm("pendulum.yaml"),
    "seed_example_2": lambda: _asm("seed_example_2.yaml"),
    "odd_names": lambda: _asm(ODD_NAMES),
    "planar_block_form": lambda: mbody.assemble(mbody.load(planar_model(1, n=8, n_joints=6))),
    "spatial_30_bodies": lambda: mbody.assemble(mbody.load(spatial_model(2, n=30,
                                                                         n_joints=40))),
}


def check_structure(tex: str) -> None:
    """A small parser: braces balance (escaped ones aside), environments nest and close,
    display math opens and closes, and the document has a preamble and a body."""
    assert tex.startswith(r"\documentclass") and tex.rstrip().endswith(r"\end{document}")
    assert r"\usepackage{amsmath}" in tex and r"\begin{document}" in tex
    stack: list[str] = []
    tokens = re.finditer(r"\\[\\{}$&#%_]|\\begin\{([^}]*)\}|\\end\{([^}]*)\}|\\\[|\\\]|[{}]",
                         tex)
    for m in tokens:
        tok = m.group(0)
        if m.group(1) is not None:
            stack.append(f"env:{m.group(1)}")
        elif m.group(2) is not None:
            assert stack and stack.pop() == f"env:{m.group(2)}", f"unbalanced \\end at {m.start()}"
        elif tok == r"\[":
            stack.append("display")
        elif tok == r"\]":
            assert stack and stack.pop() == "display"
        elif tok == "{":
            stack.append("{")
        elif tok == "}":
            assert stack and stack.pop() == "{", f"unbalanced }} at {m.start()}"
    assert stack == []
    # No raw specials from names: every '_' is a subscript in math or escaped.
    for name in re.findall(r"\\section\*\{Body ([^\n]*)\}", tex):
        assert "_" not in name.replace(r"\_", "") and "&" not in name.replace(r"\&", "")


@pytest.mark.parametrize("case", list(DOC_CASES))
def test_document_structure_parses(case):
    check_structure(document(DOC_CASES[case]()))


@pytest.mark.skipif(shutil.which("pdflatex") is None,
                    reason="pdflatex not installed (Debian: texlive-latex-base)")
@pytest.mark.parametrize("case", list(DOC_CASES))
def test_document_compiles_with_pdflatex(tmp_path, case):
    (tmp_path / "eqs.tex").write_text(document(DOC_CASES[case]()), encoding="utf-8")
    r = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error",
                        "-no-shell-escape", "eqs.tex"], cwd=tmp_path, capture_output=True,
                       text=True, timeout=120)
    log = r.stdout
    assert r.returncode == 0, log[-3000:]
    assert (tmp_path / "eqs.pdf").stat().st_size > 1000
    assert not re.search(r"^! |Undefined control sequence|Missing character", log, re.M)
    assert "LaTeX Warning" not in log and "Font Warning" not in log, log[-3000:]


# -- command line and API give the same text -----------------------------------------------------
def test_cli_latex_file_and_stdout_match_the_api(tmp_path):
    path = MODELS / "pendulum.yaml"
    want = document(_asm("pendulum.yaml"))
    out = tmp_path / "eqs.tex"
    r = subprocess.run([sys.executable, "-m", "mbody.cli", "assemble", str(path), "--latex",
                        str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_text(encoding="utf-8") == want
    r = subprocess.run([sys.executable, "-m", "mbody.cli", "assemble", str(path), "--latex"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout == want
    r = subprocess.run([sys.executable, "-m", "mbody.cli", "assemble", str(path), "--latex",
                        "--body", "rood"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "did you mean 'rod'" in r.stderr


def test_document_for_one_body_only():
    asm = _asm(ODD_NAMES)
    text = document(asm, bodies=["link_1"])
    assert r"\section*{Body link\_1}" in text
    assert text.count(r"\section*{Body ") == 1 and "(2 more bodies not shown;" in text
    big = DOC_CASES["spatial_30_bodies"]()
    text = document(big, max_bodies=5)
    assert text.count(r"\section*{Body ") == 5 and "(25 more bodies not shown;" in text
    assert r"\section*{Body b4}" in text and r"\section*{Body b5}" not in text

"""Notebook displays (issue 14): every rich display is well-formed XHTML with the real
numbers in it, its pictures are valid SVG (or PNG), names are escaped, large models stay
bounded, and the LaTeX compiles."""

from __future__ import annotations

import base64
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import mbody
from mbody.present import rich
from mbody.present.text import body_text

MODELS = Path(__file__).resolve().parents[1] / "models"
SVG = "{http://www.w3.org/2000/svg}svg"
SHOWN = ["pendulum", "heavy_top", "fourbar_spatial", "point_pendulum", "slider_crank",
         "seed_example_1", "spring_mass_damper", "planar_time_varying_force",
         "spinning_disc_bearings"]


def parse(html: str) -> ET.Element:
    """The display as XML: fails on anything not well-formed (unclosed tags, bare &)."""
    root = ET.fromstring(html)
    assert root.tag == "div" and root.get("class") == "mbody"
    return root


def text_of(root: ET.Element) -> str:
    return " ".join(" ".join(root.itertext()).split())


def rows(root: ET.Element) -> list[list[str]]:
    """Every table row's cells as text, tables in order."""
    return [[" ".join("".join(c.itertext()).split()) for c in tr] for tr in root.iter("tr")]


@pytest.mark.parametrize("name", SHOWN)
def test_model_and_assembly_displays_are_well_formed_and_name_everything(name):
    model = mbody.load(MODELS / f"{name}.yaml")
    asm = mbody.assemble(model)
    root = parse(model._repr_html_())
    txt = text_of(root)
    assert f"Model {model.name!r}" in txt
    cells = rows(root)
    assert [r[0] for r in cells[1:model.n + 1]] == list(model.body_names)
    for j in model.joints:
        assert [j.name, j.type, f"{j.parent} → {j.child}"] in [r[:3] for r in cells]
    for ld in model.loads:
        assert any(r[0] == ld.name and r[1] == ld.type for r in cells)
    assert len(list(root.iter(SVG))) == 1  # the body/joint graph
    assert "mobility:" in txt and "mbody.assemble(model)" in txt

    root = parse(asm._repr_html_())
    txt = text_of(root)
    assert len(list(root.iter(SVG))) == model.n  # one free-body diagram per body
    for b in model.body_names:
        for eq in asm.bodies[b].equations:
            assert str(eq) in txt
    unknown = [r for r in model.reactions if r not in model.known_reactions]
    assert f"{len(model.reactions)} reaction components, {len(unknown)} unknown" in txt
    assert ".solve()" in txt


def test_pendulum_body_display_separates_applied_and_constraint_forces():
    asm = mbody.assemble(mbody.load(MODELS / "pendulum.yaml"))
    root = parse(asm.bodies["rod"]._repr_html_())
    assert rows(root) == [
        ["force", "kind", "point (m)", "components", "moment about G (N m)"],
        ["gravity", "gravity", "(0, 0)", "(0, -19.62) N", "0"],
        ["O.Fx", "reaction, unknown", "(0, 0.5)", "unit (1, 0) N", "-0.433013"],
        ["O.Fy", "reaction, unknown", "(0, 0.5)", "unit (0, 1) N", "-0.25"]]
    txt = text_of(root)
    assert "Applied (known): gravity; constraint (reaction unknowns): O.Fx, O.Fy" in txt
    assert "2 a_y = -19.62 + O.Fy" in txt and "0.167083 alpha = -0.433013 O.Fx - 0.25 O.Fy" in txt
    (svg,) = root.iter(SVG)
    assert "rod" in "".join(svg.find("{http://www.w3.org/2000/svg}title").itertext())


def test_pendulum_solution_shows_accelerations_and_reactions_with_units():
    sol = mbody.assemble(mbody.load(MODELS / "pendulum.yaml")).solve()
    root = parse(sol._repr_html_())
    table = rows(root)
    # models/README.md: α = −7.353 rad/s², pin force (−6.37, 15.94) N
    assert table[1] == ["rod", "a_x = -3.1839 m/s², a_y = -1.83823 m/s², alpha = -7.3529 rad/s²"]
    assert table[3:] == [["O.Fx", "-6.3678 N", "solved"], ["O.Fy", "15.9435 N", "solved"]]


def test_spatial_solution_units_and_given_reactions():
    """Heavy top: ω̇ in rad/s² (body axes), pivot force (0, 0.128, 9.81) N; the spinning
    disc's bearing reactions are given in the file, the turntable's solved (T.My in N m)."""
    txt = text_of(parse(mbody.assemble(mbody.load(MODELS / "heavy_top.yaml")).solve()
                        ._repr_html_()))
    assert "a_y = 0.128405 m/s²" in txt and "alpha_1 = " in txt and "rad/s²" in txt
    assert "pivot.Fz 9.81 N solved" in txt
    sol = mbody.assemble(mbody.load(MODELS / "spinning_disc_bearings.yaml")).solve()
    cells = {r[0]: r[1:] for r in rows(parse(sol._repr_html_()))}
    assert cells["T.My"] == ["16.875 N m", "solved"]
    assert [v[1] for k, v in cells.items() if k.startswith(("A.", "B."))] \
        == ["given"] * sum(k.startswith(("A.", "B.")) for k in cells)


def test_body_str_is_the_block_mbody_assemble_prints():
    path = MODELS / "heavy_top.yaml"
    eq = mbody.assemble(mbody.load(path)).bodies["top"]
    assert str(eq) == body_text(eq, 3)
    r = subprocess.run([sys.executable, "-m", "mbody.cli", "assemble", str(path)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and str(eq) in r.stdout
    assert str(eq).startswith("== top ==")
    assert "Euler (about the mass centre, body axes):" in str(eq)


def test_names_and_descriptions_are_escaped():
    model = mbody.load({
        "model": "x</div><script>&", "dimension": 2, "gravity": [0, -9.81],
        "description": '<i>d</i> & "q"',
        "bodies": [{"name": "a<b>&c", "mass": 1, "inertia": 1, "position": [0.5, 0]}],
        "loads": [{"name": "<f>", "type": "force", "body": "a<b>&c", "force": [1, 0]}],
        "joints": [{"name": "p<i>", "type": "revolute", "parent": "ground",
                    "child": "a<b>&c", "at": [0, 0]}]})
    asm = mbody.assemble(model)
    for html in (model._repr_html_(), asm._repr_html_(), asm.solve()._repr_html_(),
                 asm.bodies["a<b>&c"]._repr_html_()):
        root = parse(html)
        assert not list(root.iter("script")) and not list(root.iter("i"))
        assert "a<b>&c" in text_of(root) and "a&lt;b&gt;&amp;c" in html
    assert "x</div><script>&" in text_of(parse(model._repr_html_()))


def test_a_long_chain_is_shown_in_bounded_size():
    n = 120
    bodies = [{"name": f"b{i}", "mass": 1, "inertia": 0.1, "position": [i + 0.5, 0]}
              for i in range(n)]
    joints = [{"name": f"j{i}", "type": "revolute", "parent": f"b{i - 1}" if i else "ground",
               "child": f"b{i}", "at": [i, 0]} for i in range(n)]
    model = mbody.load({"model": "chain", "dimension": 2, "gravity": [0, -9.81],
                        "bodies": bodies, "joints": joints})
    asm = mbody.assemble(model)
    root = parse(model._repr_html_())
    assert not list(root.iter(SVG))  # more than MAX_GRAPH bodies: no graph drawing
    assert f"... and {n - rich.MAX_ROWS} more bodies" in text_of(root)
    html = asm._repr_html_()
    root = parse(html)
    assert len(list(root.iter(SVG))) == rich.MAX_BODIES
    assert f"... and {n - rich.MAX_BODIES} more bodies" in text_of(root)
    assert len(html) < 2_000_000
    sol = asm.solve()
    assert len(rows(parse(sol._repr_html_()))) == 2 * (rich.MAX_ROWS + 1)


def test_trajectory_display_has_facts_and_plots_and_no_megabyte_animation(monkeypatch):
    """With the animation turned off (a light notebook), the display is the facts and the
    plots; by default it embeds the animation too (the next test)."""
    traj = mbody.simulate(mbody.load(MODELS / "double_pendulum.yaml"), 0.3, 20)
    monkeypatch.setattr(rich, "EMBED_ANIMATION", False)
    html = traj._repr_html_()
    root = parse(html)
    cells = {r[0]: r[1] for r in rows(root) if len(r) == 2}
    assert cells["bodies"] == "upper, lower" and cells["samples"] == "7, t = 0 .. 0.3 s"
    assert cells["reaction series"] == "O.Fx, O.Fy, A.Fx, A.Fy"
    # the drift where the model conserves the quantity, else why not (test_drift_report)
    energy = cells["energy T + V"]
    assert energy.startswith("E(0) = ") and float(energy.split("relative drift ")[1]) < 1e-8
    assert cells["linear momentum"] == "not conserved here (gravity; joints to ground: O)"
    (img,) = root.iter("img")
    png = base64.b64decode(img.get("src").removeprefix("data:image/png;base64,"))
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 10_000
    assert not list(root.iter("iframe")) and len(html) < 400_000
    assert "mbody.present.rich.animation(traj, reactions=True)" in text_of(root)


def test_animation_embeds_the_offline_page_in_an_iframe():
    pytest.importorskip("meshcat")
    traj = mbody.simulate(mbody.load(MODELS / "pendulum.yaml"), 0.2, 10)
    anim = rich.animation(traj, height=300)
    assert len(repr(anim)) < 300
    frame = ET.fromstring(anim._repr_html_())
    assert frame.tag == "iframe" and frame.get("height") == "300"
    page = frame.get("srcdoc")
    assert page.startswith("<!DOCTYPE html>") and "MeshCat.Viewer" in page
    assert "window.mbody_ready = true" in page
    assert rich.EMBED_ANIMATION  # by default a run's display plays it
    shown = parse(traj._repr_html_())
    (frame,) = shown.iter("iframe")
    assert "MeshCat.Viewer" in frame.get("srcdoc") and list(shown.iter("img"))


# -- LaTeX ---------------------------------------------------------------------------------------
def _latex_cases() -> list[str]:
    out = []
    for name in ("pendulum", "heavy_top", "point_pendulum", "fourbar_spatial"):
        asm = mbody.assemble(mbody.load(MODELS / f"{name}.yaml"))
        out.append(asm._repr_latex_())
        for b in asm.model.body_names:
            out.append(asm.bodies[b]._repr_latex_())
            out += [e._repr_latex_() for e in asm.bodies[b].equations]
    return out


def test_latex_displays_are_display_math_with_balanced_environments():
    for tex in _latex_cases():
        assert tex.startswith("$$") and tex.endswith("$$") and tex.count("$$") == 2
        assert len(re.findall(r"\\begin\{", tex)) == len(re.findall(r"\\end\{", tex))
        assert tex.count("{") == tex.count("}")
    eq = mbody.assemble(mbody.load(MODELS / "pendulum.yaml")).bodies["rod"].newton[1]
    assert eq._repr_latex_() == (r"$$\begin{aligned}2\,a_{y} &= -19.62 + F^{\text{O}}_{y}"
                                 r"\end{aligned}$$")


@pytest.mark.skipif(shutil.which("pdflatex") is None,
                    reason="pdflatex not installed (Debian: texlive-latex-base)")
def test_latex_displays_compile_with_pdflatex(tmp_path):
    body = "\n\n".join(_latex_cases())
    doc = ("\\documentclass{article}\n\\usepackage[utf8]{inputenc}\n\\usepackage{amsmath}\n"
           "\\begin{document}\n" + body + "\n\\end{document}\n")
    (tmp_path / "d.tex").write_text(doc, encoding="utf-8")
    r = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error",
                        "-no-shell-escape", "d.tex"], cwd=tmp_path, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stdout[-3000:]
    assert not re.search(r"^! |Undefined control sequence", r.stdout, re.M)
    assert (tmp_path / "d.pdf").stat().st_size > 1000


def test_displays_are_not_loaded_by_import_mbody():
    code = ("import sys, mbody; m = mbody.load('models/pendulum.yaml'); repr(m); "
            "repr(mbody.assemble(m)); print(sorted(k for k in sys.modules if k in "
            "('mbody.present.rich', 'matplotlib', 'meshcat')))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120, cwd=MODELS.parent)
    assert r.returncode == 0 and r.stdout.strip() == "[]", r.stderr


def test_the_docs_show_the_current_solution_display():
    """docs/notebook.md shows the pendulum's Solution display as real HTML (refreshed by
    `tools/make_notebook.py --docs`): it must be what the code gives now."""
    page = (MODELS.parent / "docs" / "notebook.md").read_text(encoding="utf-8")
    shown = page.split("<!-- solution display (tools/make_notebook.py --docs) -->\n", 1)[1]
    shown = shown.split("\n<!-- end -->", 1)[0]
    sol = mbody.assemble(mbody.load(MODELS / "pendulum.yaml")).solve()
    assert shown == rich.solution_html(sol)
    assert (MODELS.parent / "docs" / "images" / "notebook_body.png").stat().st_size > 20_000


def _force_rows(block: str) -> dict[str, list[str]]:
    """The free-body rows of a body's text block: name -> [kind, point, components, moment]
    (columns split on runs of two or more spaces)."""
    lines = block.splitlines()
    start = lines.index("free body:") + 2
    out = {}
    for line in lines[start:]:
        if not line.startswith("  "):
            break
        cells = re.split(r"\s{2,}", line.strip())
        out[cells[0]] = cells[1:]
    return out


@pytest.mark.parametrize(("model_file", "body", "parent_rows"), [
    ("double_pendulum", "upper", {"A.Fx": ("(1, 0)", "0.216506"),
                                  "A.Fy": ("(0, 1)", "0.125")}),
    ("slider_crank", "rod", {"B.Fx": ("(1, 0)", "0.0176777"),
                             "B.Fy": ("(0, 1)", "0.0780224")}),
    ("fourbar_spatial", "coupler", {"B.Fz": ("(0, 0, 1)", None)})])
def test_parent_side_rows_read_like_the_picture(model_file, body, parent_rows):
    """A reaction on the joint's parent (−R) is listed as the picture labels it, −A.Fx,
    with the unit vector and moment the arrow carries (the +axis): the name times the row
    is the column of G in the body's equations, which do not change."""
    asm = mbody.assemble(mbody.load(MODELS / f"{model_file}.yaml"))
    eq = asm.bodies[body]
    text_rows = _force_rows(str(eq))
    html_rows = {r[0]: r[1:] for r in rows(parse(eq._repr_html_()))}
    for fo in eq.fbd.reactions:
        child = fo.side > 0
        assert (fo.label in text_rows) == child and (f"-{fo.label}" in text_rows) != child
        assert (fo.label in html_rows) == child and (f"−{fo.label}" in html_rows) != child
        row = text_rows[fo.label if child else f"-{fo.label}"]
        hrow = html_rows[fo.label if child else f"−{fo.label}"]
        assert row[2].startswith("unit ") and hrow[2] == row[2]
        assert hrow[3] == row[3]
    for label, (unit, moment) in parent_rows.items():
        row = text_rows[f"-{label}"]
        assert row[2] == f"unit {unit} N"
        if moment is not None:
            assert row[3] == moment
    # the equations keep their signs: −A.Fx on the upper link is "- A.Fx" in Newton
    if model_file == "double_pendulum":
        assert str(eq.newton[0]) == "a_x = O.Fx - A.Fx"
        assert "- 0.216506 A.Fx" in str(eq.euler[0])


def test_a_planar_reaction_couple_is_a_scalar_about_z():
    """The prismatic joint's P.Mz on the piston: 'unit 1 N m' (about z), not (0, 0)."""
    eq = mbody.assemble(mbody.load(MODELS / "slider_crank.yaml")).bodies["piston"]
    assert _force_rows(str(eq))["P.Mz"] == ["reaction", "-", "unit 1 N m", "1"]
    assert {r[0]: r[1:] for r in rows(parse(eq._repr_html_()))}["P.Mz"] == [
        "reaction, unknown", "-", "unit 1 N m", "1"]


def test_solve_lists_a_planar_reaction_couple_about_z():
    """`mbody solve`'s reaction table: the prismatic joint's P.Mz turns about z; its axis
    column said (0, 0), the planar part of (0, 0, 1)."""
    from mbody.present.text import reaction_table_text

    asm = mbody.assemble(mbody.load(MODELS / "slider_crank.yaml"))
    lines = reaction_table_text(asm, asm.solve()).splitlines()
    row = next(line.split() for line in lines if line.split()[:2] == ["P", "Mz"])
    assert row[2:5] == ["about", "z", "0"] and row[5:] == ["N", "m", "solved"]
    assert next(line.split() for line in lines if line.split()[:2] == ["P", "Fy"])[2:4] \
        == ["(0,", "1)"]

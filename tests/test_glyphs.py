"""Any Unicode name in a picture (issue 22): a character the drawing font lacks (杆 in
DejaVu, an emoji in DejaVu Sans Mono) or one that draws as nothing (U+200B) is shown as
<U+XXXX>, never an internal error ("No glyphs have been loaded") or a warning; text
outputs keep every name exact.
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import mbody
from mbody.cli import main
from mbody.present.draw import fbd_scene, figure_bytes, graph_scene
from mbody.present.draw.fonts import drawable, layout

NAMES = ["杆", "a\u200bb", "😀", "bell\ab"]
MODEL = """\
dimension: 2
gravity: [0, -9.81]
bodies:
  - {name: "杆", mass: 1, inertia: 0.1, shape: {box: [1, 0.1]}}
  - {name: "a\\u200bb", mass: 1, inertia: 0.1, position: [1, 0]}
  - {name: "😀", mass: 1, inertia: 0.1, position: [2, 0]}
  - {name: "bell\\ab", mass: 1, inertia: 0.1, position: [3, 0]}
loads:
  - {name: "力😀", type: force, body: "杆", force: [1, 0]}
joints:
  - {name: "销", type: revolute, parent: ground, child: "杆", at: [0, 0]}
  - {name: "轴", type: revolute, parent: "杆", child: "a\\u200bb", at: [0.5, 0]}
"""


@pytest.fixture
def model_file(tmp_path) -> Path:
    path = tmp_path / "名.yaml"
    path.write_text(MODEL, encoding="utf-8")
    return path


def test_drawable_escapes_what_the_font_cannot_draw():
    assert drawable("rod") == "rod"
    assert drawable("杆.Fx") == "<U+6746>.Fx"
    assert drawable("a\u200bb") == "a<U+200B>b"  # in DejaVu, but it draws nothing
    assert drawable("😀") == "😀"  # DejaVu Sans has it ...
    assert drawable("😀", family="mono") == "<U+1F600>"  # ... DejaVu Sans Mono has not
    assert drawable("θ̇ ω₁ −A.Fx m²") == "θ̇ ω₁ −A.Fx m²"
    assert drawable("two\nlines\t") == "two\nlines<U+0009>"
    # escapes keep names apart that a replacement character would merge
    assert drawable("杆1") != drawable("轴1")


def test_layout_of_any_text_never_fails():
    for s in ["杆", "😀", "\x00", "\ud800", "\U0010ffff", "a\u202eb", "\u0301"]:
        for family in ("sans", "mono"):
            lay = layout(s, 9, family=family)
            assert lay.height > 0 and lay.width >= 0


@pytest.mark.parametrize("fmt", ["svg", "png", "pdf"])
def test_every_diagram_of_unicode_names_draws_without_a_warning(fmt):
    model = mbody.loads(MODEL)
    asm = mbody.assemble(model)
    pictures = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # matplotlib's "Glyph ... missing" would fail here
        for name in model.body_names:
            pictures[name] = figure_bytes(fbd_scene(asm.bodies[name].fbd), fmt)
        pictures["graph"] = figure_bytes(graph_scene(model), fmt)
    assert all(len(data) > 1000 for data in pictures.values())
    if fmt == "svg":
        for data in pictures.values():
            assert ET.fromstring(data).tag.endswith("svg")  # well-formed XML, all of them
        title = ET.fromstring(pictures["bell\ab"]).find("{http://www.w3.org/2000/svg}title")
        assert title.text.startswith("Free-body diagram of bell<U+0007>b ")


def test_the_commands_draw_unicode_names_and_keep_them_exact_in_text(model_file, tmp_path,
                                                                     capsys):
    out = tmp_path / "pictures"
    assert main(["fbd", str(model_file), "-o", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split("(body ")[1][:-1] for line in lines] == NAMES  # exact in the text
    svg = (out / "fbd_body.svg").read_text(encoding="utf-8")
    assert "<title>Free-body diagram of 杆" in svg  # the exact name for search ...
    assert "<!-- 力😀 1 N -->" in svg
    for fmt in ("png", "pdf"):
        assert main(["fbd", str(model_file), "-o", str(out), "--image-format", fmt]) == 0
    assert main(["graph", str(model_file), "-o", str(tmp_path / "g.png")]) == 0
    assert main(["report", str(model_file), "-o", str(tmp_path / "r.html")]) == 0
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "杆" in page and "力😀" in page
    assert main(["graph", str(model_file)]) == 0
    text = capsys.readouterr().out
    assert "销  revolute  ground -> 杆" in text and "轴  revolute  杆 -> a\u200bb" in text
    assert main(["assemble", str(model_file), "--body", "杆"]) == 0
    assert capsys.readouterr().out.startswith("== 杆 ==")


def test_the_picture_shows_the_code_point(model_file):
    """What is drawn for 杆 is the text <U+6746>: its glyphs are those of '<', 'U', '+'..."""
    model = mbody.load(model_file)
    scene = fbd_scene(mbody.assemble(model).bodies["杆"].fbd, equations=False)
    title = next(t for t in scene.root.items if getattr(t, "gid", None) == "title")
    assert title.s.startswith("Free-body diagram of 杆")  # the scene keeps the name
    assert layout(title.s, 12).width == layout(drawable(title.s), 12).width


def test_plot_of_a_run_with_unicode_names_has_no_warning(model_file, tmp_path, capsys):
    run = tmp_path / "run.npz"
    assert main(["simulate", str(model_file), "--t-end", "0.1", "--no-progress", "-o",
                 str(run)]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["plot", str(run), "-o", str(tmp_path / "p.png")]) == 0
    assert "Warning" not in capsys.readouterr().err

"""The model report page: self-contained, complete, and it renders in a real browser."""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.present.report import report_html

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


def test_report_holds_summary_topology_every_body_and_sizes():
    model = mbody.load(ROOT / "models" / "slider_crank.yaml")
    asm = mbody.assemble(model)
    page = report_html(model, asm=asm)
    assert page.startswith("<!DOCTYPE html>")
    # one topology picture and one diagram per body, inlined
    assert page.count("<svg") == 1 + model.n
    for name in model.body_names:
        assert f"<h2>Body {name}</h2>" in page
        for e in asm.bodies[name].equations:  # the Newton-Euler pair as text too
            assert str(e) in page
    N, m = len(asm.coordinates), len(asm.reactions)
    assert f"<td>M</td><td>{N} × {N}</td>" in page
    assert f"<td>G</td><td>{N} × {m}</td>" in page
    assert "mobility: 1" in page  # from the model summary
    # matplotlib keeps every drawn string as a comment beside its glyphs
    assert "<!-- O: revolute -->" in page and "<!-- P.Fy -->" in page
    # self-contained: nothing fetched from anywhere
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//|file:)""", page)
    assert "<link" not in page and "<script" not in page and "@import" not in page
    assert "<?xml" not in page and "<!DOCTYPE svg" not in page


def test_report_escapes_names_from_the_file():
    model = mbody.load({"model": "<b>&co", "dimension": 2,
                        "bodies": [{"name": "plate", "mass": 1, "inertia": 0.1}]})
    page = report_html(model)
    assert "&lt;b&gt;&amp;co" in page and "<b>&co" not in page


def test_report_command_writes_the_page(tmp_path, capsys):
    out = tmp_path / "r.html"
    assert main(["report", "models/heavy_top.yaml", "-o", str(out), "--view", "front"]) == 0
    page = out.read_text(encoding="utf-8")
    assert page.count("<svg") == 2  # one body, one graph
    assert "view front" in page  # the diagram's title names the view asked for
    assert "wrote" in capsys.readouterr().out
    assert main(["report", "models/no_such_model.yaml", "-o", str(tmp_path / "x.html")]) == 2
    assert not (tmp_path / "x.html").exists()


@pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="chromium is not installed")
def test_report_renders_in_headless_chromium(tmp_path):
    from PIL import Image

    page = tmp_path / "report.html"
    assert main(["report", "models/fourbar_planar.yaml", "-o", str(page)]) == 0
    shot = tmp_path / "shot.png"
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
                        "--enable-unsafe-swiftshader", "--disable-quic", "--no-first-run",
                        "--disable-background-networking", "--disable-component-update",
                        "--disable-sync", f"--user-data-dir={profile}",
                        "--window-size=1000,1600", f"--screenshot={shot}", page.as_uri()],
                       capture_output=True, timeout=120, check=False)
    assert shot.exists(), "chromium wrote no screenshot"
    img = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert img.shape[:2] == (1600, 1000)
    assert img.std() > 20  # text, tables and pictures, not a blank page
    # the page's blue headings rule and the diagrams' colours are there
    blue = (img[..., 2] > 120) & (img[..., 0] < 80)
    assert blue.sum() > 200


def _table(page, table_id):
    """The rows of <table id=table_id> as lists of cell texts (tags stripped)."""
    m = re.search(rf'<table class="solution" id="{table_id}">(.*?)</table>', page, re.S)
    assert m, f"no table {table_id}"
    return [[re.sub(r"<[^>]+>", "", c) for c in re.findall(r"<t[dh]>(.*?)</t[dh]>", row)]
            for row in re.findall(r"<tr>(.*?)</tr>", m.group(1))]


def test_report_shows_the_solved_mechanism_with_units():
    """The double pendulum released from rest: the angular accelerations of Lagrange's
    equations (models/double_pendulum.yaml), a_G = α × r at rest, and the four pin
    reactions solved, each with its unit."""
    model = mbody.load(ROOT / "models" / "double_pendulum.yaml")
    page = report_html(model)
    assert '<a href="#solution">' in page
    acc = _table(page, "accelerations")
    assert acc[0] == ["body", "ax (m/s²)", "ay (m/s²)", "α (rad/s²)"]
    assert [r[0] for r in acc[1:]] == ["upper", "lower"]
    np.testing.assert_allclose([float(acc[1][3]), float(acc[2][3])], [-7.36215, -10.1432],
                               rtol=2e-6)
    # at rest a_G1 = α1 × r_G1 (pivot at the origin), r_G1 = (0.125, -0.216506)
    np.testing.assert_allclose([float(acc[1][1]), float(acc[1][2])],
                               [7.36215 * -0.216506, -7.36215 * 0.125], rtol=2e-5)
    rx = _table(page, "reactions")
    assert rx[0] == ["reaction", "value", "unit", "status"]
    assert [r[0] for r in rx[1:]] == ["O.Fx", "O.Fy", "A.Fx", "A.Fy"]
    assert all(r[2] == "N" and r[3] == "solved" for r in rx[1:])
    sol = mbody.assemble(model).solve()
    np.testing.assert_allclose([float(r[1]) for r in rx[1:]],
                               [sol.reactions[r] for r in model.reactions], rtol=1e-5)
    # Newton for the lower rod: m a_G2 = A + m g, so A.Fx = 1 * a_x2
    assert rx[3][1] == acc[2][1]


def test_report_reactions_given_and_couples_in_newton_metres():
    """Given reactions are marked given; moment components are in N·m; a spatial
    model's columns are world-axis a and body-axis α."""
    model = mbody.load(ROOT / "models" / "practice_2_flywheel.yaml")
    rx = _table(report_html(model), "reactions")
    assert rx[1:] == [["bearing.Fx", "0", "N", "given"], ["bearing.Fy", "122.625", "N", "given"]]
    acc = _table(report_html(model), "accelerations")
    assert acc[1] == ["flywheel", "0", "0", "40"]
    model = mbody.load(ROOT / "models" / "rotor_gyroscopic_bearings.yaml")
    page = report_html(model)
    acc = _table(page, "accelerations")
    assert acc[0][1:] == ["ax (m/s²)", "ay (m/s²)", "az (m/s²)", "α1 (rad/s²)",
                          "α2 (rad/s²)", "α3 (rad/s²)"]
    rx = _table(page, "reactions")
    units = {r[0]: r[2] for r in rx[1:]}
    asm = mbody.assemble(model)
    for c, label in enumerate(model.reactions):
        assert units[label] == ("N·m" if asm.columns.is_moment[c] else "N"), label
    assert "N·m" in units.values()


def test_report_without_joints_has_accelerations_only():
    model = mbody.load(ROOT / "models" / "practice_1_translation.yaml")
    page = report_html(model)
    assert "No joints, so v̇ = M⁻¹ (Q − b)." in page
    sol = mbody.assemble(model).solve()
    acc = _table(page, "accelerations")
    np.testing.assert_allclose([float(v) for v in acc[1][1:]], sol.accelerations, rtol=1e-5)
    assert 'id="reactions"' not in page


def test_report_help_names_the_solution_section():
    """`mbody report --help` says the page holds the solved accelerations and reactions."""
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "mbody.cli", "report", "--help"],
                       capture_output=True, text=True, timeout=120)
    text = " ".join(r.stdout.split())
    assert r.returncode == 0
    assert "accelerations and joint reactions solved at the initial state" in text

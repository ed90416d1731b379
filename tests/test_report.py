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

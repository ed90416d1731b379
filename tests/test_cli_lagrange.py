"""`mbody lagrange`, `mbody modes` and `mbody animate --mode`, run as a user runs them.

The double pendulum's file (models/double_pendulum.yaml) works its accelerations out by
hand: O.angle'' = −7.36215 (the upper rod) and −10.1432 for the lower rod's absolute
angle, so A.angle'' (relative) = −10.1432 − (−7.36215) = −2.78105. Its natural
frequencies hanging are the roots of det(K − ω² M) (tests/test_linearize.py's closed
form; here: 3.79025 and 10.1663 rad/s for two equal rods, 0.5 m and 1 kg).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_cli import MODELS, fails, mbody, succeeds

import mbody as mbody_api
from mbody.io.export.generalized import read_generalized
from mbody.simulate.modes import mode_trajectory


def test_lagrange_prints_the_equations_and_the_accelerations():
    out = succeeds("lagrange", MODELS / "double_pendulum.yaml")
    assert "2 generalized coordinates (a spanning tree: O, A)" in out
    assert "0.658148*O.angle'' + 0.204074*A.angle'' = -5.41293" in out
    assert "O.angle'' = -7.36215" in out and "A.angle'' = -2.78106" in out
    assert "gravity: -5.41293, -1.73418" in out


def test_lagrange_symbolic_is_compact():
    pytest.importorskip("sympy")
    out = succeeds("lagrange", MODELS / "double_pendulum.yaml", "--symbolic")
    assert "m_lower*cos(A.angle)/8" in out  # m L a cos(θ2) with L = 0.5, a = 0.25
    assert "- g*m_lower*sin(A.angle + O.angle)/4" in out
    assert "where I_lower = 0.0208333" in out


def test_lagrange_latex_and_exports(tmp_path):
    doc = succeeds("lagrange", MODELS / "double_pendulum.yaml", "--latex")
    assert doc.startswith("\\documentclass") and "\\ddot{\\theta}_{\\text{O}}" in doc
    outs = [tmp_path / f"dp.{s}" for s in ("npz", "mat", "json")]
    printed = succeeds("lagrange", MODELS / "double_pendulum.yaml",
                       *[a for p in outs for a in ("-o", p)])
    for p in outs:
        assert f"wrote {p}" in printed
        data = read_generalized(p)
        assert list(data["coordinates"]) == ["O.angle", "A.angle"]
        np.testing.assert_allclose(np.asarray(data["M"], float),
                                   [[0.658148, 0.204074], [0.204074, 0.0833333]], rtol=1e-5)
        np.testing.assert_allclose(np.ravel(data["f"]), [-5.41293, -1.73418], rtol=1e-5)
        assert len(data["body_coordinates"]) == 6
        assert np.asarray(data["T"], float).shape == (6, 2)


def test_lagrange_bad_input():
    err = fails(2, "lagrange", MODELS / "double_pendulum.yaml", "--coordinates",
                "O.angle,A.angel")
    assert "did you mean 'A.angle'" in err
    pytest.importorskip("sympy")
    err = fails(2, "lagrange", MODELS / "fourbar_planar.yaml", "--symbolic")
    assert "close a loop" in err
    err = fails(2, "lagrange", MODELS / "double_pendulum.yaml", "-o", "out.xlsx")
    assert "unknown export format" in err


def test_modes_about_the_equilibrium(tmp_path):
    picture = tmp_path / "modes.svg"
    out = succeeds("modes", MODELS / "double_pendulum.yaml", "--equilibrium", "--picture",
                   picture)
    assert "the static equilibrium nearest its initial pose" in out
    rows = [line.split() for line in out.splitlines() if "oscillation" in line]
    assert [float(r[3]) for r in rows] == pytest.approx([3.79025, 10.1663], rel=1e-5)
    assert out.rstrip().endswith("1/s)") and "\nstable: no eigenvalue" in out
    assert picture.read_text().startswith("<?xml")


def test_modes_not_steady_says_so():
    out = succeeds("modes", MODELS / "double_pendulum.yaml")
    assert "no verdict: the state is not an equilibrium" in out


def test_modes_json_of_a_spin_about_the_intermediate_axis():
    """The shipped box spins mostly about its intermediate axis with a small wobble
    (ω = (0.01, 10, 0.01)): not a steady motion; the wobble removed, it is unstable."""
    out = json.loads(succeeds("modes", MODELS / "intermediate_axis_flip.yaml", "--json"))
    assert out["steady"] is False and out["stable"] is None


def test_animate_a_mode(tmp_path):
    page = tmp_path / "mode.html"
    out = succeeds("animate", MODELS / "double_pendulum.yaml", "--mode", "2", "--equilibrium",
                   "-o", page)
    assert "2 bodies" in out and page.stat().st_size > 10_000
    err = fails(2, "animate", MODELS / "double_pendulum.yaml", "--mode", "9")
    assert "no mode 9" in err
    err = fails(2, "animate", MODELS / "double_pendulum.yaml", "--equilibrium")
    assert "--equilibrium only applies with --mode" in err


def test_animating_a_mode_about_a_state_not_at_rest_says_so(tmp_path):
    """Review R7-4: the pendulum starts at 30 degrees, not at rest; `mbody modes` gives no
    verdict there, and `animate --mode` played the tangent system's mode without a word.
    The run's warnings (Python) and the command's (stderr) now say it; about the
    equilibrium, nothing is said."""
    lin = mbody_api.linearize(mbody_api.load(MODELS / "pendulum.yaml"))
    traj = mode_trajectory(lin, 1)
    assert any("not an equilibrium" in w for w in traj.info["warnings"])
    p = mbody("animate", MODELS / "pendulum.yaml", "--mode", "1", "-o", tmp_path / "m.html")
    assert p.returncode == 0 and "not an equilibrium" in p.stderr
    assert "--equilibrium plays the mode" in p.stderr
    p = mbody("animate", MODELS / "pendulum.yaml", "--mode", "1", "--equilibrium",
              "-o", tmp_path / "e.html")
    assert p.returncode == 0 and "warning" not in p.stderr


def test_no_verdict_on_a_moving_state_does_not_send_the_user_to_rest():
    """Review R7-18: the ball-jointed heavy top precesses steadily, but its body-axis
    rates turn: no verdict, and the hint was --equilibrium, a top at rest without its
    spin. A moving state's hint says what makes a motion steady; a state at rest keeps
    --equilibrium's."""
    top = succeeds("modes", MODELS / "heavy_top.yaml")
    assert "no verdict" in top and "gimbals" in top
    assert "--equilibrium would drop the motion" in top
    swung = succeeds("modes", MODELS / "pendulum.yaml")
    assert "no verdict" in swung and "--equilibrium linearises about the static" in swung
    assert "gimbals" not in swung


def test_modes_of_a_fully_driven_mechanism_says_nothing_oscillates():
    """The driven slider-crank has no free coordinate: a verdict saying so (the fuzzer
    found an internal error here: the largest of no eigenvalue errors)."""
    out = succeeds("modes", str(MODELS / "slider_crank_driven.yaml"))
    # no empty table with its header (review R7-14): "coordinates: none", then the verdict
    assert "no free coordinate" in out and "coordinates: none\n" in out
    assert "eigenvalue" not in out
    data = json.loads(succeeds("modes", str(MODELS / "slider_crank_driven.yaml"), "--json"))
    assert data["coordinates"] == [] and "no free coordinate" in data["verdict"]


def test_a_large_models_equations_are_bounded_and_its_progress_said(tmp_path):
    # 201 rods: the equations' 201^2 terms are not printed (the exports hold them), no
    # LaTeX document of them is written, and --progress draws the steps on stderr once a
    # second has passed (here, quicker: no bar at all)
    from test_lagrange_large import chain_yaml

    model = tmp_path / "chain.yaml"
    model.write_text(chain_yaml(201, 0.1), encoding="utf-8")
    out = succeeds("lagrange", model, "--no-progress")
    assert "(201 equations of up to 201 terms each: not written out above 200 " \
        "coordinates; -o FILE.npz, .mat or .json exports M, f and T)" in out
    assert "j200.angle  " in out and "so: j0.angle'' = " in out
    err = fails(2, "lagrange", model, "--latex", tmp_path / "eq.tex")
    assert "the equations of 201 coordinates (up to 201 terms each) are too many for a " \
        "document: --latex writes at most 200" in err
    assert not (tmp_path / "eq.tex").exists()
    p = mbody("lagrange", model, "-o", tmp_path / "eq.npz", "--progress")
    assert p.returncode == 0 and p.stderr == ""
    assert read_generalized(tmp_path / "eq.npz")["M"].shape == (201, 201)

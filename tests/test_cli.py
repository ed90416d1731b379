"""The `mbody` command, run as a user runs it: a subprocess, its output and exit code.

Shipped models give real numbers (the course's worked examples, a pendulum with known
pin forces computed by hand); bad models and bad arguments give exit code 2, one
message naming file:line:column, and never a Python traceback.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"


def mbody(*args: str | Path, module: str = "mbody.cli") -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    p = subprocess.run([sys.executable, "-m", module, *map(str, args)], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=120)
    assert "Traceback" not in p.stderr and "Traceback" not in p.stdout, p.stderr
    return p


def succeeds(*args: str | Path) -> str:
    p = mbody(*args)
    assert p.returncode == 0, p.stderr
    return p.stdout


def fails(code: int, *args: str | Path) -> str:
    p = mbody(*args)
    assert p.returncode == code, (p.returncode, p.stdout, p.stderr)
    assert p.stderr.startswith(("mbody: ", "usage: mbody")), p.stderr
    return p.stderr


# == shipped models ===================================================================

def test_python_dash_m_mbody_works():
    p = mbody("--version", module="mbody")
    assert p.returncode == 0 and re.fullmatch(r"mbody \d+\.\d+\.\d+\n", p.stdout)


def test_assemble_seed_example_1_shows_the_equations():
    out = succeeds("assemble", MODELS / "seed_example_1.yaml")
    assert "10 a_x = 50\n" in out
    assert "10 a_y = 0\n" in out
    assert "0.5 alpha = 20\n" in out  # the 50 N force 0.4 m below G: 50 x 0.4 = 20 N m
    assert re.search(r"push\s+applied\s+\(0, -0\.4\)\s+\(50, 0\) N\s+20\n", out)
    assert "stacked: M 3x3, b 3, Q 3, G 3x0" in out


def test_assemble_seed_example_2_shows_the_gyroscopic_terms():
    out = succeeds("assemble", MODELS / "seed_example_2.yaml")
    # J w_dot + w x (J w) = 0 with J w = (2, 6, 12): w x J w = (6, -6, 2).
    assert "  2 alpha_1 + 6 = 0\n  3 alpha_2 - 6 = 0\n  4 alpha_3 + 2 = 0\n" in out
    assert "stacked: M 6x6, b 6, Q 6, G 6x0" in out


def test_solve_seed_example_1():
    out = succeeds("solve", MODELS / "seed_example_1.yaml")
    assert re.search(r"plate\s+a_x = 5 m/s\^2\s+a_y = 0 m/s\^2\s+alpha = 40 rad/s\^2", out)


def test_solve_seed_example_2_json():
    data = json.loads(succeeds("solve", MODELS / "seed_example_2.yaml", "--json"))
    assert data["model"] == "seed-example-2"
    assert data["coordinates"] == ["body.x", "body.y", "body.z", "body.w1", "body.w2",
                                   "body.w3"]
    # Euler's equations, torque-free, I = (2, 3, 4), omega = (1, 2, 3):
    # w1' = (I2 - I3) w2 w3 / I1 = -3, w2' = (I3 - I1) w3 w1 / I2 = 2,
    # w3' = (I1 - I2) w1 w2 / I3 = -0.5.
    assert data["accelerations"] == pytest.approx([0, 0, 0, -3, 2, -0.5], abs=1e-12)
    assert data["by_body"]["body"]["body.w2"] == pytest.approx(2.0)
    assert data["reactions"] == {}


def test_assemble_pendulum_names_the_unknown_pin_forces():
    out = succeeds("assemble", MODELS / "pendulum.yaml")
    assert "2 a_x = O.Fx\n" in out
    assert "2 a_y = -19.62 + O.Fy\n" in out
    assert "stacked: M 3x3, b 3, Q 3, G 3x2  (reaction unknowns: 2)" in out


def test_solve_pendulum_with_known_pin_forces_by_hand():
    # Rod: m = 2 kg, 0.05 x 1.0 box, I_G = m (a^2 + b^2) / 12; hung from O at the origin,
    # 30 degrees from the vertical, G at (0.25, -0.433). Known pin force (1, 2) N:
    # a = ((1, 2) + m g) / m; alpha = (r_OG x F) / I_G with r from G to O.
    I_G = 2 * (0.05**2 + 1.0**2) / 12
    r = (-0.25, 0.4330127018922193)
    alpha = (r[0] * 2 - r[1] * 1) / I_G
    data = json.loads(succeeds("solve", MODELS / "pendulum.yaml", "--known", "O.Fx=1",
                               "--known", "O.Fy=2", "--json"))
    assert data["coordinates"] == ["rod.x", "rod.y", "rod.theta"]
    assert data["accelerations"] == pytest.approx([0.5, (2 - 2 * 9.81) / 2, alpha])
    assert data["reactions"] == {"O.Fx": 1.0, "O.Fy": 2.0}
    text = succeeds("solve", MODELS / "pendulum.yaml", "--known", "O.Fx=1", "--known",
                    "O.Fy=2")
    assert re.search(r"rod\s+a_x = 0\.5 m/s\^2\s+a_y = -8\.81 m/s\^2\s+alpha = "
                     + re.escape(f"{alpha:.6g}") + " rad/s", text)


def test_solve_pendulum_for_its_pin_forces():
    # Released from rest: alpha = -m g (L/2) sin(30 deg) / I_O, I_O = I_G + m (L/2)^2.
    I_O = 2 * (0.05**2 + 1.0) / 12 + 2 * 0.25
    alpha = -2 * 9.81 * 0.5 * math.sin(math.pi / 6) / I_O
    data = json.loads(succeeds("solve", MODELS / "pendulum.yaml", "--json"))
    assert data["accelerations"][2] == pytest.approx(alpha)
    # Newton: the pin force is m a_G - m g, a_G = alpha x r_OG (at rest, no centripetal).
    a_G = (-alpha * -0.4330127018922193, alpha * 0.25)
    assert data["reactions"]["O.Fx"] == pytest.approx(2 * a_G[0])
    assert data["reactions"]["O.Fy"] == pytest.approx(2 * a_G[1] + 2 * 9.81)


def test_solve_keeps_a_long_body_name_apart_from_its_values(tmp_path):
    """A body name longer than the column (URDF links: panda_rightfinger) is not run into
    its first value ('panda_rightfingera_x = ...')."""
    text = (MODELS / "pendulum.yaml").read_text().replace("rod", "a_rather_long_link_name")
    (tmp_path / "long.yaml").write_text(text)
    out = succeeds("solve", tmp_path / "long.yaml")
    assert "  a_rather_long_link_name  a_x = " in out, out


def test_assemble_one_body():
    out = succeeds("assemble", MODELS / "pendulum.yaml", "--body", "rod")
    assert out.startswith("== rod ==  m 2 kg, mass centre at (0.25, -0.433013) m")
    assert "stacked:" not in out


def test_check_pendulum_summary():
    out = succeeds("check", MODELS / "pendulum.yaml")
    assert "model 'physical-pendulum': planar, 1 body, 0 loads, 1 joint" in out
    assert "O              revolute ground -> rod at (0, 0): O.Fx, O.Fy" in out
    assert "reaction unknowns (2): O.Fx, O.Fy" in out
    assert "graph: 2 nodes (bodies + ground), 1 joint edge; a tree (no closed loops)" in out
    assert "mobility: 1 = 3 x 1 bodies - 2 independent constraints (2 reaction " \
           "components)" in out
    assert out.rstrip().endswith("is a valid model.")


@pytest.mark.parametrize("path", sorted(MODELS.glob("*.yaml")), ids=lambda p: p.name)
def test_check_every_shipped_model(path):
    out = succeeds("check", path)
    # (a particle, inertia: 0, counts its translations only: "2 x 1 particle")
    assert re.search(r"mobility: -?\d+ = ([36] x \d+ bodies|[23] x \d+ particles?)", out)
    assert f"OK: {path} is a valid model." in out


# == graph summary of small models ====================================================

FOURBAR_PLANAR = """\
model: fourbar
dimension: 2
bodies:
  - {name: crank, mass: 1, inertia: 0.1, position: [0.25, 0.5]}
  - {name: coupler, mass: 2, inertia: 0.7, position: [1.5, 1.25]}
  - {name: rocker, mass: 1.5, inertia: 0.2, position: [2.75, 0.75]}
joints:
  - {name: A, type: revolute, parent: ground, child: crank, at: [0, 0]}
  - {name: B, type: revolute, parent: crank, child: coupler, at: [0.5, 1]}
  - {name: C, type: revolute, parent: coupler, child: rocker, at: [2.5, 1.5]}
  - {name: D, type: revolute, parent: ground, child: rocker, at: [3, 0]}
"""

FOURBAR_SPATIAL = """\
model: fourbar-spatial
dimension: 3
bodies:
  - {name: crank, mass: 1, inertia: [0.1, 0.1, 0.1], position: [0.25, 0.5, 0]}
  - {name: coupler, mass: 2, inertia: [0.7, 0.7, 0.7], position: [1.5, 1.25, 0]}
  - {name: rocker, mass: 1.5, inertia: [0.2, 0.2, 0.2], position: [2.75, 0.75, 0]}
joints:
  - {name: A, type: revolute, parent: ground, child: crank, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: B, type: revolute, parent: crank, child: coupler, at: [0.5, 1, 0], axis: [0, 0, 1]}
  - {name: C, type: revolute, parent: coupler, child: rocker, at: [2.5, 1.5, 0],
     axis: [0, 0, 1]}
  - {name: D, type: revolute, parent: ground, child: rocker, at: [3, 0, 0], axis: [0, 0, 1]}
"""


def test_check_planar_fourbar(tmp_path):
    path = tmp_path / "fourbar.yaml"
    path.write_text(FOURBAR_PLANAR)
    out = succeeds("check", path)
    assert "graph: 4 nodes (bodies + ground), 4 joint edges; 1 closed loop" in out
    assert "connected parts: 1\n    ground, coupler, crank, rocker\n" in out
    # Gruebler: 3 x 3 - 4 pins x 2 = 1.
    assert "mobility: 1 = 3 x 3 bodies - 8 independent constraints (8 reaction " \
           "components)" in out
    assert "redundant" not in out and "attached to nothing" not in out


def test_check_spatial_fourbar_warns_of_redundant_constraints(tmp_path):
    path = tmp_path / "fourbar3.yaml"
    path.write_text(FOURBAR_SPATIAL)
    out = succeeds("check", path)
    assert "1 closed loop" in out
    # 6 x 3 - 4 x 5 = -2 by counting, yet the linkage moves: 3 of the 20 out-of-plane
    # constraints repeat the others, so the rank is 17 and the mobility 1.
    assert "mobility: 1 = 6 x 3 bodies - 17 independent constraints (20 reaction " \
           "components)" in out
    m = re.search(r"warning: 3 redundant constraints: 3 indeterminacies .*: (.*); their "
                  r"values are not unique", out)
    assert m, out
    groups = [g.strip("{}").split(", ") for g in m.group(1).split("; ")]
    assert len(groups) == 3
    named = {lab for g in groups for lab in g}
    # Only out-of-plane components can be redundant: in the plane the loop is exact.
    assert all(lab.split(".")[0] in "ABCD" and lab.split(".")[1] in ("Fz", "Mx", "My")
               for lab in named), named


def test_check_floating_bodies_and_parts(tmp_path):
    path = tmp_path / "parts.yaml"
    path.write_text("""\
dimension: 2
bodies:
  - {name: rod, mass: 2, inertia: 0.2, position: [0, -0.5]}
  - {name: drifter, mass: 1, inertia: 0.1, position: [5, 5]}
  - {name: a, mass: 1, inertia: 0.1, position: [10, 0]}
  - {name: b, mass: 1, inertia: 0.1, position: [11, 0]}
joints:
  - {name: O, type: revolute, parent: ground, child: rod, at: [0, 0]}
  - {name: W, type: fixed, parent: a, child: b, at: [10.5, 0]}
""")
    out = succeeds("check", path)
    assert "connected parts: 3\n    ground, rod\n    a, b\n    drifter\n" in out
    assert "attached to nothing (1): drifter" in out
    assert "a tree (no closed loops)" in out
    assert "mobility: 7 = 3 x 4 bodies - 5 independent constraints" in out


# == bad models =======================================================================

def write_bad(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return path


BAD = """\
dimension: 2
bodies:
  - {name: plate, mass: 10, inertia: 0.5}
loads:
  - {type: force, body: plaet, force: [50, 0]}
"""


@pytest.mark.parametrize("command", ["check", "assemble", "solve"])
def test_bad_model_exit_2_with_file_line_column(tmp_path, command):
    path = write_bad(tmp_path, BAD)
    err = fails(2, command, path)
    assert err == (f"mbody: error: {path}:5:25: loads[0].body: no body named 'plaet' "
                   "(did you mean 'plate'?)\n")


def test_several_problems_in_one_message(tmp_path):
    path = write_bad(tmp_path, BAD.replace("mass: 10", "mass: -10").replace("[50, 0]",
                                                                             "[50, 0, 0]"))
    err = fails(2, "check", path)
    assert err.startswith("mbody: error: 3 problems in the model:\n")
    assert f"{path}:3:25: bodies[0].mass: expected a number > 0, got -10" in err
    assert f"{path}:5:25: loads[0].body: no body named 'plaet'" in err
    assert f"{path}:5:39: loads[0].force: expected 2 components, got 3" in err


@pytest.mark.parametrize(("text", "words"), [
    ("dimension: 2\ndimension: 3\n", ":2:1: dimension: duplicate key 'dimension'"),
    ("dimension: 2\nbodies: [\n", ":3:1: YAML syntax error"),
    ("dimension: !!python/object/apply:os.system ['true']\n", ":1:12: dimension: the tag"),
    ("", ":1:1: the file is empty"),
])
def test_bad_yaml(tmp_path, text, words):
    path = write_bad(tmp_path, text)
    assert f"{path}{words}" in fails(2, "check", path)


def test_missing_file_and_directory(tmp_path):
    assert fails(2, "check", tmp_path / "nope.yaml") == \
        f"mbody: error: {tmp_path / 'nope.yaml'}: no such file\n"
    assert "this is a directory" in fails(2, "solve", tmp_path)


def test_non_utf8_model(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_bytes(b"dimension: 2\nmodel: \xff\n")
    assert f"{path}:2:8: not UTF-8 text" in fails(2, "assemble", path)


# == bad arguments ====================================================================

def test_known_without_equals():
    err = fails(2, "solve", MODELS / "pendulum.yaml", "--known", "O.Fx")
    assert err == "mbody: error: --known expects LABEL=VALUE (for example A.Fx=3), got " \
                  "'O.Fx'\n"


@pytest.mark.parametrize("value", ["abc", "nan", "inf"])
def test_known_value_must_be_a_finite_number(value):
    err = fails(2, "solve", MODELS / "pendulum.yaml", "--known", f"O.Fx={value}")
    assert err.startswith("mbody: error: --known O.Fx: ") and repr(value) in err


def test_known_unknown_label_with_did_you_mean():
    err = fails(2, "solve", MODELS / "pendulum.yaml", "--known", "O.fx=1")
    assert err == "mbody: error: no reaction component 'O.fx' in this model; did you mean " \
                  "'O.Fx'?\n"


def test_assemble_misspelt_body():
    err = fails(2, "assemble", MODELS / "pendulum.yaml", "--body", "rood")
    assert err == "mbody: error: no body named 'rood'; did you mean 'rod'?\n"


def test_misspelt_command():
    err = fails(2, "chek", MODELS / "pendulum.yaml")
    assert "invalid choice: 'chek'" in err and "did you mean 'check'?" in err


def test_missing_model_argument():
    assert "the following arguments are required: MODEL" in fails(2, "solve")


def test_no_command():
    """A bare `mbody` shows the help (every command listed) and exits 2."""
    err = fails(2)
    assert "usage: mbody" in err and "Start with: mbody check MODEL" in err
    assert all(c in err for c in ("check", "assemble", "solve", "simulate", "animate"))


@pytest.mark.parametrize(("command", "words"), [
    ("check", "mobility"),
    ("assemble", "--body NAME"),
    ("solve", "--known LABEL=VALUE"),
])
def test_help_of_each_command(command, words):
    out = succeeds(command, "--help")
    assert out.startswith(f"usage: mbody {command} ")
    assert "MODEL" in out and words in out


# == warnings =========================================================================

QN = ("dimension: 3\nbodies:\n  - {name: a, mass: 1, inertia: [1, 1, 1], "
      "orientation: {quaternion: [2, 0, 0, 0]}}\n")


def test_warnings_go_to_stderr_and_do_not_fail(tmp_path):
    path = tmp_path / "q.yaml"
    path.write_text(QN)
    p = mbody("solve", path)
    assert p.returncode == 0
    assert p.stderr == (f"mbody: warning: {path}:3:70: bodies[0].orientation.quaternion: the "
                        "quaternion has norm 2; it was normalised\n")
    p = mbody("check", path)  # the summary lists it once, on stdout
    assert p.returncode == 0 and p.stderr == ""
    assert p.stdout.count("the quaternion has norm 2") == 1


# == simulate compiles nothing ==========================================================

def test_a_first_simulate_in_a_fresh_process_compiles_nothing_and_says_nothing():
    """The compiled core is built by `pip install`: the first run after an install has
    nothing to compile (once numba compiled its kernels here, for a minute, and said so on
    stderr). The command's stderr is empty; neither numba nor scipy's integrators load."""
    code = ("import contextlib, io, json, sys\nimport mbody.cli\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    assert mbody.cli.main(['simulate', {str(MODELS / 'pendulum.yaml')!r}, "
            "'--t-end', '0.2', '--no-progress']) == 0\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] == 'numba'\n"
            "                        or m.startswith('scipy.integrate'))))\n")
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    p = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                       text=True, timeout=120, env=env)
    assert (p.returncode, p.stderr) == (0, "")
    assert p.stdout.splitlines()[-1] == "[]"

"""Messages and refusals a hostile review found missing (review R1's papercuts P3, P4,
P5, P9-P13 and P15): every one is exit 2 (or a located warning) naming the file, the
key or option, and what was expected, before any output is written.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.test_cli_options import run

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"


def line_of(path: Path, text: str) -> int:
    """The 1-based line of the first line of `path` holding `text`."""
    return next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if text in ln)


# == P3: a body's colour is checked when the model is read ======================================

@pytest.mark.parametrize(("colour", "hint"), [
    ("#zzzzzz", "'#rrggbb' with six hex digits"),
    ("oragne", "did you mean 'orange'?"),
])
def test_a_bad_colour_is_refused_by_check_at_its_line(tmp_path, capsys, colour, hint):
    text = (MODELS / "heavy_top.yaml").read_text()
    assert '    color: "#d35400"' in text
    bad = tmp_path / "badcolor.yaml"
    bad.write_text(text.replace('    color: "#d35400"', f'    color: "{colour}"'))
    code, _, err = run(capsys, "check", bad)
    line = line_of(bad, colour)
    assert code == 2
    assert f"{bad}:{line}:12: bodies[0].color: '{colour}' is not a colour" in err
    assert hint in err


def test_colour_names_and_forms_that_draw_are_accepted(tmp_path, capsys):
    text = (MODELS / "heavy_top.yaml").read_text()
    for colour in ("SteelBlue", "#D35400", "tab:blue"):
        good = tmp_path / "color.yaml"
        good.write_text(text.replace('    color: "#d35400"', f'    color: "{colour}"'))
        code, out, err = run(capsys, "check", good)
        assert (code, err) == (0, ""), colour


# == P4: a spring whose ends coincide while it has tension ====================================

SMD = MODELS / "spring_mass_damper.yaml"
TOUCHING = "bodies.block.position=[0,-0.05]"  # the block's top (0, 0.05) on the ceiling point


def test_coincident_spring_ends_with_tension_warn_at_the_spring(capsys):
    code, out, err = run(capsys, "solve", SMD, "--set", TOUCHING)
    line = line_of(SMD, "type: spring") - 1  # the entry starts on its '- name:' line
    assert code == 0
    assert f"mbody: warning: {SMD}:{line}:5: loads[0]: the spring's ends coincide" in err
    assert "k(L − L0) = 800 × (0 − 0.5) = -400 N is not zero" in err  # k = 800, L0 = 0.5
    code, out, err = run(capsys, "check", SMD, "--set", TOUCHING)
    assert code == 0 and "loads[0]: the spring's ends coincide" in out


def test_coincident_spring_ends_without_rest_length_lose_nothing(capsys):
    code, out, err = run(capsys, "solve", SMD, "--set", TOUCHING,
                         "--set", "loads.suspension.rest_length=0")
    assert (code, err) == (0, "")


# == P5: a kinematic run that cannot end at --t-end says so =====================================

CRANK = MODELS / "slider_crank_driven.yaml"


def test_kinematics_stopping_short_of_t_end_warns_with_the_fps_that_ends_there(capsys):
    code, out, err = run(capsys, "kinematics", CRANK, "--t-end", 0.1, "--fps", 15)
    assert code == 0
    # samples at 0 and 1/15 s; the next, 2/15 s, is past 0.1 s; 20 fps divides 0.1 s
    assert "2 samples, t = 0 .. 0.0666667 s at 15 per second" in out
    warning = next(ln for ln in out.splitlines() if "the last sample" in ln)
    assert "the last sample is at t = 0.0666667 s, short of t_end = 0.1 s" in warning
    assert "use fps = 20 (or a multiple of it)" in warning
    code, out, err = run(capsys, "kinematics", CRANK, "--t-end", 0.1, "--fps", 20)
    assert code == 0 and "the last sample" not in out


def test_kinematics_json_reports_the_fps_asked_for(capsys):
    code, out, err = run(capsys, "kinematics", CRANK, "--fps", 1e-6, "--json")
    assert code == 0
    doc = json.loads(out)
    assert (doc["samples"], doc["fps"]) == (1, 1e-6)
    assert any("the last sample is at t = 0 s" in w for w in doc["warnings"])


def test_kinematic_run_from_python_warns_as_the_command_does():
    import mbody
    from mbody.simulate.kinematic import kinematic_run

    traj = kinematic_run(mbody.load(CRANK), 0.1, 15)
    assert traj.info["fps"] == 15
    (short,) = [w for w in traj.info["warnings"] if "the last sample" in w]
    assert short.startswith("the last sample is at t = 0.0666667 s, short of t_end = 0.1 s")
    assert "use fps = 20 (or a multiple of it)" in short


# == P9: a unit hint fits the key's quantity ====================================================

def planar_model(tmp_path: Path, gravity: str) -> Path:
    path = tmp_path / "g.yaml"
    path.write_text(f"model: g\ndimension: 2\ngravity: [0, {gravity}]\nbodies:\n"
                    "  - {name: b, mass: 1, inertia: 1}\n")
    return path


def test_gravity_in_g_is_converted_as_an_acceleration(tmp_path, capsys):
    path = planar_model(tmp_path, '"-1 g"')
    code, _, err = run(capsys, "check", path)
    assert code == 2
    # standard gravity is 9.80665 m/s^2 by definition (CGPM 1901)
    assert (f"{path}:3:14: gravity[1]: expected a number, got the text '-1 g' (numbers are "
            "in SI units, written without the unit: -1 g is -9.80665 m/s^2)") in err


def test_a_unit_of_another_quantity_is_named_not_converted(tmp_path, capsys):
    path = planar_model(tmp_path, '"1 kg"')
    code, _, err = run(capsys, "check", path)
    assert code == 2
    assert ("gravity[1]: expected a number, got the text '1 kg' (this number is an "
            "acceleration in m/s^2, written without the unit; kg measures a mass)") in err
    code, _, err = run(capsys, "check", PENDULUM, "--set", "bodies.rod.position.0=3 s")
    assert code == 2
    assert "this number is a length in m, written without the unit; s measures a time" in err


def test_a_planar_zero_axis_gets_a_planar_example(tmp_path, capsys):
    text = PENDULUM.read_text()
    assert "name: O, type: revolute," in text
    path = tmp_path / "ax.yaml"
    path.write_text(text.replace("name: O, type: revolute,", "name: O, axis: [0, 0], "
                                 "type: revolute,"))
    code, _, err = run(capsys, "check", path)
    assert code == 2
    assert "joints[0].axis: the axis is the zero vector (give a direction, such as [1, 0])" in err


# == P10: a NAME=VALUE option given twice for one name is refused, by every command ============

ARM = MODELS / "robots" / "two_link_arm.urdf"


@pytest.mark.parametrize(("args", "message"), [
    (("solve", PENDULUM, "--known", "O.Fx=3", "--known", "O.Fx=4"), "--known O.Fx"),
    (("check", ARM, "--q", "shoulder=1", "--q", "shoulder=2"), "--q shoulder"),
    (("check", ARM, "--qd", "elbow=1", "--qd", " elbow = 2"), "--qd elbow"),
    (("check", PENDULUM, "--set", "bodies.rod.mass=2", "--set", "bodies.rod.mass=3"),
     "--set bodies.rod.mass"),
    (("kinematics", CRANK, "--point", "P=crank:0,0", "--point", "P=crank:0.1,0"),
     "--point P"),
])
def test_an_option_given_twice_for_one_name_is_refused(capsys, args, message):
    code, out, err = run(capsys, *args)
    assert (code, out) == (2, "")
    assert err == f"mbody: error: {message} is given twice\n"


def test_the_same_option_for_different_names_is_taken(capsys):
    code, out, err = run(capsys, "check", ARM, "--q", "shoulder=1", "--q", "elbow=2")
    assert (code, err) == (0, "")


# == P11: option values within a model file's bounds; modes --view checked as fbd's ============

@pytest.mark.parametrize(("args", "message"), [
    # a model file's angle is at most 1e9 rad, any other number at most 1e100
    (("check", ARM, "--q", "shoulder=1e300"), "--q shoulder: expected a number of magnitude "
     "at most 1e100"),
    # worded as its siblings in the URDF reader (review R3, Y7; was "--q[shoulder]: ...")
    (("check", ARM, "--q", "shoulder=1e20"), "--q: joint 'shoulder': expected an angle of at "
     "most 1e+09 rad in magnitude"),
    (("check", ARM, "--qd", "elbow=1e101"), "--qd elbow: expected a number of magnitude at "
     "most 1e100"),
    (("solve", PENDULUM, "--known", "O.Fx=-1e101"), "--known O.Fx: expected a number of "
     "magnitude at most 1e100"),
    (("kinematics", CRANK, "--point", "P=crank:1e300,0"), "point 'P': expected coordinates "
     "of magnitude at most 1e+100 m"),
])
def test_option_numbers_obey_the_model_files_bounds(capsys, args, message):
    code, out, err = run(capsys, *args)
    assert (code, out) == (2, "")
    assert message in err


def test_within_the_bounds_they_are_taken(capsys):
    code, out, err = run(capsys, "check", ARM, "--q", "shoulder=1e9", "--qd", "elbow=1e99")
    assert (code, err) == (0, "")


@pytest.mark.parametrize("view", ["diag", "nan,nan"])
def test_modes_refuses_a_view_as_fbd_does(tmp_path, capsys, view):
    model = MODELS / "double_pendulum.yaml"
    code, _, fbd_err = run(capsys, "fbd", model, "--view", view, "-o", tmp_path / "f")
    assert code == 2
    picture = tmp_path / "m.svg"
    code, out, err = run(capsys, "modes", model, "--view", view, "--picture", picture)
    assert (code, out, err) == (2, "", fbd_err)
    assert f"unknown view '{view}'" in err and not picture.exists()


# == P12: an output named for another format is refused, with the name meant =================

@pytest.mark.parametrize(("args", "name", "message"), [
    (("assemble", PENDULUM, "--latex"), "x.pdf",
     "--latex {out}: the name says PDF (.pdf), but --latex writes LaTeX; did you mean "
     "'{stem}.tex'?"),
    (("lagrange", PENDULUM, "--latex"), "x.pdf",
     "--latex {out}: the name says PDF (.pdf), but --latex writes LaTeX; did you mean "
     "'{stem}.tex'?"),
    (("convert", PENDULUM, "--to", "yaml", "-o"), "q.xml",
     "-o {out}: the name says XML (.xml), but -o writes mbody YAML (--to yaml); did you "
     "mean '{stem}.yaml'?"),
    (("convert", PENDULUM, "--to", "mjcf", "-o"), "q.yaml",
     "-o {out}: the name says YAML (.yaml), but -o writes MJCF (--to mjcf); did you mean "
     "'{stem}.xml'?"),
    (("simulate", PENDULUM, "--t-end", 0.01, "-o"), "run.csv",
     "-o {out}: the name says CSV (.csv), but -o writes a run file (.npz); did you mean "
     "'{stem}.npz'?"),
    (("kinematics", CRANK, "--t-end", 0.01, "-o"), "run.txt",
     "-o {out}: the name says text (.txt), but -o writes a run file (.npz); did you mean "
     "'{stem}.npz'?"),
    (("report", PENDULUM, "-o"), "r.pdf",
     "-o {out}: the name says PDF (.pdf), but -o writes an HTML page; did you mean "
     "'{stem}.html'?"),
    (("animate", PENDULUM, "--t-end", 0.1, "-o"), "a.svg",
     "-o {out}: the name says SVG (.svg), but -o writes an HTML page; did you mean "
     "'{stem}.html'?"),
])
def test_an_output_named_for_another_format_is_refused(tmp_path, capsys, args, name,
                                                       message):
    out = tmp_path / name
    code, stdout, err = run(capsys, *args, out)
    assert (code, stdout) == (2, "")
    stem = str(out.with_suffix(""))
    assert err.startswith(f"mbody: error: {message.format(out=out, stem=stem)}")
    assert "--force" in err and not out.exists()


def test_an_output_without_a_format_suffix_is_written_as_asked(tmp_path, capsys):
    out = tmp_path / "equations"
    code, stdout, err = run(capsys, "assemble", PENDULUM, "--latex", out)
    assert (code, err) == (0, "")
    assert out.read_text().startswith("\\documentclass")


# == P13: --force is offered only where it helps ==============================================

@pytest.mark.parametrize(("args", "why"), [
    (("export", "{m}", "--csv", "{m}"), "--csv writes a folder; give a folder's name"),
    (("fbd", "{m}", "-o", "{m}"), "-o writes a folder; give a folder's name"),
    (("export", "{m}", "-o", "{m}"), "-o writes a file ending in .npz, .mat, .json; give "
     "another output file"),
    (("graph", "{m}", "-o", "{m}"), "-o writes a file ending in .svg, .png, .pdf; give "
     "another output file"),
    (("plot", "{run}", "-o", "{run}"), "-o writes a file ending in .svg, .png, .pdf; give "
     "another output file"),
])
def test_an_input_as_an_output_force_cannot_write_is_refused_without_offering_force(
        tmp_path, capsys, args, why):
    m = tmp_path / "q.yaml"
    m.write_text(PENDULUM.read_text())
    run_file = tmp_path / "run.npz"
    assert run(capsys, "simulate", PENDULUM, "--t-end", 0.05, "--no-progress", "-o",
               run_file)[0] == 0
    files = {p: p.read_bytes() for p in (m, run_file)}
    given = [a.format(m=m, run=run_file) for a in args]
    target, what = Path(given[-1]), "the model" if given[-1] == str(m) else "the run file"
    for force in ((), ("--force",)):  # the same answer: --force could not help
        code, out, err = run(capsys, *given, *force)
        assert (code, out) == (2, "")
        assert err == (f"mbody: error: {given[-2]} {target} is {what} itself ({target}): "
                       f"{why}\n")
    assert {p: p.read_bytes() for p in files} == files


def test_an_input_as_an_output_force_can_write_offers_force(tmp_path, capsys):
    m = tmp_path / "q.yaml"
    m.write_text(PENDULUM.read_text())
    code, out, err = run(capsys, "assemble", m, "--latex", m)
    assert code == 2 and err.endswith("or --force to replace it\n")
    code, out, err = run(capsys, "assemble", m, "--latex", m, "--force")
    assert code == 0 and m.read_text().startswith("\\documentclass")


def test_the_command_lines_export_suffixes_are_the_exports():
    from mbody.cli.common import EXPORT_SUFFIXES
    from mbody.io.export import SUFFIXES
    from mbody.io.export.generalized import SUFFIXES as GENERALIZED

    assert set(EXPORT_SUFFIXES) == set(SUFFIXES) == set(GENERALIZED)


# == P15: sizes in the unit they are read in; fbd with a body name too long for a file ==========

def test_a_small_size_limit_is_told_in_kib_and_bytes(capsys):
    path = PENDULUM
    assert path.stat().st_size == 1042  # 1042 / 1024 = 1.0176 KiB
    code, out, err = run(capsys, "check", path, "--max-bytes", "1k")
    assert (code, out) == (2, "")
    assert err.startswith(f"mbody: error: {path}: the file is 1.02 KiB (1,042 bytes); mbody "
                          "reads at most 1 KiB (")
    code, out, err = run(capsys, "check", path, "--max-bytes", "100")
    assert "the file is 1.02 KiB (1,042 bytes); mbody reads at most 100 bytes (" in err


def test_fbd_of_bodies_named_beyond_a_file_names_length(tmp_path, capsys):
    long = "a" * 300  # check accepts it; a file name holds at most 255 bytes
    text = (MODELS / "double_pendulum.yaml").read_text()
    text = text.replace("upper", long + "_upper").replace("lower", long + "_lower")
    model = tmp_path / "long.yaml"
    model.write_text(text)
    code, out, err = run(capsys, "fbd", model, "-o", tmp_path / "pictures")
    assert (code, err) == (0, "")
    files = sorted(p.name for p in (tmp_path / "pictures").iterdir())
    assert len(files) == 2 and all(len(f) <= 255 for f in files)  # apart, though alike
    assert all(f.startswith("fbd_aaaa") and f.endswith(".svg") for f in files)
    for f, body in zip(files, (long + "_lower", long + "_upper"), strict=False):
        assert f"wrote {tmp_path / 'pictures' / f}  (body {body})" in out


def test_fbd_file_names_keep_numbering_repeats(tmp_path, capsys):
    text = (MODELS / "double_pendulum.yaml").read_text()
    model = tmp_path / "two.yaml"  # 'a+b' and 'a_b' both make fbd_a_b
    model.write_text(text.replace("upper", "a+b").replace("lower", "a_b"))
    code, out, err = run(capsys, "fbd", model, "-o", tmp_path / "pictures")
    assert (code, err) == (0, "")
    assert sorted(p.name for p in (tmp_path / "pictures").iterdir()) == [
        "fbd_a_b.svg", "fbd_a_b_2.svg"]

"""Command-line options (issue 22): one name, one meaning; numbers within documented
bounds; `mbody graph` writes nothing unasked.

- `--format` (alias `--model-format`) is the input model's format on every command; the
  old meanings (`fbd --format png`, `convert --format mjcf`) get a did-you-mean.
- A number given as an option is checked against the bounds its --help states: exit 2
  with the range, never an internal error (`--t-end 1e308` was an OverflowError, `--dpi
  1` a FreeType error, `--dpi 100000` a MemoryError).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from mbody.cli import build_parser, main
from mbody.cli.common import MODEL_FORMATS, PICTURE_FORMATS

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"


def run(capsys, *args) -> tuple[int, str, str]:
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def last_line(err: str) -> str:
    return err.rstrip("\n").rsplit("\n", 1)[-1]


def commands() -> dict:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return dict(sub.choices)


# == mbody graph ===============================================================================

def test_graph_without_output_prints_the_graph_and_writes_nothing(tmp_path, capsys,
                                                                  monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "graph", MODELS / "slider_crank.yaml")
    assert (code, err) == (0, "")
    assert out.splitlines()[:5] == [
        "body/joint graph of 'slider-crank': 3 bodies + ground, 4 joints (edges: joint, "
        "type, parent -> child, reaction components)",
        "  O  revolute   ground -> crank  (2 reaction components)",
        "  A  revolute   crank -> rod  (2 reaction components)",
        "  B  revolute   rod -> piston  (2 reaction components)",
        "  P  prismatic  ground -> piston  (2 reaction components)"]
    assert "graph: 4 nodes (bodies + ground), 4 joint edges; 1 closed loop" in out
    assert "mobility: 1 = " in out
    assert list(tmp_path.iterdir()) == []  # no graph.svg in the current folder


def test_graph_with_output_draws_it(tmp_path, capsys):
    code, out, _ = run(capsys, "graph", MODELS / "fourbar_planar.yaml", "-o",
                       tmp_path / "g.svg")
    assert code == 0 and out.startswith(f"wrote {tmp_path / 'g.svg'}")
    assert ET.parse(tmp_path / "g.svg").getroot().tag.endswith("svg")


# == --format: the input model's format, everywhere ============================================

def test_format_is_the_model_format_on_every_command_that_reads_one():
    for name, parser in commands().items():
        acts = parser._option_string_actions
        if not any(a.dest in ("model", "source") for a in parser._get_positional_actions()):
            assert "--format" not in acts, name
            continue
        assert acts["--format"] is acts["--model-format"], name
        assert acts["--format"].dest == "model_format", name
        assert tuple(acts["--format"].choices) == MODEL_FORMATS, name
        # no other option keeps a format of something else under a model's name
        assert not [a for a in parser._actions if a.dest == "format"], name


def test_picture_formats_of_the_command_line_are_the_drawings():
    from mbody.present.draw import FORMATS

    assert PICTURE_FORMATS == FORMATS


@pytest.mark.parametrize("flag", ["--format", "--model-format"])
@pytest.mark.parametrize("command", ["check", "assemble", "solve", "jacobian", "graph"])
def test_both_names_read_a_model_with_another_extension(tmp_path, capsys, flag, command):
    model = tmp_path / "pendulum.model"
    model.write_text(PENDULUM.read_text())
    code, _, err = run(capsys, command, model, flag, "yaml")
    assert code == 0, err


def test_fbd_format_png_says_image_format(capsys):
    code, _, err = run(capsys, "fbd", PENDULUM, "--format", "png")
    assert code == 2
    assert last_line(err) == ("mbody: error: argument --format/--model-format: invalid choice: "
                              "'png' (choose from 'yaml', 'mjcf', 'urdf'); --format is the "
                              "model file's format: did you mean --image-format png?")


def test_graph_format_png_says_the_extension(capsys):
    code, _, err = run(capsys, "graph", PENDULUM, "--format", "png")
    assert code == 2
    assert last_line(err).endswith("; --format is the model file's format; a picture's "
                                   "format follows the output file's extension (-o NAME.png)")


def test_fbd_image_format_and_model_format(tmp_path, capsys):
    model = tmp_path / "p.txt"
    model.write_text(PENDULUM.read_text())
    code, out, err = run(capsys, "fbd", model, "--model-format", "yaml", "--image-format",
                         "pdf", "-o", tmp_path / "pics")
    assert code == 0, err
    assert (tmp_path / "pics" / "fbd_rod.pdf").read_bytes()[:5] == b"%PDF-"


def test_convert_format_names_the_input_and_to_the_output(tmp_path, capsys):
    code, _, err = run(capsys, "convert", PENDULUM, "-o", tmp_path / "p.model", "--format",
                       "mjcf")
    assert (code, err) == (2, f"mbody: error: --format mjcf: --format is SOURCE's format, and "
                           f"{PENDULUM} is mbody YAML by its extension; did you mean --to mjcf "
                           "(the output's format)?\n")
    assert list(tmp_path.iterdir()) == []
    code, out, err = run(capsys, "convert", PENDULUM, "-o", tmp_path / "p.model", "--to",
                         "mjcf")
    assert code == 0, err
    assert (tmp_path / "p.model").read_text().lstrip().startswith("<!--")
    # the input's format: --format, or --from as before
    for flag in ("--format", "--from", "--model-format"):
        code, out, err = run(capsys, "convert", tmp_path / "p.model", flag, "mjcf", "-o",
                             tmp_path / f"back{flag}.yaml")
        assert code == 0, err
    code, _, err = run(capsys, "convert", PENDULUM, "-o", tmp_path / "p.out")
    assert (code, err) == (2, f"mbody: error: {tmp_path / 'p.out'}: cannot tell the format of "
                           "OUTPUT from '.out' (extensions: .yaml, .xml; or give --to)\n")


# == numbers in bounds ===========================================================================

BOUNDS = [
    (["simulate", "{m}", "--t-end", "1e308"], "argument --t-end: expected a time in seconds "
     "from 1e-9 to 1e9, or turns such as '1 rev', got '1e308'"),
    (["simulate", "{m}", "--t-end", "nan"], "argument --t-end: expected a time in seconds "
     "from 1e-9 to 1e9, or turns such as '1 rev', got 'nan'"),
    (["simulate", "{m}", "--t-end=-inf"], "argument --t-end: expected a time in seconds "
     "from 1e-9 to 1e9, or turns such as '1 rev', got '-inf'"),
    (["simulate", "{m}", "--t-end", "0"], "argument --t-end: expected a time in seconds "
     "from 1e-9 to 1e9, or turns such as '1 rev', got '0'"),
    (["simulate", "{m}", "--fps", "1e400"], "argument --fps: expected a number of samples per "
     "second above 0 up to 1e6, got '1e400'"),
    (["simulate", "{m}", "--t-end", "1e9", "--fps", "1e6"], "--t-end x --fps asks for 1e15 "
     "samples (1e9 s at 1e6 per second); at most 10 000 000 (give a shorter time or fewer per "
     "second)"),
    (["simulate", "{m}", "--rtol", "1e-20"], "argument --rtol: expected a relative tolerance "
     "from 1e-13 to 0.01, got '1e-20'"),
    (["simulate", "{m}", "--atol", "0"], "argument --atol: expected an absolute tolerance from "
     "1e-300 to 0.01, got '0'"),
    (["simulate", "{m}", "--rtol", "0.5"], "argument --rtol: expected a relative tolerance "
     "from 1e-13 to 0.01, got '0.5'"),
    (["simulate", "{m}", "--max-steps", "1.5"], "argument --max-steps: expected a whole number "
     "of steps from 1 to 1 000 000 000 (0: no limit), got '1.5'"),
    (["simulate", "{m}", "--max-steps", "99999999999999999999999"], "argument --max-steps: "
     "expected a whole number of steps from 1 to 1 000 000 000 (0: no limit), got "
     "'99999999999999999999999'"),
    (["simulate", "{m}", "--max-wall", "inf"], "argument --max-wall: expected a number of "
     "seconds above 0 up to 1e7, got 'inf'"),
    (["fbd", "{m}", "--dpi", "1"], "argument --dpi: expected a whole number of dots per inch "
     "from 10 to 600, got '1'"),
    (["fbd", "{m}", "--dpi", "5"], "argument --dpi: expected a whole number of dots per inch "
     "from 10 to 600, got '5'"),
    (["fbd", "{m}", "--dpi", "100000"], "argument --dpi: expected a whole number of dots per "
     "inch from 10 to 600, got '100000'"),
    (["fbd", "{m}", "--dpi", "150.5"], "argument --dpi: expected a whole number of dots per "
     "inch from 10 to 600, got '150.5'"),
    (["animate", "{m}", "--fps", "1e9"], "argument --fps: expected a number of frames per "
     "second above 0 up to 1000, got '1e9'"),
    (["animate", "{m}", "--t-end", "1e6"], "--t-end x --fps asks for 60 000 001 frames (1e6 s "
     "at 60 "
     "per second); a page holds at most 100 000 (give a shorter time or fewer per second)"),
    (["animate", "{m}", "--live", "--hold", "-1"], "argument --hold: expected a number of "
     "seconds above 0 up to 1e7, got '-1'"),
    (["export", "{m}", "-o", "{tmp}/e.json", "--time", "nan"], "argument --time: expected a "
     "finite number of seconds, got 'nan'"),
]


@pytest.mark.parametrize(("args", "message"), BOUNDS)
def test_numbers_out_of_bounds_are_exit_2_with_the_range(tmp_path, capsys, args, message):
    code, out, err = run(capsys, *(a.format(m=PENDULUM, tmp=tmp_path) for a in args))
    assert (code, last_line(err)) == (2, f"mbody: error: {message}")
    assert out == "" and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("dpi", ["10", "600"])
def test_the_ends_of_the_dpi_range_draw(tmp_path, capsys, dpi):
    code, _, err = run(capsys, "fbd", MODELS / "seed_example_1.yaml", "--image-format", "png",
                       "--dpi", dpi, "-o", tmp_path)
    assert code == 0, err
    assert (tmp_path / "fbd_plate.png").read_bytes()[:4] == b"\x89PNG"


def test_a_tiny_span_and_the_bounds_in_help(capsys):
    code, out, err = run(capsys, "simulate", PENDULUM, "--t-end", "1e-9", "--no-progress")
    assert code == 0, err
    assert "1 samples at 60 fps" in out
    # a denormal span overflowed the simulator's step-rate estimate (exit 70)
    code, out, err = run(capsys, "simulate", PENDULUM, "--t-end=5e-324")
    assert (code, last_line(err)) == (2, "mbody: error: argument --t-end: expected a time "
                                      "in seconds from 1e-9 to 1e9, or turns such as '1 rev', "
                                      "got '5e-324'")
    code, out, _ = run(capsys, "simulate", "--help")
    text = " ".join(out.split())
    assert "(default 10; from 1e-9 to 1e9, and t_end x fps at most 10 000 000 samples)" in text
    assert "(default 1e-10; 1e-13 to 0.01)" in text
    code, out, _ = run(capsys, "fbd", "--help")
    assert "resolution of png pictures, 10 to 600 (default 150)" in " ".join(out.split())


def test_the_cli_samples_bound_is_the_simulators():
    """`simulate --t-end x --fps` is refused where mbody.simulate would refuse it."""
    import mbody
    from mbody.cli.sim import SAMPLES_MAX

    model = mbody.load(PENDULUM)
    with pytest.raises(mbody.MbodyError, match="at most 10 million"):
        mbody.simulate(model, t_end=(SAMPLES_MAX + 1) / 60.0, fps=60.0)


def test_options_keep_their_meaning_when_repeated(capsys):
    """argparse keeps the last of a repeated option; a value that is refused is refused
    wherever it stands."""
    code, _, err = run(capsys, "fbd", PENDULUM, "--dpi", "300", "--dpi", "3")
    assert code == 2 and "got '3'" in err


def test_no_option_takes_a_special_file_as_a_folder(tmp_path, capsys):
    if not os.path.exists("/dev/null"):
        pytest.skip("no /dev/null")
    code, _, err = run(capsys, "fbd", PENDULUM, "-o", "/dev/null")
    assert (code, err) == (2, "mbody: error: -o /dev/null: not a folder (fbd writes one picture "
                           "per body)\n")
    code, _, err = run(capsys, "export", PENDULUM, "--csv", "/dev/null")
    assert (code, err) == (2, "mbody: error: /dev/null: exists and is not a folder\n")


@pytest.mark.parametrize(("args", "what"), [
    (["check", ""], "the model"),
    (["simulate", "{m}", "-o", ""], "-o"),
    (["animate", ""], "the input"),
    (["verify", "{m}", ""], "the answers file"),
    (["assemble", "{m}", "--latex", ""], "--latex"),
    (["export", "{m}", "--csv", ""], "--csv"),
])
def test_an_empty_file_name_is_refused(capsys, args, what):
    """'' was read as the current folder, or taken for 'no output' after simulating
    ('simulate -o ""' printed "wrote " and wrote nothing; 'animate ""' was exit 70)."""
    code, out, err = run(capsys, *(a.format(m=PENDULUM) for a in args))
    assert (code, out, err) == (2, "", f"mbody: error: an empty name for {what}; give a file "
                                "name\n")


def test_animate_forces_need_the_runs_own_model(tmp_path, capsys):
    """A pendulum's run drawn with the slider-crank's loads was an IndexError (exit 70)."""
    import mbody

    run_file = tmp_path / "run.npz"
    mbody.simulate(mbody.load(PENDULUM), t_end=0.2, fps=20).save(run_file)
    code, out, err = run(capsys, "animate", run_file, "--forces", "--model",
                         MODELS / "slider_crank.yaml", "-o", tmp_path / "a.html")
    assert (code, out, err) == (2, "", f"mbody: error: the model 'slider-crank' has bodies the "
                                f"run {run_file} does not have (crank, piston): its forces and "
                                "reactions cannot be drawn on that run; give the model the run "
                                "was computed from\n")


def test_a_refused_set_leaves_no_import_option_to_the_next_command(tmp_path, capsys):
    # `--set` given twice is refused after the command read its --keyframe: the next
    # command of the same process (the test suite, a notebook) must not inherit it (a YAML
    # model converted was refused, its --keyframe taken for the last command's)
    code, _, err = run(capsys, "check", PENDULUM, "--keyframe", "swing", "--set",
                       "bodies.rod.mass=2", "--set", "bodies.rod.mass=2")
    assert code == 2 and "given twice" in err
    code, _, err = run(capsys, "convert", PENDULUM, "-o", tmp_path / "p.xml")
    assert code == 0, err

"""Bad input of every kind found by fuzzing (issue 11): one clear message and exit code 2,
never an internal error (70), a hang, a silent misreading or a half-written output.

One section per class of input; each asserts the whole message and the exit code.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.model import loader
from mbody.model.expressions import MAX_CHECK_SAMPLES, check_times
from mbody.simulate import simulation

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PLANAR = "dimension: 2\nbodies:\n  - name: a\n    mass: {mass}\n    inertia: {inertia}\n"


def run(capsys, *args) -> tuple[int, str, str]:
    """`mbody ARGS` in this process: (exit code, stdout, stderr)."""
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def check(tmp_path, capsys, text: str, name: str = "m.yaml") -> tuple[int, str]:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    code, _, err = run(capsys, "check", path)
    return code, err.replace(str(path), name)


def cli(*args, **kw) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    kw.setdefault("stdout", subprocess.PIPE)
    p = subprocess.run([sys.executable, "-m", "mbody", *map(str, args)], env=env,
                       stderr=subprocess.PIPE, text=True, timeout=120, **kw)
    assert "Traceback" not in p.stderr
    return p


# == YAML tags that do not fit their text; integers too long to convert =====================

@pytest.mark.parametrize(("mass", "message"), [
    ("!!float abc", "bodies[0].mass: the tag !!float does not fit: 'abc' is not a number "
     "(!!float takes a decimal number such as 1.5, -2e-3 or .inf)"),
    ("!!bool maybe", "bodies[0].mass: the tag !!bool does not fit: 'maybe' is not a boolean "
     "(!!bool takes true or false)"),
    ("!!int 1.5", "bodies[0].mass: the tag !!int does not fit: '1.5' is not an integer "
     "(!!int takes a decimal integer such as 42)"),
    ("!!null 3", "bodies[0].mass: the tag !!null does not fit: '3' is not null (!!null takes "
     "null, ~ or nothing)"),
])
def test_a_tag_that_does_not_fit_its_text(tmp_path, capsys, mass, message):
    code, err = check(tmp_path, capsys, PLANAR.format(mass=mass, inertia=1))
    assert (code, err) == (2, f"mbody: error: m.yaml:4:11: {message}\n")


@pytest.mark.parametrize("any_parser", ["libyaml", "python"])
def test_tags_that_fit_are_read(monkeypatch, any_parser):
    if any_parser == "python":
        monkeypatch.setattr(loader, "_Loader", loader.yaml.SafeLoader)
    data = loader.load_text("a: !!float 3\nb: !!int -4\nc: !!str 010\nd: !!bool false\n"
                            "e: !!null ~\nf: ! 12\n").data
    assert data == {"a": 3.0, "b": -4, "c": "010", "d": False, "e": None, "f": "12"}
    assert type(data["a"]) is float


@pytest.mark.parametrize(("digits", "shown"), [
    ("9" * 5000, "an integer of 5000 digits"),
    ("-" + "1" * 4301, "an integer of 4301 digits"),
    ("2" + "0" * 100, "2e+100"),
    ("1" + "0" * 101, "an integer of 102 digits"),
])
def test_integers_beyond_the_number_range(tmp_path, capsys, digits, shown):
    # reading time linear in the number of digits: tools/bench_reading_text.py, "integer
    # of n digits" (int() of a long text is quadratic; the reader counts digits first)
    code, err = check(tmp_path, capsys, PLANAR.format(mass=digits, inertia=1))
    assert (code, err) == (2, f"mbody: error: m.yaml:4:11: bodies[0].mass: expected a number "
                           f"of magnitude at most 1e+100, got {shown} (products of such "
                           "numbers (r x F, m r^2) would overflow)\n")


@pytest.mark.parametrize(("prefix", "digit", "kind"), [("0x", "F", "a hexadecimal"),
                                                       ("0b", "1", "a binary"),
                                                       ("0o", "7", "an octal")])
def test_long_integers_in_other_bases(tmp_path, capsys, prefix, digit, kind):
    code, err = check(tmp_path, capsys, PLANAR.format(mass=prefix + digit * 20000, inertia=1))
    shown = (prefix + digit * 40)[:37] + "..."
    assert (code, err) == (2, f"mbody: error: m.yaml:4:11: bodies[0].mass: '{shown}' is "
                           f"{kind} number; model files take decimal numbers (write it in "
                           "decimal, or quote it for text)\n")


# == finite but absurd numbers ===============================================================

@pytest.mark.parametrize(("mass", "inertia", "message"), [
    ("5e-324", "1", "m.yaml:4:11: bodies[0].mass: expected a magnitude of at least 1e-100, got "
     "5e-324 (masses and sizes are divided by; a smaller one would leave double precision)"),
    ("1", "5e-324", "m.yaml:5:14: bodies[0].inertia: a moment of inertia of 4.94e-324 kg m^2 is "
     "below 1e-100 (its inverse would leave double precision; give a realistic value)"),
    ("1", "2.2e-308", "m.yaml:5:14: bodies[0].inertia: a moment of inertia of 2.2e-308 kg m^2 "
     "is below 1e-100 (its inverse would leave double precision; give a realistic value)"),
    ("1e-400", "1", "m.yaml:4:11: bodies[0].mass: expected a number a double can hold, got "
     "1e-400 (below about 5e-324 it would be read as 0; write 0 if that is meant)"),
])
def test_denormal_and_underflowing_numbers(tmp_path, capsys, mass, inertia, message):
    code, err = check(tmp_path, capsys, PLANAR.format(mass=mass, inertia=inertia))
    assert (code, err) == (2, f"mbody: error: {message}\n")


def test_a_tiny_inertia_from_a_shape_is_refused_too(tmp_path, capsys):
    text = "dimension: 3\nbodies:\n  - {name: a, mass: 1e-60, shape: {sphere: {radius: 1e-30}}}\n"
    code, err = check(tmp_path, capsys, text)
    assert (code, err) == (2, "mbody: error: m.yaml:3:35: bodies[0].shape: a moment of inertia "
                           "of 4e-121 kg m^2 is below 1e-100 (its inverse would leave double "
                           "precision; give a realistic value)\n")


def test_tiny_values_that_are_never_divided_by_are_fine():
    model = mbody.loads("dimension: 2\nbodies: [{name: a, mass: 1, inertia: 1, "
                        "velocity: [1e-300, 5e-324], angular_velocity: 1e-200}]\n")
    assert model.initial.velocity[0, 1] == 5e-324
    assert mbody.assemble(model).solve().accelerations.tolist() == [0.0, 0.0, 0.0]


def test_denormal_spatial_inertia_never_reaches_the_solver(tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text("dimension: 3\nbodies:\n  - {name: a, mass: 1, inertia: [[5e-324, 0, 0], "
                    "[0, 1, 0], [0, 0, 1]]}\n")
    code, _, err = run(capsys, "solve", path)
    assert code == 2
    assert err == (f"mbody: error: {path}:3:33: bodies[0].inertia: a moment of inertia of "
                   "4.94e-324 kg m^2 is below 1e-100 (its inverse would leave double precision; "
                   "give a realistic value)\n")


@pytest.mark.parametrize(("angle", "message"), [
    ("1e400 deg", "expected a number of magnitude at most 1e+100, got 1e400 (products of such "
     "numbers (r x F, m r^2) would overflow)"),
    ("1e300", "expected a number of magnitude at most 1e+100, got 1e+300 (products of such "
     "numbers (r x F, m r^2) would overflow)"),
    ("1e99 deg", "expected an angle of at most 1e+09 rad in magnitude, got 1.74533e+97 rad (a "
     "double cannot resolve the pose of a larger angle; reduce it by whole turns)"),
    ("-2e9", "expected an angle of at most 1e+09 rad in magnitude, got -2e+09 rad (a double "
     "cannot resolve the pose of a larger angle; reduce it by whole turns)"),
])
def test_absurd_angles(tmp_path, capsys, angle, message):
    text = PLANAR.format(mass=1, inertia=1) + f"    angle: {angle}\n"
    code, err = check(tmp_path, capsys, text)
    assert (code, err) == (2, f"mbody: error: m.yaml:6:12: bodies[0].angle: {message}\n")


def test_absurd_euler_angle(tmp_path, capsys):
    text = ("dimension: 3\nbodies:\n  - {name: a, mass: 1, inertia: [1, 1, 1], "
            "orientation: {euler: [0, 1e400 deg, 0]}}\n")
    code, err = check(tmp_path, capsys, text)
    assert (code, err) == (2, "mbody: error: m.yaml:3:69: bodies[0].orientation.euler[1]: "
                           "expected a number of magnitude at most 1e+100, got 1e400 "
                           "(products of such numbers (r x F, m r^2) would overflow)\n")


def test_the_range_holds_for_dictionaries_too():
    with pytest.raises(mbody.ModelError) as err:
        mbody.load({"dimension": 2, "bodies": [{"name": "a", "mass": 10 ** 5000,
                                                "inertia": 5e-324}]})
    assert [i.message for i in err.value.issues] == [
        "expected a number of magnitude at most 1e+100, got an integer of about 5001 digits",
        "a moment of inertia of 4.94e-324 kg m^2 is below 1e-100"]
    with pytest.raises(mbody.ModelError) as err:
        mbody.load({"dimension": 2, "bodies": [{"name": "a", "mass": 1, "inertia": 5e-324}]})
    assert [i.message for i in err.value.issues] == [
        "a moment of inertia of 4.94e-324 kg m^2 is below 1e-100"]


# == YAML 1.1 forms: refused with both readings, or read as YAML 1.2 does ===================

@pytest.mark.parametrize(("mass", "message"), [
    ("010", "'010' has a leading zero: YAML 1.1 reads it as the octal number 8, YAML 1.2 as "
     "10 (write 10, without the leading zero, or quote it for text)"),
    ("09", "'09' has a leading zero: YAML 1.1 reads it as text, YAML 1.2 as 9 (write 9, "
     "without the leading zero, or quote it for text)"),
    ("1:20", "'1:20' is a base-60 number (80) in YAML 1.1 and text in YAML 1.2 (write 80 if "
     "that is meant, or quote it for text)"),
    ("0x1F", "'0x1F' is a hexadecimal number (31); model files take decimal numbers (write "
     "31, or quote it for text)"),
    ("0b101", "'0b101' is a binary number (5); model files take decimal numbers (write 5, or "
     "quote it for text)"),
    ("1_000", "'1_000' has underscores: YAML 1.1 reads it as the number 1000, YAML 1.2 as "
     "text (write 1000, or quote it for text)"),
])
def test_forms_yaml_1_1_reads_otherwise_are_refused(tmp_path, capsys, mass, message):
    code, err = check(tmp_path, capsys, PLANAR.format(mass=mass, inertia=1))
    assert (code, err) == (2, f"mbody: error: m.yaml:4:11: bodies[0].mass: {message}\n")


@pytest.mark.parametrize("word", ["on", "yes", "No", "OFF"])
def test_yes_no_on_off_are_text(tmp_path, capsys, word):
    code, err = check(tmp_path, capsys, PLANAR.format(mass=word, inertia=1))
    assert (code, err) == (2, f"mbody: error: m.yaml:4:11: bodies[0].mass: expected a number, "
                           f"got the text '{word}'\n")
    # ... and so a body may be called that, as the file says
    model = mbody.loads(f"dimension: 2\nbodies: [{{name: {word}, mass: 1, inertia: 1}}]\n")
    assert model.body_names == (word,)


def test_quoting_keeps_text_and_decimal_numbers_are_numbers():
    data = loader.load_text("a: '010'\nb: \"0x1F\"\nc: 10\nd: 1e3\ne: -.5\nf: 2001-12-14\n"
                            "g: =\nh: ~\n").data
    assert data == {"a": "010", "b": "0x1F", "c": 10, "d": 1000.0, "e": -0.5,
                    "f": "2001-12-14", "g": "=", "h": None}


# == tabs ======================================================================================

@pytest.mark.parametrize(("text", "where", "what"), [
    ("dimension: 2\nbodies:\n\t- {name: a, mass: 1, inertia: 1}\n", "3:1",
     "a tab in the indentation; YAML indents with spaces only"),
    ("dimension: 2\nbodies:\n  - name: a\n  \tmass: 1\n", "4:3",
     "a tab in the indentation; YAML indents with spaces only"),
])
def test_tab_indentation(tmp_path, capsys, text, where, what):
    code, err = check(tmp_path, capsys, text)
    assert (code, err) == (2, f"mbody: error: m.yaml:{where}: YAML syntax error: {what} "
                           "(replace tabs with spaces)\n")


def test_tab_after_a_value_is_fine_with_libyaml():
    if not hasattr(loader.yaml, "CSafeLoader"):  # pragma: no cover
        pytest.skip("PyYAML without libyaml")
    assert loader.load_text("a:\t1\n").data == {"a": 1}


# == outputs: a full device or a file-size limit ============================================

@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full")
@pytest.mark.parametrize("command", [["check"], ["solve"], ["solve", "--json"], ["assemble"]])
def test_stdout_on_a_full_device(command):
    with open("/dev/full", "w") as full:
        p = cli(command[0], MODELS / "slider_crank.yaml", *command[1:], stdout=full)
    assert p.returncode == 2
    assert p.stderr == ("mbody: error: cannot write to standard output: No space left on "
                        "device; the output is incomplete and was discarded\n")


def _limited(max_bytes: int):
    """A subprocess preexec_fn: files may grow to `max_bytes` at most (EFBIG beyond)."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (max_bytes, max_bytes))
    return limit


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_FSIZE semantics")
def test_stdout_to_a_file_that_cannot_grow_leaves_the_file_as_it_was(tmp_path):
    out = tmp_path / "out.txt"
    out.write_text("kept\n")
    with open(out, "a") as fh:
        p = cli("assemble", MODELS / "triple_pendulum.yaml", stdout=fh,
                preexec_fn=_limited(2048))
    assert p.returncode == 2
    assert p.stderr == ("mbody: error: cannot write to standard output: File too large; the "
                        "output is incomplete and was discarded\n")
    assert out.read_text() == "kept\n"  # cut back to where mbody started writing


@pytest.fixture(scope="module")
def pendulum_run(tmp_path_factory) -> Path:
    """A short run of the pendulum saved as a run file."""
    path = tmp_path_factory.mktemp("run") / "pendulum.npz"
    mbody.simulate(mbody.load(MODELS / "pendulum.yaml"), t_end=1.0).save(path)
    return path


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_FSIZE semantics")
@pytest.mark.parametrize(("command", "name"), [
    (["simulate", MODELS / "triple_pendulum.yaml", "--t-end", "2", "-o"], "run.npz"),
    (["export", MODELS / "triple_pendulum.yaml", "-o"], "eqs.json"),
    (["report", MODELS / "triple_pendulum.yaml", "-o"], "page.html"),
    (["fbd", MODELS / "seed_example_1.yaml", "--image-format", "svg", "-o"], "pictures"),
    (["plot", "{run}", "-o"], "p.pdf"),
])
def test_a_file_that_cannot_be_written_leaves_nothing(tmp_path, command, name, pendulum_run):
    target = tmp_path / name
    command = [pendulum_run if c == "{run}" else c for c in command]
    p = cli(*command, target, cwd=tmp_path, preexec_fn=_limited(4096))
    assert p.returncode == 2, p.stderr
    temporary = "folder" if name == "pictures" else "file"
    assert p.stderr == (f"mbody: error: cannot write {str(target)!r}: File too large; nothing "
                        f"was written (the temporary {temporary} is removed, and {name!r} is "
                        "as it was)\n")
    left = [f.name for f in tmp_path.rglob("*")]
    assert left == []  # no file, and no folder made for the output either


def test_write_errors_from_python_are_model_free_messages(tmp_path, monkeypatch):
    import errno

    from mbody.util.atomic import write_atomic

    target = tmp_path / "x.txt"
    target.write_text("old")

    def full(fh):
        fh.write(b"new")
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(mbody.MbodyError) as err:
        write_atomic(target, full)
    assert str(err.value) == (f"cannot write {str(target)!r}: No space left on device; nothing "
                              "was written (the temporary file is removed, and 'x.txt' is as "
                              "it was)")
    assert target.read_text() == "old" and [f.name for f in tmp_path.iterdir()] == ["x.txt"]
    # ... and still an OSError, for code that catches those
    assert isinstance(err.value, OSError) and err.value.errno == errno.ENOSPC
    assert err.value.filename == str(target)


# == files that are not files ====================================================================

@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes")
def test_a_named_pipe_without_a_writer_is_refused_quickly(tmp_path, capsys, monkeypatch):
    """The wait for a writer is bounded: every wait the reader makes has a timeout, and
    together they last FIFO_WAIT. (The time to the refusal against FIFO_WAIT is measured
    by tools/bench_reading.py, "refusals".)"""
    monkeypatch.setattr(loader, "FIFO_WAIT", 0.2)
    waits: list[float | None] = []
    real_wait = loader._wait_readable

    def wait(fd: int, timeout: float | None) -> None:
        waits.append(timeout)
        real_wait(fd, timeout)

    monkeypatch.setattr(loader, "_wait_readable", wait)
    fifo = tmp_path / "m.yaml"
    os.mkfifo(fifo)
    code, _, err = run(capsys, "check", fifo)
    assert (code, err) == (2, f"mbody: error: {fifo}: nothing came through this pipe in 0.2 s "
                           "(no writer, or an empty one); start the writer first, or give a "
                           "model file\n")
    assert waits and None not in waits  # never a wait without an end
    assert all(0 < w <= 0.02 for w in waits) and sum(waits) <= 0.2 + 0.02


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes")
def test_a_named_pipe_whose_writer_comes_late_is_read(tmp_path):
    fifo = tmp_path / "m.yaml"
    os.mkfifo(fifo)
    writer = subprocess.Popen(f"sleep 0.3; cat {MODELS / 'pendulum.yaml'} > {fifo}",
                              shell=True)
    try:
        assert mbody.load(fifo).body_names == ("rod",)
    finally:
        writer.wait(timeout=10)


def test_stdin_pipe_and_redirect_are_read():
    text = (MODELS / "seed_example_1.yaml").read_text()
    p = cli("check", "/dev/stdin", input=text)
    assert p.returncode == 0 and p.stdout.endswith("OK: /dev/stdin is a valid model.\n")
    with open(MODELS / "seed_example_1.yaml") as fh:
        p = cli("check", "/dev/stdin", stdin=fh)
    assert p.returncode == 0


@pytest.mark.skipif(not Path("/dev/null").exists(), reason="no /dev/null")
def test_devices_are_refused_unread(capsys):
    code, _, err = run(capsys, "check", "/dev/null")
    assert (code, err) == (2, "mbody: error: /dev/null: this is a character device (a "
                           "terminal, /dev/null...), not a file; expected a YAML model file (to "
                           "read a model from a pipe: mbody check /dev/stdin < model.yaml)\n")


# == simulations too costly to finish: predicted early, with how to go on ===================

_EARLY = (r"mbody: error: the simulation was stopped early: after 1000 steps it is at "
          r"t = \S+ s of 10 s \(\S+ steps per simulated second so far\); at that rate the "
          r"whole run needs about \S+ steps, more than 1\.5 times the budget "
          r"\(--max-steps 1000000\)\. ")


def test_stiff_inertia_is_stopped_early_and_says_why(tmp_path, capsys):
    path = tmp_path / "needle.yaml"
    path.write_text("dimension: 3\ngravity: [0, 0, -9.81]\nbodies:\n  - {name: needle, "
                    "mass: 1, inertia: [1e-12, 1e12, 1e12], angular_velocity: [1, 1, 1]}\n")
    code, out, err = run(capsys, "simulate", path, "--no-progress")
    assert code == 2 and out == ""  # the work is bounded: "after 1000 steps", below
    assert re.fullmatch(
        _EARLY + r"The body 'needle' has principal moments of inertia from 1e-12 to 1e\+12 "
        r"kg m\^2 \(a ratio of 1e\+24\): its Euler equation divides the rounding errors of the "
        r"large moments by the small one, and the steps shrink to follow that noise; no "
        r"integrator steps over it\. To go on: a realistic smallest moment \(a thin rod's "
        r"m r\^2 / 2 with its real radius\), a shorter --t-end, or raise --max-steps\. No "
        r"trajectory is kept \(rerun with --t-end \S+ to see the motion up to here\)\.\n", err)


def test_fast_spin_is_stopped_early_and_says_why(tmp_path, capsys):
    path = tmp_path / "spin.yaml"
    path.write_text("dimension: 3\nbodies:\n  - {name: rotor, mass: 1, inertia: [1, 2, 2.5], "
                    "angular_velocity: [1e6, 1, 1]}\n")
    code, out, err = run(capsys, "simulate", path, "--no-progress")
    assert code == 2 and out == ""
    assert re.fullmatch(
        _EARLY + r"The steps follow the fastest motion: 'rotor' spins at 1e\+06 rad/s "
        r"\(1\.59e\+05 rev/s\), and any integrator must take steps shorter than a turn, so a "
        r"stiff integrator would not help\. To go on: a shorter --t-end \(the cost grows with "
        r"it\), a looser --rtol \(e\.g\. 1e-6\), a slower spin, or raise --max-steps\. No "
        r"trajectory is kept \(rerun with --t-end \S+ to see the motion up to here\)\.\n", err)


STIFF_SPRING = """\
dimension: 2
bodies:
  - {name: a, mass: 1, inertia: 1, position: [1.1, 0]}
loads:
  - {name: k, type: spring, bodies: [ground, a], at: [[0, 0], [0, 0]], stiffness: 1e9,
     damping: 1e6, rest_length: 1}
"""


def test_stiff_spring_is_stopped_early_and_a_stiff_integrator_finishes_it(tmp_path, capsys):
    path = tmp_path / "spring.yaml"
    path.write_text(STIFF_SPRING)
    code, out, err = run(capsys, "simulate", path, "--no-progress")
    assert code == 2 and out == ""
    assert re.fullmatch(
        _EARLY + r"That is far more steps than the motion explains \(the fastest spin at the "
        r"start: none\): the model is stiff \(time scales far apart, such as a very stiff "
        r"spring on a light body\), and an explicit integrator must resolve the fastest of "
        r"them\. To go on: a stiff integrator \(--method LSODA, BDF or Radau\), a shorter "
        r"--t-end, or raise --max-steps\. No trajectory is kept \(rerun with --t-end \S+ to "
        r"see the motion up to here\)\.\n", err)
    traj = mbody.simulate(mbody.load(path), t_end=10.0, method="BDF")
    assert traj.info["steps"] < 5000 and abs(traj.position[-1, 0, 0] - 1.0) < 1e-6


def test_a_long_smooth_run_is_stopped_early_as_long_not_stiff(capsys):
    """A pendulum at rest takes 16 steps a simulated second: a run of 1e5 s needs 1.6
    million steps, over the budget, and the reason given is its length, not stiffness."""
    code, out, err = run(capsys, "simulate", MODELS / "pendulum.yaml", "--t-end", "1e5",
                         "--no-progress")
    assert code == 2 and out == ""
    assert "the run is long, and its cost grows with --t-end; a stiff integrator would " \
        "not help. To go on: a shorter --t-end, a looser --rtol (e.g. 1e-6), or raise " \
        "--max-steps." in err
    assert "stiff (time scales" not in err


def test_an_implicit_method_whose_jacobian_breaks_down_says_what_to_try(tmp_path, capsys):
    path = tmp_path / "spring.yaml"
    path.write_text(STIFF_SPRING)
    code, out, err = run(capsys, "simulate", path, "--no-progress", "--method", "Radau",
                         "--rtol", "1e-8")
    assert code == 2 and out == ""
    assert re.fullmatch(
        r"mbody: error: the integrator Radau failed at t = \S+ s: array must not contain "
        r"infs or NaNs \(its numerical Jacobian broke down, as it can where the state barely "
        r"changes\)\. Try another stiff integrator \(--method LSODA or BDF\) or looser "
        r"tolerances \(e\.g\. --rtol 1e-6 --atol 1e-9\)\n", err)


@pytest.mark.parametrize("method", ["Radau", "BDF", "LSODA"])
def test_implicit_methods_run(method):
    traj = mbody.simulate(mbody.load(MODELS / "torque_free_asymmetric.yaml"), t_end=1.0,
                          method=method, rtol=1e-8)
    assert traj.info["integrator"] == method and traj.info["energy_drift"] < 1e-6


# == expressions of t over the simulated span ================================================

SINGULAR = ("dimension: 2\nbodies: [{name: p, mass: 1, inertia: 1}]\n"
            "loads: [{name: push, type: force, body: p, force: [\"{expr}\", 0]}]\n")


def test_check_warns_about_an_expression_not_finite_within_ten_seconds(tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text(SINGULAR.replace("{expr}", "1/(t-1)"))
    code, out, err = run(capsys, "check", path)
    assert code == 0 and err == ""
    assert (f"warning: {path}:3:52: loads[0].force[0]: the expression \"1/(t-1)\" is not "
            "finite at t = 1 s (inf); a simulation cannot go past that time (sampled every "
            "millisecond from 0 to 10 s, simulate's default span)\n") in out


@pytest.mark.parametrize(("expr", "where"), [("1/(t-1)", "1 s (inf)"),
                                             ("sqrt(2.5-t)", "2.501 s (nan)"),
                                             ("exp(100*t)", "7.098 s (inf)")])
def test_simulate_refuses_a_span_where_an_expression_is_not_finite(tmp_path, capsys,
                                                                   monkeypatch, expr, where):
    """Refused before any integration step, after a bounded number of samples."""
    started = []
    real_start = simulation.start

    def start(*args, **kw):
        started.append(args[0])
        return real_start(*args, **kw)

    monkeypatch.setattr(simulation, "start", start)
    path = tmp_path / "m.yaml"
    path.write_text(SINGULAR.replace("{expr}", expr))
    code, out, err = run(capsys, "simulate", path, "--no-progress")
    assert code == 2 and out == "" and started == []
    at = where.split(" s")[0]
    assert err.endswith(f"mbody: error: the load 'push' (force x on p) = \"{expr}\" is not "
                        f"finite at t = {where}, within the simulated span 0 .. 10 s: the "
                        "integration could not go past it. Change the expression, or simulate "
                        f"a shorter span (--t-end below {at}).\n")
    # a span that stops short of it is fine
    assert run(capsys, "simulate", path, "--no-progress", "--t-end", "0.9")[0] == 0
    assert len(started) == 1


def test_a_span_is_checked_again_at_each_run_until_it_passes():
    """The check's result is kept per model and t_end (a span that passed is not sampled
    again), so a span that failed must fail at every run, and a shorter one pass."""
    model = mbody.loads(SINGULAR.replace("{expr}", "1/(t-1)"))
    for _ in range(2):
        with pytest.raises(mbody.MbodyError, match="is not finite at t = 1 s"):
            mbody.simulate(model, 2.0, 10)
    for _ in range(2):
        assert len(mbody.simulate(model, 0.5, 10)) == 6
    with pytest.raises(mbody.MbodyError, match="is not finite at t = 1 s"):
        mbody.simulate(model, 2.0, 10)


@pytest.mark.parametrize("t_end", [1e-9, 0.001, 10.0, 1234.5, 1e9])
def test_the_check_of_expressions_samples_a_bounded_number_of_times(t_end):
    """Every millisecond up to MAX_CHECK_SAMPLES points, then coarser: the check before a
    simulation costs the same for a span of a billion seconds as for 100 s."""
    t = check_times(t_end)
    assert 2 <= len(t) <= MAX_CHECK_SAMPLES and t[0] == 0 and t[-1] == t_end
    assert (np.diff(t) > 0).all()
    if t_end <= 100:
        assert np.diff(t).max() <= 0.001 * (1 + 1e-9)


def test_a_known_reaction_given_to_simulate_is_checked_too():
    model = mbody.load(MODELS / "rotor_gyroscopic_bearings.yaml")
    with pytest.raises(mbody.MbodyError) as err:
        mbody.simulate(model, t_end=1.0, known={"fork.Fx": "log(0.5-t)"})
    assert str(err.value) == ("the known reaction fork.Fx = \"log(0.5-t)\" is not finite at "
                              "t = 0.5 s (-inf), within the simulated span 0 .. 1 s: the "
                              "integration could not go past it. Change the expression, or "
                              "simulate a shorter span (t_end below 0.5).")


def test_a_singularity_between_samples_is_named_when_the_run_stops(tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text(SINGULAR.replace("{expr}", "1/(t-pi)"))
    code, out, err = run(capsys, "simulate", path, "--no-progress")
    assert code == 2 and out == ""
    assert re.fullmatch(r"mbody: error: the integration stopped at t = 3\.14159 s: the load "
                        r"'push' \(force x on p\) = \"1/\(t-pi\)\" grows without bound near "
                        r"t = 3\.14159265 s \(\|value\| \S+, \S+ times its largest before\): "
                        r"change the expression, or simulate to before that time\n", err)


# == characters YAML does not allow; numbers inside expressions ==============================

@pytest.mark.parametrize(("text", "where", "what"), [
    ("dimension: 2\nmodel: a\x00b\n", "2:9", "the character U+0000"),
    ("dimension: 2\nmodel: \x1b[31mred\n", "2:8", "the character U+001B"),
])
def test_characters_yaml_does_not_allow(tmp_path, capsys, text, where, what):
    code, err = check(tmp_path, capsys, text)
    assert (code, err) == (2, f"mbody: error: m.yaml:{where}: {what} is not allowed in a YAML "
                           "file (remove it; inside double quotes a control character may be "
                           "written escaped, such as \\t)\n")


@pytest.mark.parametrize(("expr", "message"), [
    ("1e-400*t", "the number 1e-400 is below the smallest double at character 1 (marked |): "
     "\"|1e-400*t\" (it would be read as 0; write 0 if that is meant)"),
    ("2*1e400", "the number 1e400 is out of range at character 3 (marked |): \"2*|1e400\" "
     "(at most 1e+100, as everywhere in a model)"),
])
def test_numbers_in_expressions_keep_the_range(tmp_path, capsys, expr, message):
    code, err = check(tmp_path, capsys, SINGULAR.replace("{expr}", expr))
    assert (code, err) == (2, f"mbody: error: m.yaml:3:52: loads[0].force[0]: invalid "
                           f"expression: {message}\n")


# == what a newcomer types where a number goes ===============================================

@pytest.mark.parametrize(("line", "message"), [
    ("    mass: 1,5\n", "m.yaml:6:11: bodies[0].mass: expected a number, got the text '1,5' "
     "(a decimal comma? write 1.5)"),
    ("    mass: 1.5 kg\n", "m.yaml:6:11: bodies[0].mass: expected a number, got the text "
     "'1.5 kg' (numbers are in SI units, written without the unit: 1.5)"),
    ("    mass: 500 g\n", "m.yaml:6:11: bodies[0].mass: expected a number, got the text "
     "'500 g' (numbers are in SI units, written without the unit: 500 g is 0.5 kg)"),
    # '60 rpm' is read since a body's rate takes a driver's units (review R7-13); a unit
    # with a prefix is not, and says what it is
    ("    angular_velocity: 0.06 krpm\n", "m.yaml:6:23: bodies[0].angular_velocity: expected "
     "a number (radians/s) or a string like '30 deg/s' or '100 rpm', got '0.06 krpm' (0.06 "
     "krpm is 60 rpm)"),
    ("    mass: 3 stone\n", "m.yaml:6:11: bodies[0].mass: expected a number, got the text "
     "'3 stone' (numbers are in SI units (kg, m, s, N, rad), written without the unit: "
     "convert '3 stone' to SI first)"),
    ("    angle: 30°\n", "m.yaml:6:12: bodies[0].angle: expected a number (radians) or a string "
     "like '30 deg', got '30°' (write '30 deg')"),
    ("    angle: 30 degrees\n", "m.yaml:6:12: bodies[0].angle: expected a number (radians) or "
     "a string like '30 deg', got '30 degrees' (write '30 deg')"),
    ("    angular_velocity: 90 degrees/s\n", "m.yaml:6:23: bodies[0].angular_velocity: "
     "expected a number (radians/s) or a string like '30 deg/s' or '100 rpm', got '90 "
     "degrees/s' (write '90 deg/s')"),
])
def test_units_and_decimal_commas_get_a_did_you_mean(tmp_path, capsys, line, message):
    text = ("dimension: 2\nbodies:\n  - name: a\n    inertia: 1\n"
            + ("    position: [0, 0]\n" if "mass" in line else "    mass: 1\n") + line)
    code, err = check(tmp_path, capsys, text)
    assert (code, err) == (2, f"mbody: error: {message}\n")


@pytest.mark.parametrize(("typ", "name"), [("hinge", "revolute"), ("slide", "prismatic"),
                                          ("weld", "fixed")])
def test_another_programs_joint_type_names_mbodys(tmp_path, capsys, typ, name):
    """MuJoCo's and URDF's names are not close in spelling to mbody's: say which is meant."""
    text = ("dimension: 2\nbodies: [{name: a, mass: 1, inertia: 1}]\n"
            f"joints: [{{name: O, type: {typ}, parent: ground, child: a, at: [0, 0]}}]\n")
    code, err = check(tmp_path, capsys, text)
    assert (code, err) == (2, f"mbody: error: m.yaml:3:26: joints[0].type: unknown planar "
                              f"joint type '{typ}' (mbody calls it '{name}')\n")


def test_a_file_of_millions_of_values_is_refused_early(tmp_path, capsys):
    text = ("dimension: 2\nbodies: [{name: a, mass: 1, inertia: 1}]\ngravity: ["
            + ", ".join(["0"] * 1_100_000) + "]\n")
    code, err = check(tmp_path, capsys, text)
    # refused at the first value past the limit, not after reading them all: 14 nodes come
    # before the list's first 0 (the document's mapping, 'dimension' and 2, 'bodies', its
    # list, the body's mapping and its 6 keys and values, 'gravity', its list), so the
    # refused node is the 0 of index 1 000 001 - 14 - 1, at column 11 + 3 per 0 before it.
    # Reading time linear in the number of values: tools/bench_reading_text.py, "a list of
    # n values".
    assert code == 2 and err.startswith(f"mbody: error: m.yaml:3:{11 + 3 * 999_986}: ")
    assert err.endswith(": the file holds more than 1 000 000 values (keys, numbers, lists...), "
                        "the most that is read (a 10 000-body model holds about 650 000)\n")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes")
@pytest.mark.parametrize(("args", "what"), [
    (["plot", "{fifo}", "-o", "{tmp}/x.png"], "a run file written by 'mbody simulate -o "
     "RUN.npz'"),
    (["animate", "{fifo}", "-o", "{tmp}/x.html"], "a model (.yaml) or a run file (.npz)"),
    (["export", str(MODELS / "pendulum.yaml"), "--state", "{fifo}", "-o", "{tmp}/e.json"],
     "a run file written by 'mbody simulate -o RUN.npz'"),
])
def test_run_files_that_are_pipes_are_refused_unopened(tmp_path, capsys, args, what):
    fifo = tmp_path / "run.npz"
    os.mkfifo(fifo)
    code, _, err = run(capsys, *(a.format(fifo=fifo, tmp=tmp_path) for a in args))
    assert (code, err) == (2, f"mbody: error: {fifo}: this is a named pipe, not a file; "
                           f"expected {what}\n")

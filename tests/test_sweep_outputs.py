"""What a sweep writes (issue 27): never onto its own input, and never rows of other
settings mixed with this sweep's.

- The results (``--out``) and their journal beside them (``<out>.partial``) are never the
  model file, however named (a symbolic link, a hard link, another spelling of the path):
  refused by the command (exit 2, one line) and by `mbody.run_sweep` (an `MbodyError`)
  with the same message, even with --force (a rerun reads both back to resume), before
  anything is read or written. A journal that is a named pipe or a device, an output that
  is a folder, are refused before any case runs; an output that is a named pipe is
  written through, never read.
- Each row records the settings it was computed with (its ``settings`` cell: the run,
  those of its settings that change its numbers, the model's digest). A rerun into the
  same output reuses a row only when its record is this sweep's; otherwise the output is
  refused, naming the setting that differs and both values, and with --force those cases
  run again: the rows are then those of a fresh sweep with the new settings. A file of an
  mbody that did not record the settings is refused with a message that says so.
"""

from __future__ import annotations

import contextlib
import csv
import errno
import math
import os
import re
import threading
from pathlib import Path

import pytest

import mbody
from mbody.cli import main
from mbody.errors import MbodyError, OutputError, options_named
from mbody.sweep import cluster
from mbody.sweep.record import differences, parse, record
from mbody.sweep.runs import Settings
from mbody.sweep.study import SweepInterrupted
from tests.test_sweep import driven_text, floats, read

ROOT = Path(__file__).resolve().parent.parent
PENDULUM = ROOT / "models" / "pendulum.yaml"
MASSES = ["bodies.rod.mass=0.4:0.8:2"]
RESUMED = "is read back to resume the run, which needs the model as it was; give another " \
          "output file"


def command(capsys, *args: str | Path) -> tuple[int, str, str]:
    """`mbody sweep ...` in this process, its cases here too: (exit code, stdout, stderr)."""
    code = main(["sweep", *map(str, args), "--workers", "0", "--quiet"])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


@pytest.fixture
def driven(tmp_path, monkeypatch) -> Path:
    """The slider-crank without loads, driven at 100 rad/s, as d.yaml in the test's folder
    (the current folder)."""
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "d.yaml"
    path.write_text(driven_text())
    return path


def files_of(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}


# == the output is never the model ==========================================================

def _link(tmp: Path, model: Path) -> tuple[str, str]:
    (tmp / "link.csv").symlink_to(model.name)
    return model.name, "link.csv"


def _hard_link(tmp: Path, model: Path) -> tuple[str, str]:
    os.link(model, tmp / "hard.csv")
    return model.name, "hard.csv"


def _spelling(tmp: Path, model: Path) -> tuple[str, str]:
    model.rename(tmp / "m.csv")  # a YAML model whose name ends in .csv
    return "m.csv", "./m.csv"


def _folder_spelling(tmp: Path, model: Path) -> tuple[str, str]:
    (tmp / "sub").mkdir()
    model.rename(tmp / "m.csv")
    return "m.csv", "sub/../m.csv"


@pytest.mark.parametrize("how", [_link, _hard_link, _spelling, _folder_spelling],
                         ids=["symbolic link", "hard link", "./x and x", "sub/../x and x"])
def test_an_output_that_is_the_model_is_refused(driven, capsys, how):
    """The command (with --force too) and run_sweep (given the file or the model read
    from it): the same message, naming the output, the model and that they are one
    file; nothing read into, nothing written."""
    model, out = how(driven.parent, driven)
    same = "" if out == model else ", the same file"
    said = f"--out {out} is the model itself ({model}{same}): --out {RESUMED}"
    before = files_of(driven.parent)
    for force in ((), ("--force",)):
        code, stdout, err = command(capsys, model, "--set", MASSES[0], "--out", out, *force)
        assert (code, stdout, err) == (2, "", f"mbody: error: {said}\n")
    for given in (model, mbody.load(model)):
        for force in (False, True):
            with pytest.raises(MbodyError) as refused:
                mbody.run_sweep(given, MASSES, out, workers=0, force=force)
            assert str(refused.value) == said
    assert files_of(driven.parent) == before  # the model as it was, nothing new


def test_a_journal_that_is_the_model_is_refused(driven, capsys):
    """The journal beside --out (<out>.partial) is appended to as cases finish: a model
    of that name would gain rows. Refused before any case runs, however it is named."""
    driven.rename("r.csv.partial")
    said = (f"--out's journal r.csv.partial is the model itself (r.csv.partial): --out's "
            f"journal {RESUMED}")
    before = files_of(driven.parent)
    code, stdout, err = command(capsys, "r.csv.partial", "--set", MASSES[0], "--out", "r.csv")
    assert (code, stdout, err) == (2, "", f"mbody: error: {said}\n")
    with pytest.raises(MbodyError) as refused:
        mbody.run_sweep("r.csv.partial", MASSES, "r.csv", workers=0, force=True)
    assert str(refused.value) == said
    # a journal that is a link to the model
    Path("r.csv.partial").rename("m.yaml")
    Path("x.csv.partial").symlink_to("m.yaml")
    with pytest.raises(MbodyError) as refused:
        mbody.run_sweep(mbody.load("m.yaml"), MASSES, "x.csv", workers=0)
    assert str(refused.value) == (f"--out's journal x.csv.partial is the model itself (m.yaml, "
                                  f"the same file): --out's journal {RESUMED}")
    assert Path("m.yaml").read_bytes() == before["r.csv.partial"]
    assert not Path("r.csv").exists() and not Path("x.csv").exists()


def test_a_journal_that_is_the_output_is_refused(driven):
    mbody.run_sweep(driven, MASSES, "r.csv", workers=0)
    results = Path("r.csv").read_bytes()
    Path("r.csv.partial").symlink_to("r.csv")
    with pytest.raises(MbodyError) as refused:
        mbody.run_sweep(driven, MASSES, "r.csv", workers=0)
    assert str(refused.value) == (
        "--out's journal r.csv.partial is the output itself (r.csv, the same file): --out's "
        "journal is read back to resume the run, which needs the output as it was; give "
        "another output file")
    assert Path("r.csv").read_bytes() == results


def test_a_model_without_a_file_has_nothing_to_refuse(driven):
    """A model from text named after a file that is the output (tests/test_sweep.py makes
    such models): its name is only a name, but the file is not replaced either way."""
    model = mbody.loads(driven_text(), "d.yaml")
    result = mbody.run_sweep(model, MASSES, "r.csv", workers=0)
    assert result.ran == 2 and driven.read_text() == driven_text()


# == special files ============================================================================

def test_an_output_that_is_a_folder_is_refused_before_any_case_runs(driven, capsys,
                                                                     monkeypatch):
    def no_case(*args, **kwargs):
        raise AssertionError("a case ran")

    monkeypatch.setattr(cluster, "run_chunk", no_case)
    Path("d.csv").mkdir()
    code, _, err = command(capsys, driven, "--set", MASSES[0], "--out", "d.csv")
    assert (code, err) == (2, "mbody: error: cannot write 'd.csv': it is a folder; give a "
                              "file name\n")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_journal_that_is_a_named_pipe_is_refused(driven, capsys):
    """Reading it to resume would wait for a writer forever (the command hung)."""
    os.mkfifo("g.csv.partial")
    code, _, err = command(capsys, driven, "--set", MASSES[0], "--out", "g.csv")
    assert (code, err) == (2, "mbody: error: cannot write 'g.csv.partial': it is a named "
                              "pipe, and the journal beside --out must be a regular file; "
                              "remove it or give another output\n")
    assert not Path("g.csv").exists()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_an_output_that_is_a_named_pipe_is_written_through_never_read(driven):
    """The results go to the pipe's reader (the command hung reading the pipe to resume);
    the journal beside it is a regular file, removed at the end."""
    os.mkfifo("f.csv")
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(Path("f.csv").read_bytes()))
    reader.start()
    result = mbody.run_sweep(driven, MASSES, "f.csv", workers=0)
    reader.join(timeout=60)
    assert not reader.is_alive()
    text = got[0].decode()
    assert list(csv.reader(text.splitlines())) == [result.header, *result.rows]
    assert not Path("f.csv.partial").exists()


def test_an_output_in_a_new_folder(driven):
    """The journal's folder is made as the output's is (it had failed: 'No such file or
    directory' for the journal, after the first cases had run)."""
    result = mbody.run_sweep(driven, MASSES, "new/dir/r.csv", workers=0)
    assert read(Path("new/dir/r.csv")) == (result.header, result.rows)
    assert sorted(p.name for p in Path("new/dir").iterdir()) == ["r.csv"]


def _failing(monkeypatch, errno_: int, what: str) -> None:
    """`Path.mkdir` (what == "mkdir") or the journal's opening fails with `errno_`, as on a
    file system that refuses (/proc lets root through os.access, then refuses mkdir)."""
    if what == "mkdir":
        def mkdir(self, *args, **kwargs):
            raise OSError(errno_, os.strerror(errno_), str(self))

        monkeypatch.setattr(Path, "mkdir", mkdir)
        return
    real = open

    def opening(file, *args, **kwargs):
        if str(file).endswith(".partial"):
            raise OSError(errno_, os.strerror(errno_), str(file))
        return real(file, *args, **kwargs)

    monkeypatch.setattr("builtins.open", opening)


@pytest.mark.parametrize(("what", "said"), [
    ("mkdir", "cannot write 'new/r.csv': cannot make the folder 'new' (No space left on "
              "device)"),
    ("open", "cannot write 'new/r.csv.partial', the journal beside the output new/r.csv: "
             "No space left on device"),
])
def test_an_output_whose_folder_or_journal_cannot_be_written(driven, capsys, monkeypatch,
                                                               what, said):
    """B4 of review R3: a folder that cannot be made was a FileNotFoundError naming the
    journal from run_sweep (and the command's message named the journal alone). Now the
    output --out is named, in the words every command uses for its output, as an
    OutputError (an MbodyError and an OSError) from Python and exit 2 from the command."""
    if what == "open":
        Path("new").mkdir()
    _failing(monkeypatch, errno.ENOSPC, what)
    with pytest.raises(OutputError) as refused:
        mbody.run_sweep(driven, MASSES, "new/r.csv", workers=0)
    assert str(refused.value) == said and refused.value.errno == errno.ENOSPC
    code, _, err = command(capsys, driven, "--set", MASSES[0], "--out", "new/r.csv")
    assert (code, err) == (2, f"mbody: error: {said}\n")
    assert not Path("new/r.csv").exists()


# == the settings each row was computed with ==================================================

def test_each_row_records_its_settings(driven):
    """The record: the run, those of its settings that change its numbers (a setting the
    run does not use is not recorded), the model's digest."""
    model = mbody.load(driven)
    digest = r"model=sha256:[0-9a-f]{16}"
    cases = [
        (Settings("solve"), "run=solve"),
        (Settings("solve", steps=7, fps=1.0), "run=solve"),
        (Settings("kinematics", revolutions=1.0, steps=360),
         "run=kinematics; t-end=1 rev; steps=360"),
        (Settings("kinematics", t_end=0.1, steps=11), "run=kinematics; t-end=0.1; steps=11"),
        # no --steps: mbody kinematics' sampling, one a degree of the crank's steady turn
        (Settings("kinematics", t_end=0.1), "run=kinematics; t-end=0.1; steps=360 a turn"),
        (Settings("simulate", t_end=2.5, fps=60.0), "run=simulate; t-end=2.5; fps=60"),
        (Settings("modes"), "run=modes; equilibrium=no"),
        (Settings("modes", equilibrium=True, steps=3), "run=modes; equilibrium=yes"),
    ]
    for settings, want in cases:
        assert re.fullmatch(f"{re.escape(want)}; {digest}", record(settings, model)), settings
    result = mbody.run_sweep(driven, MASSES, "k.csv", run="kinematics", t_end=0.05,
                             steps=11, workers=0)
    assert result.header[-2:] == ["error", "settings"]
    assert result.settings == record(Settings("kinematics", t_end=0.05, steps=11), model)
    assert [r[-1] for r in result.rows] == [result.settings] * 2
    assert parse(result.settings)["t-end"] == "0.05"


SWEEP_FLAGS = {"run": "--run", "t_end": "--t-end", "revolutions": "--t-end",
               "steps": "--steps", "fps": "--fps", "equilibrium": "--equilibrium"}
"""The flags `mbody sweep` names its settings by (as `mbody.cli.app.option_flags` gives
them; the command's own wording is checked end to end below)."""


@pytest.mark.parametrize("surface", ["command line", "Python"])
def test_the_differences_are_named(surface):
    """As the caller names each setting: the command's flags, run_sweep's keywords (before,
    the flags from Python too: '--steps 11', where run_sweep takes steps=11)."""
    a = "run=kinematics; t-end=0.1; steps=11; model=sha256:0123456789abcdef"
    cli = surface == "command line"
    with options_named(SWEEP_FLAGS) if cli else contextlib.nullcontext():
        assert differences(a, a) == []
        assert differences(a, a.replace("0.1", "0.2").replace("=11", "=21")) == (
            ["--t-end 0.1 (this sweep: 0.2)", "--steps 11 (this sweep: 21)"] if cli else
            ["t_end=0.1 (this sweep: t_end=0.2)", "steps=11 (this sweep: steps=21)"])
        assert differences(a, a.replace("t-end=0.1", "t-end=1 rev")) == (
            ["--t-end 0.1 (this sweep: 1 rev)"] if cli else
            ["t_end=0.1 (this sweep: revolutions=1)"])
        assert differences(a, "run=simulate; t-end=0.1; fps=60; model=sha256:0123456789abcdef"
                           ) == (["--run kinematics (this sweep: simulate)"] if cli else
                                 ["run='kinematics' (this sweep: run='simulate')"])
        # the default sampling changed from 101 instants: such rows are another sweep's
        assert differences(a.replace("=11", "=101"), a.replace("=11", "=360 a turn")) == (
            ["--steps 101 (this sweep: 360 a turn)"] if cli else
            ["steps=101 (this sweep: steps=None (360 a turn))"])
        modes = "run=modes; equilibrium=no; model=sha256:0123456789abcdef"
        assert differences(modes, modes.replace("=no", "=yes")) == (
            ["--equilibrium no (this sweep: yes)"] if cli else
            ["equilibrium=False (this sweep: equilibrium=True)"])
        assert differences(a, a.replace("steps=11; ", "")) == (
            ["--steps 11 (this sweep has none)"] if cli else ["steps=11 (this sweep has none)"])
        assert differences(a.replace("steps=11; ", ""), a) == (
            ["no --steps recorded (this sweep: --steps 11)"] if cli else
            ["no steps recorded (this sweep: steps=11)"])
        assert differences(a, a.replace("0123", "3210")) == [
            "another model (another file, the file changed since, or other values set for "
            "every case)"]


def test_a_rerun_with_another_t_end_does_not_keep_the_earlier_rows(driven, capsys):
    """The command: refused, naming --t-end and both values, the file as it was; with
    --force every case runs again and the rows are a fresh sweep's with the new end (they
    were the first run's, with a note)."""
    args = ["--set", MASSES[0], "--run", "kinematics", "--steps", "11"]
    code, out, err = command(capsys, driven, *args, "--t-end", "0.05", "--out", "k.csv")
    assert code == 0, err
    first = Path("k.csv").read_bytes()
    code, out, err = command(capsys, driven, *args, "--t-end", "0.1", "--out", "k.csv")
    assert (code, out) == (2, "")
    assert err == ("mbody: error: k.csv:2: case 0 was computed with --t-end 0.05 (this "
                   "sweep: 0.1): the file holds the results of other settings, which are "
                   "not this sweep's; give another --out to keep it, or --force to run those "
                   "cases again and replace their rows\n")
    assert Path("k.csv").read_bytes() == first
    code, out, err = command(capsys, driven, *args, "--t-end", "0.1", "--out", "k.csv",
                             "--force")
    assert code == 0, err
    assert out.startswith("wrote k.csv: 2 cases, 2 run now (2 earlier rows of other settings "
                          "or values replaced, as --force asks)\n")
    code, out, err = command(capsys, driven, *args, "--t-end", "0.1", "--out", "fresh.csv")
    assert code == 0, err
    assert read(Path("k.csv")) == read(Path("fresh.csv"))
    header, rows = read(Path("k.csv"))
    old = list(csv.reader(first.decode().splitlines()))[1:]
    assert all("t-end=0.05;" in r[-1] for r in old) and all("t-end=0.1;" in r[-1] for r in rows)
    # the crank turns at 100 rad/s: 0.05 s more turns it 5 rad further (its angle wrapped
    # into (-pi, pi]), within the kinematic analysis's tolerance
    crank = header.index("final:crank.theta")
    for a, b in zip(old, rows, strict=True):
        turned = (float(b[crank]) - float(a[crank]) + math.pi) % (2 * math.pi) - math.pi
        assert turned == pytest.approx(5.0 - 2 * math.pi, abs=1e-9)
    # the same settings again: the rows are kept, and the line says so
    code, out, err = command(capsys, driven, *args, "--t-end", "0.1", "--out", "k.csv")
    assert out.startswith("wrote k.csv: 2 cases, 0 run now (2 kept from an earlier run "
                          "with the same settings)\n")
    assert read(Path("k.csv"))[1] == rows


SLIDER_KIN = {"run": "kinematics", "t_end": 0.05, "steps": 11}
RERUNS = [
    (SLIDER_KIN, {**SLIDER_KIN, "steps": 21}, "steps=11 (this sweep: steps=21)",
     "--steps 11 (this sweep: 21)"),
    (SLIDER_KIN, {**SLIDER_KIN, "t_end": None, "revolutions": 1.0},
     "t_end=0.05 (this sweep: revolutions=1)", "--t-end 0.05 (this sweep: 1 rev)"),
    # --steps is refused with --run simulate (review R7-11): not carried over
    (SLIDER_KIN, {"run": "simulate", "t_end": SLIDER_KIN["t_end"], "fps": 200.0},
     "run='kinematics' (this sweep: run='simulate')", "--run kinematics (this sweep: simulate)"),
    ({"run": "simulate", "t_end": 0.02, "fps": 100.0},
     {"run": "simulate", "t_end": 0.02, "fps": 400.0}, "fps=100 (this sweep: fps=400)",
     "--fps 100 (this sweep: 400)"),
]
RERUN_IDS = ["steps", "seconds to turns", "run", "fps"]


@pytest.mark.parametrize(("first", "then", "said"), [
    *((first, then, said) for first, then, said, _ in RERUNS),
    ({}, {"fixed": "gravity=[0, -1.62]"}, "another model"),
    ({}, {"edit": ("mass: 0.5", "mass: 0.6")}, "another model"),
], ids=[*RERUN_IDS, "a value for every case", "the file"])
def test_a_rerun_with_other_settings_is_refused_or_run_again(driven, first, then, said):
    """From Python: each setting that changes the numbers, the run, the model's content;
    the message names it as run_sweep takes it (before: by the command's flags, '--steps
    11', '--force'); force=True gives a fresh sweep's rows."""
    def sweep(kw: dict, out: str, force: bool = False):
        kw = dict(kw)
        values = [*MASSES, *([kw.pop("fixed")] if "fixed" in kw else [])]
        if "edit" in kw:
            old, new = kw.pop("edit")
            text = driven_text()
            assert text.count(old) == 1
            driven.write_text(text.replace(old, new))
        return mbody.run_sweep(driven, values, out, workers=0, force=force, **kw)

    sweep(first, "r.csv")
    before = Path("r.csv").read_bytes()
    with pytest.raises(MbodyError) as refused:
        sweep(then, "r.csv")
    assert f"r.csv:2: case 0 was computed with {said}" in str(refused.value)
    assert str(refused.value).endswith("give another out=... to keep it, or force=True to run "
                                       "those cases again and replace their rows")
    assert "--" not in str(refused.value)
    assert Path("r.csv").read_bytes() == before
    forced = sweep(then, "r.csv", force=True)
    assert (forced.ran, forced.kept, forced.replaced) == (2, 0, 2)
    fresh = sweep(then, "fresh.csv")
    assert forced.rows == fresh.rows == read(Path("r.csv"))[1]
    assert forced.settings == fresh.settings != read_settings(before)


def flags(settings: dict) -> list[str]:
    """run_sweep's keyword arguments as `mbody sweep`'s options."""
    out = []
    for key, value in settings.items():
        if key == "revolutions":
            out += ["--t-end", f"{value:g} rev"]
        elif value is not None:
            out += [f"--{key.replace('_', '-')}", f"{value:g}" if isinstance(value, float)
                    else str(value)]
    return out


@pytest.mark.parametrize(("first", "then", "said"), [(f, t, s) for f, t, _, s in RERUNS],
                         ids=RERUN_IDS)
def test_a_rerun_with_other_settings_names_the_command_s_options(driven, capsys, first,
                                                                  then, said):
    """The same reruns from the command line: the options as typed."""
    code, out, err = command(capsys, driven, "--set", MASSES[0], *flags(first), "-o", "r.csv")
    assert code == 0, err
    code, out, err = command(capsys, driven, "--set", MASSES[0], *flags(then), "-o", "r.csv")
    assert (code, out) == (2, ""), err
    assert err == (f"mbody: error: r.csv:2: case 0 was computed with {said}: the file holds "
                   "the results of other settings, which are not this sweep's; give another "
                   "--out to keep it, or --force to run those cases again and replace their "
                   "rows\n")


def read_settings(data: bytes) -> str:
    rows = list(csv.reader(data.decode().splitlines()))
    return rows[1][rows[0].index("settings")]


def test_the_same_model_however_its_values_are_given_keeps_the_rows(driven):
    """The record is of the model the cases are built from: a value set for every case,
    or the same value written in the file, and comments or layout changed, are the same
    model; its rows are kept."""
    first = mbody.run_sweep(driven, [*MASSES, "gravity=[0, -1.62]"], "r.csv", workers=0)
    text = driven_text()
    assert text.count("gravity: [0, -9.81]") == 1
    driven.write_text("# the Moon\n" + text.replace("gravity: [0, -9.81]",
                                                     "gravity: [0,   -1.62]"))
    again = mbody.run_sweep(driven, MASSES, "r.csv", workers=0)
    assert (again.ran, again.kept, again.rows) == (0, 2, first.rows)


def old_format(path: Path) -> None:
    """`path` as an mbody before 0.4 wrote it: no settings column."""
    header, rows = read(path)
    assert header[-1] == "settings"
    with open(path, "w", newline="") as fh:
        csv.writer(fh).writerows([header[:-1], *(r[:-1] for r in rows)])


def test_an_old_results_file_is_refused_with_what_to_do(driven, capsys):
    mbody.run_sweep(driven, MASSES, "r.csv", workers=0)
    old_format(Path("r.csv"))
    before = Path("r.csv").read_bytes()
    said = ("r.csv was written by an earlier mbody, which did not record the settings its "
            "rows were computed with (the run's --t-end, --steps or --fps, the model): they "
            "cannot be told to be this sweep's; give another --out to keep it, or --force to "
            "run those cases again and replace their rows")
    with pytest.raises(MbodyError) as refused:
        mbody.run_sweep(driven, MASSES, "r.csv", workers=0)
    # in Python, by run_sweep's keywords (before: the command's flags)
    assert str(refused.value) == (
        "r.csv was written by an earlier mbody, which did not record the settings its rows "
        "were computed with (the run's t_end, steps or fps, the model): they cannot be told "
        "to be this sweep's; give another out=... to keep it, or force=True to run those "
        "cases again and replace their rows")
    code, out, err = command(capsys, driven, "--set", MASSES[0], "--out", "r.csv")
    assert (code, out, err) == (2, "", f"mbody: error: {said}\n")
    assert Path("r.csv").read_bytes() == before
    forced = mbody.run_sweep(driven, MASSES, "r.csv", workers=0, force=True)
    assert (forced.ran, forced.replaced) == (2, 2)
    assert read(Path("r.csv"))[0][-1] == "settings"


def test_an_interrupted_run_with_other_settings_is_not_resumed(driven, monkeypatch):
    """The journal of an interrupted run holds rows of its settings: a run with others is
    refused at the journal; with force the journal is begun anew (interrupted again, it
    holds this sweep's rows only), and the resumed output is a fresh sweep's."""
    real = cluster.run_chunk
    calls: list[list[int]] = []

    def second_stops(job, part):
        calls.append(list(part))
        if len(calls) % 2 == 0:
            raise KeyboardInterrupt
        return real(job, part)

    grid = ["bodies.rod.mass=0.4:0.8:4"]
    kw = {"run": "kinematics", "steps": 11, "workers": 0, "chunk": 2}
    monkeypatch.setattr(cluster, "run_chunk", second_stops)
    with pytest.raises(SweepInterrupted):
        mbody.run_sweep(driven, grid, "r.csv", t_end=0.05, **kw)
    journal = Path("r.csv.partial")
    assert len(read(journal)[1]) == 2
    with pytest.raises(MbodyError, match=r"^r\.csv\.partial:2: case 0 was computed with "
                                         r"t_end=0\.05 \(this sweep: t_end=0\.1\)"):
        mbody.run_sweep(driven, grid, "r.csv", t_end=0.1, **kw)
    with pytest.raises(SweepInterrupted):
        mbody.run_sweep(driven, grid, "r.csv", t_end=0.1, force=True, **kw)
    header, rows = read(journal)
    assert len(rows) == 2 and all("t-end=0.1;" in r[-1] for r in rows)
    monkeypatch.setattr(cluster, "run_chunk", real)
    resumed = mbody.run_sweep(driven, grid, "r.csv", t_end=0.1, **kw)
    assert (resumed.ran, resumed.kept) == (2, 2) and not journal.exists()
    fresh = mbody.run_sweep(driven, grid, "fresh.csv", t_end=0.1, **kw)
    assert resumed.rows == fresh.rows


def test_another_sweeps_rows_are_replaced_with_force(driven):
    """Other values under the same case numbers (the grid changed): refused as before; with
    force those cases run again."""
    mbody.run_sweep(driven, MASSES, "r.csv", workers=0)
    with pytest.raises(MbodyError, match="another sweep's results"):
        mbody.run_sweep(driven, ["bodies.rod.mass=0.5:0.8:2"], "r.csv", workers=0)
    forced = mbody.run_sweep(driven, ["bodies.rod.mass=0.5:0.8:2"], "r.csv", workers=0,
                             force=True)
    assert (forced.ran, forced.kept, forced.replaced) == (1, 1, 1)  # case 1 is 0.8 in both
    fresh = mbody.run_sweep(driven, ["bodies.rod.mass=0.5:0.8:2"], "fresh.csv", workers=0)
    assert forced.rows == fresh.rows


def test_the_results_are_read_by_csv_readers(driven):
    """The settings column is text to a CSV reader, and the other columns are what they
    were: pyarrow's reader (pandas's read_csv infers types the same way) and the
    standard library's."""
    pa_csv = pytest.importorskip("pyarrow.csv")  # the sweep extra
    result = mbody.run_sweep(driven, MASSES, "r.csv", run="kinematics", t_end=0.05,
                             steps=11, workers=0)
    table = pa_csv.read_csv("r.csv")
    assert table.column_names == result.header
    assert str(table.schema.field("settings").type) == "string"
    assert table.column("settings").to_pylist() == [result.settings] * 2
    for name in result.header[1:-2]:
        assert str(table.schema.field(name).type) == "double", name
        assert table.column(name).to_pylist() == floats(
            [r[result.header.index(name)] for r in result.rows]).tolist()

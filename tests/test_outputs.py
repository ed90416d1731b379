"""Where outputs go (issue 22): never onto what is not a regular file, never onto the
command's own input, never half-written.

- A device, a named pipe or standard output given as an output is written through
  (opened and written), never replaced by a renamed file: as root, a rename onto
  /dev/null would turn the device into a regular file for every program on the machine.
  A block device and a socket are refused. A symbolic link is followed: the file it names
  is replaced and the link stays.
- An output that is the command's own input (the same file, however named) is refused,
  with or without --force (review R5-6), with exit code 2 and both names; so are two
  outputs of one command that are one file.
- A write that fails (a full disk) is exit 2 with the system's reason, and leaves nothing:
  no temporary file, no half-written picture set, no folder made for it.
"""

from __future__ import annotations

import errno
import io
import json
import os
import socket
import stat
import subprocess
import sys
import threading
import zipfile
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.util import atomic

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"
ROOT_USER = hasattr(os, "geteuid") and os.geteuid() == 0


def run(capsys, *args) -> tuple[int, str, str]:
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def cli(*args, **kw) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    kw.setdefault("stdout", subprocess.PIPE)
    p = subprocess.run([sys.executable, "-m", "mbody", *map(str, args)], env=env,
                       stderr=subprocess.PIPE, timeout=300, **kw)
    assert b"Traceback" not in p.stderr
    return p


@pytest.fixture(scope="module")
def run_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("run") / "pendulum.npz"
    mbody.simulate(mbody.load(PENDULUM), t_end=0.5, fps=20).save(path)
    return path


def writers(tmp: Path, run_file: Path, target: str | Path) -> dict[str, list[str]]:
    """Every command that writes one file, writing `target`."""
    model = tmp / "m.yaml"
    if not model.exists():
        model.write_text(PENDULUM.read_text())
    t = str(target)
    return {
        "simulate": ["simulate", str(model), "--t-end", "0.2", "--no-progress", "-o", t],
        "report": ["report", str(model), "-o", t],
        "latex": ["assemble", str(model), "--latex", t],
        "animate": ["animate", str(run_file), "-o", t],
        "convert": ["convert", str(model), "-o", t, "--to", "mjcf", "--force"],
        "export": ["export", str(model), "-o", t],
        "plot": ["plot", str(run_file), "-o", t],
        "graph": ["graph", str(model), "-o", t],
    }


# == devices, pipes, links ====================================================================

DEVNULL = Path("/dev/null")


@pytest.mark.skipif(not DEVNULL.exists(), reason="no /dev/null")
@pytest.mark.parametrize("command", ["simulate", "report", "latex", "animate", "convert",
                                     "plot", "graph"])
def test_dev_null_stays_a_device(tmp_path, capsys, run_file, command):
    """As root a rename would replace /dev/null by a regular file; mbody writes through."""
    before = os.stat(DEVNULL)
    argv = writers(tmp_path, run_file, DEVNULL)[command]
    if command in ("plot", "graph"):  # the picture's format comes from the name: a link
        link = tmp_path / "picture.svg"
        link.symlink_to(DEVNULL)
        argv[-1] = str(link)
    code, out, err = run(capsys, *argv)
    assert code == 0, err
    after = os.stat(DEVNULL)
    assert stat.S_ISCHR(after.st_mode) and after.st_rdev == before.st_rdev
    assert "wrote " in out + err


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes")
@pytest.mark.parametrize("command", ["simulate", "report", "latex", "animate", "export"])
def test_a_named_pipe_is_written_through_to_its_reader(tmp_path, capsys, run_file, command):
    fifo = tmp_path / ("out.json" if command == "export" else "out")
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    code, _, err = run(capsys, *writers(tmp_path, run_file, fifo)[command])
    reader.join(timeout=60)
    assert code == 0, err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)  # still the pipe
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["m.yaml", fifo.name])  # no temporary file left beside it
    data = got[0]
    if command == "simulate":
        path = tmp_path / "back.npz"
        path.write_bytes(data)
        assert mbody.Trajectory.load(path).body_names == ("rod",)
    elif command == "export":
        assert json.loads(data)["format"] == "mbody-export"
    else:
        assert len(data) > 100


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes")
def test_a_named_pipe_nobody_reads_is_refused_after_a_short_wait(tmp_path, capsys, monkeypatch,
                                                                 run_file):
    monkeypatch.setattr(atomic, "PIPE_WAIT", 0.2)
    fifo = tmp_path / "page.html"
    os.mkfifo(fifo)
    code, _, err = run(capsys, "report", PENDULUM, "-o", fifo)
    assert (code, err) == (2, f"mbody: error: cannot write {str(fifo)!r}: no program reads "
                           "this named pipe (waited 0.2 s); start the reader first, or give "
                           "a file name\n")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


@pytest.mark.skipif(not DEVNULL.exists(), reason="no /dev/null")
def test_a_link_to_a_device_is_followed_and_both_stay(tmp_path, capsys):
    link = tmp_path / "out.html"
    link.symlink_to(DEVNULL)
    code, _, err = run(capsys, "report", PENDULUM, "-o", link)
    assert code == 0, err
    assert os.readlink(link) == str(DEVNULL) and stat.S_ISCHR(os.stat(DEVNULL).st_mode)


def test_a_link_to_a_file_keeps_the_link_and_replaces_the_file(tmp_path, capsys):
    real = tmp_path / "runs" / "page.html"
    real.parent.mkdir()
    real.write_text("old")
    link = tmp_path / "latest.html"
    link.symlink_to(real)
    code, _, err = run(capsys, "report", PENDULUM, "-o", link)
    assert code == 0, err
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert real.read_text().startswith("<!DOCTYPE html>")
    assert sorted(p.name for p in real.parent.iterdir()) == ["page.html"]


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full")
def test_a_full_device_is_exit_2_and_says_the_output_is_incomplete(tmp_path, capsys):
    code, _, err = run(capsys, "assemble", PENDULUM, "--latex", "/dev/full")
    assert (code, err) == (2, "mbody: error: cannot write '/dev/full': No space left on "
                           "device; the output is incomplete (a device or a pipe is written "
                           "as it goes and cannot be taken back)\n")
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


def test_a_socket_is_refused(tmp_path, capsys):
    path = tmp_path / "s.html"
    with socket.socket(socket.AF_UNIX) as s:
        s.bind(str(path))
        code, _, err = run(capsys, "report", PENDULUM, "-o", path)
    assert (code, err) == (2, f"mbody: error: cannot write {str(path)!r}: it is a socket, "
                           "which mbody never writes onto; give a file name\n")


@pytest.mark.skipif(not ROOT_USER, reason="making a device node needs root")
def test_a_block_device_is_refused_before_any_work(tmp_path, capsys):
    disk = tmp_path / "run.npz"
    try:
        os.mknod(disk, 0o600 | stat.S_IFBLK, os.makedev(7, 0))
    except OSError as exc:  # pragma: no cover - a container without CAP_MKNOD
        pytest.skip(f"cannot make a block device: {exc}")
    code, _, err = run(capsys, "simulate", PENDULUM, "-o", disk)
    assert (code, err) == (2, f"mbody: error: cannot write {str(disk)!r}: it is a block "
                           "device (a disk), which mbody never writes onto; give a file name\n")
    assert stat.S_ISBLK(os.lstat(disk).st_mode)


@pytest.mark.skipif(sys.platform != "linux", reason="/dev/stdout")
def test_dev_stdout_gets_the_data_and_the_messages_go_to_stderr(tmp_path):
    p = cli("simulate", PENDULUM, "--t-end", "0.2", "--no-progress", "-o", "/dev/stdout")
    assert p.returncode == 0, p.stderr
    with zipfile.ZipFile(io.BytesIO(p.stdout)) as z:  # the whole file, only
        assert "t.npy" in z.namelist()
    assert b"simulated 'physical-pendulum'" in p.stderr
    # stdout redirected to a file: written at its place, the file is not replaced
    out = tmp_path / "run.npz"
    with open(out, "wb") as fh:
        p = cli("simulate", PENDULUM, "--t-end", "0.2", "--no-progress", "-o", "/dev/stdout",
                stdout=fh)
    assert p.returncode == 0
    t = mbody.Trajectory.load(out).t
    assert np.allclose(t, np.linspace(0, 0.2, len(t)))
    assert Path("/dev/stdout").is_symlink()


# == an output onto the command's own input ==================================================

@pytest.mark.parametrize(("args", "flag", "what"), [
    (["simulate", "{m}", "--t-end", "0.1", "-o", "{m}"], "-o", "the model"),
    (["report", "{m}", "-o", "{m}"], "-o", "the model"),
    (["assemble", "{m}", "--latex", "{m}"], "--latex", "the model"),
    (["convert", "{m}", "-o", "{m}"], "-o", "the input"),
    (["animate", "{run}", "-o", "{run}"], "-o", "the input"),
    (["report", "{m}", "--answers", "{a}", "-o", "{a}"], "-o", "the answers file"),
    (["export", "{m}", "--state", "{run}", "-o", "{run}"], "-o", "the run file"),
    (["animate", "{run}", "--model", "{m}", "-o", "{m}"], "-o", "the model"),
])
def test_an_output_onto_an_input_is_refused_even_forced(tmp_path, capsys, run_file, args,
                                                        flag, what):
    # export -o, graph -o and plot -o onto an input whose suffix they cannot write:
    # tests/test_review_papercuts.py (--force is not offered where it cannot help)
    m = tmp_path / "m.yaml"
    m.write_text(PENDULUM.read_text())
    answers = tmp_path / "a.yaml"
    answers.write_text("equations:\n  - {body: rod, eq: \"a_x = 0\"}\n")
    run = tmp_path / "run.npz"
    run.write_bytes(run_file.read_bytes())
    files = {p: p.read_bytes() for p in (m, answers, run)}
    names = {"m": m, "a": answers, "run": run}
    argv = [a.format(**names) for a in args]
    target = Path(argv[argv.index(flag) + 1])
    for force in ([], ["--force"]):  # --force never replaces an input (it once did)
        code = main(argv + force)
        err = capsys.readouterr().err
        assert (code, err) == (2, f"mbody: error: {flag} {target} is {what} itself "
                               f"({target}): writing there would replace the input, which "
                               "no option allows (--force neither); give another output "
                               "file\n")
    assert {p: p.read_bytes() for p in files} == files  # every input as it was


def test_the_same_file_under_another_name_is_the_same_file(tmp_path, capsys):
    m = tmp_path / "m.yaml"
    m.write_text(PENDULUM.read_text())
    hard = tmp_path / "hard.yaml"
    os.link(m, hard)
    link = tmp_path / "sub" / "link.yaml"
    link.parent.mkdir()
    link.symlink_to(m)
    for output, spelled in ((hard, hard), (link, link), (tmp_path / "sub" / ".." / "m.yaml",
                                                          tmp_path / "sub" / ".." / "m.yaml")):
        code, _, err = run(capsys, "report", m, "-o", output)
        assert (code, err) == (2, f"mbody: error: -o {spelled} is the model itself ({m}, the "
                               "same file): writing there would replace the input, which "
                               "no option allows (--force neither); give another output "
                               "file\n")
    assert m.read_text() == PENDULUM.read_text()


def test_force_never_replaces_the_input(tmp_path, capsys):
    """Review R5-6: --force once replaced the model with the LaTeX, the CSV or the
    converted model (convert "in place"); an input is never an output now."""
    m = tmp_path / "m.yaml"
    m.write_text(PENDULUM.read_text())
    answers = tmp_path / "b2.csv"  # an answers file under a CSV's name
    answers.write_text("equations:\n  - {body: rod, eq: \"a_x = 0\"}\n")
    crank = tmp_path / "crank.yaml"
    crank.write_text((PENDULUM.parent / "slider_crank_driven.yaml").read_text())
    before = {p: p.read_bytes() for p in (m, answers, crank)}
    for argv, flag, target, what in [
            (["assemble", m, "--latex", m], "--latex", m, "the model"),
            (["convert", m, "-o", m], "-o", m, "the input"),
            (["convert", m, "--to", "mjcf", "-o", m], "-o", m, "the input"),
            (["verify", m, answers, "--summary", answers], "--summary", answers,
             "the answers file"),
            (["kinematics", crank, "--every", "90 deg", "--csv", crank], "--csv", crank,
             "the model")]:
        code, out, err = run(capsys, *argv, "--force")
        assert (code, out) == (2, ""), err
        assert err.startswith(f"mbody: error: {flag} {target} is {what} itself ({target}): ")
        assert err.endswith("(--force neither); give another output file\n")
    assert {p: p.read_bytes() for p in before} == before


@pytest.mark.parametrize(("args", "message"), [
    (["kinematics", "{crank}", "--t-end", "0.05", "--csv", "{d}/x.npz", "-o", "{d}/x.npz"],
     "-o and --csv are both {d}/x.npz"),
    (["kinematics", "{crank}", "--t-end", "0.05", "--csv", "{d}/link.csv", "-o",
      "{d}/x.npz"], "--csv {d}/link.csv is -o {d}/x.npz, the same file"),
    (["export", "{m}", "-o", "{d}/e.json", "-o", "{d}/sub/../e.json"],
     "-o {d}/sub/../e.json is -o {d}/e.json, the same file"),
    (["export", "{m}", "-o", "{d}/e.json", "-o", "{d}/e.json"], "-o {d}/e.json is given "
     "twice"),
    (["lagrange", "{m}", "--latex", "{d}/hard.tex", "-o", "{d}/l.tex"],
     "--latex {d}/hard.tex is -o {d}/l.tex, the same file"),
])
def test_two_outputs_of_one_command_are_never_one_file(tmp_path, capsys, args, message):
    """Review R5-6: `-o x.npz --csv x.npz --force` wrote the run, then the CSV over it.
    Two outputs that are one file (as named, through a link to a file to be made, as a
    hard link, spelt another way) are refused, --force or not, before any work."""
    m = tmp_path / "m.yaml"
    m.write_text(PENDULUM.read_text())
    crank = tmp_path / "crank.yaml"
    crank.write_text((PENDULUM.parent / "slider_crank_driven.yaml").read_text())
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.csv").symlink_to(tmp_path / "x.npz")  # x.npz is not there yet
    (tmp_path / "l.tex").write_text("old")
    os.link(tmp_path / "l.tex", tmp_path / "hard.tex")
    argv = [a.format(d=tmp_path, m=m, crank=crank) for a in args]
    for force in ([], ["--force"]):
        code, out, err = run(capsys, *argv, *force)
        assert (code, out) == (2, "")
        assert err == (f"mbody: error: {message.format(d=tmp_path)}: one output would "
                       "replace the other; give each output its own file\n")
    assert not (tmp_path / "x.npz").exists() and not (tmp_path / "e.json").exists()
    assert (tmp_path / "l.tex").read_text() == "old"


def test_two_outputs_onto_one_device_are_written_through(tmp_path, capsys):
    """/dev/null twice is not one file replaced by the other: both are written through."""
    if not DEVNULL.exists():
        pytest.skip("no /dev/null")
    crank = tmp_path / "crank.yaml"
    crank.write_text((PENDULUM.parent / "slider_crank_driven.yaml").read_text())
    code, out, err = run(capsys, "kinematics", crank, "--t-end", "0.05", "--csv", DEVNULL,
                         "-o", DEVNULL)
    assert code == 0, err


@pytest.mark.skipif(sys.platform != "linux", reason="/dev/stdout")
def test_two_outputs_on_standard_output_pass_wherever_it_goes(tmp_path):
    """Review R6-5: -o and --csv both /dev/stdout were refused when the shell redirected
    stdout to a file and accepted on a pipe; both are written through the descriptor, one
    after the other, so both pass, and the file holds both, in order."""
    out = tmp_path / "both.out"
    args = ("kinematics", PENDULUM.parent / "slider_crank_driven.yaml", "--t-end", "0.05",
            "--csv", "/dev/stdout", "-o", "/dev/stdout")
    with open(out, "wb") as fh:
        p = cli(*args, stdout=fh)
    assert p.returncode == 0, p.stderr
    piped = cli(*args)
    assert piped.returncode == 0, piped.stderr
    assert out.read_bytes() == piped.stdout
    assert piped.stdout.startswith(b"PK") and b"motor (deg),t (s)" in piped.stdout  # npz, table


def test_every_command_that_writes_has_force():
    from mbody.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    writing = {name for name, p in sub.choices.items()
               if any(a.dest in ("output", "latex", "csv", "summary", "picture")
                      for a in p._actions)}
    assert writing == {"simulate", "plot", "fbd", "graph", "report", "animate", "export",
                       "assemble", "convert", "kinematics", "lagrange", "modes", "sweep",
                       "verify"}
    for name in writing:
        assert "--force" in sub.choices[name]._option_string_actions, name


# == a write that fails: nothing left behind ===================================================

def _no_space(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_fbd_on_a_full_disk_leaves_no_folder_and_no_picture(tmp_path, capsys, monkeypatch):
    """The third picture fails: the first two are not left behind, nor the new folder."""
    from mbody.present.draw import mpl

    calls = []

    def third_fails(path, data):
        calls.append(path)
        if len(calls) == 3:
            _no_space()
        return real(path, data)

    real = mpl.write_atomic
    monkeypatch.setattr(mpl, "write_atomic", third_fails)
    out = tmp_path / "new" / "pictures"
    code, _, err = run(capsys, "fbd", MODELS / "slider_crank.yaml", "-o", out)
    assert (code, err) == (2, f"mbody: error: cannot write {str(out)!r}: No space left on "
                           "device; nothing was written (the temporary folder is removed, "
                           "and 'pictures' is as it was)\n")
    assert list(tmp_path.iterdir()) == []
    # into a folder that exists: its files stay as they were
    out.mkdir(parents=True)
    (out / "fbd_crank.svg").write_text("old")
    calls.clear()
    code, _, err = run(capsys, "fbd", MODELS / "slider_crank.yaml", "-o", out)
    assert code == 2
    assert [p.name for p in out.iterdir()] == ["fbd_crank.svg"]
    assert (out / "fbd_crank.svg").read_text() == "old"


@pytest.mark.parametrize("name", ["p.pdf", "p.png", "p.svg"])
def test_plot_on_a_full_disk_is_exit_2(tmp_path, capsys, monkeypatch, run_file, name):
    monkeypatch.setattr(os, "fsync", _no_space)  # the last step before the rename
    code, _, err = run(capsys, "plot", run_file, "-o", tmp_path / name)
    assert (code, err) == (2, f"mbody: error: cannot write {str(tmp_path / name)!r}: No space "
                           f"left on device; nothing was written (the temporary file is "
                           f"removed, and {name!r} is as it was)\n")
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def small_disk(tmp_path):
    """A 64 kB tmpfs (root only: CI runs as root); skipped where it cannot be mounted."""
    where = tmp_path / "disk"
    where.mkdir()
    if not ROOT_USER:
        pytest.skip("mounting a small file system needs root")
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(where)],
                       capture_output=True, text=True)
    if p.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {p.stderr.strip()}")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=False)


@pytest.mark.parametrize(("command", "name"), [
    (["fbd", MODELS / "heavy_top.yaml", "--image-format", "png", "-o"], "pictures"),
    (["plot", "{run}", "-o"], "p.pdf"),
    (["report", MODELS / "fourbar_spatial.yaml", "-o"], "page.html"),
    (["simulate", MODELS / "triple_pendulum.yaml", "--t-end", "2", "--no-progress", "-o"],
     "run.npz"),
])
def test_a_real_full_disk(small_disk, run_file, command, name):
    filler = small_disk / "filler"
    filler.write_bytes(b"x" * 40_000)  # leaves about 24 kB
    argv = [run_file if c == "{run}" else c for c in command] + [small_disk / name]
    p = cli(*argv)
    err = p.stderr.decode()
    temporary = "folder" if name == "pictures" else "file"
    assert (p.returncode, err) == (2, f"mbody: error: cannot write "
                                   f"{str(small_disk / name)!r}: No space left on device; "
                                   f"nothing was written (the temporary {temporary} is "
                                   f"removed, and {name!r} is as it was)\n")
    assert [f.name for f in small_disk.iterdir()] == ["filler"]


def test_export_writes_every_output_or_none(tmp_path, capsys, monkeypatch):
    """The .npz fails after the .json is complete: neither is put in place, and a .json
    that was there is as it was."""
    from mbody.io.export import npz

    def full(exp, path):
        Path(path).write_bytes(b"PK partial")
        _no_space()

    monkeypatch.setattr(npz, "write", full)
    old = tmp_path / "a.json"
    old.write_text("old")
    code, out, err = run(capsys, "export", PENDULUM, "-o", old, "-o", tmp_path / "b.npz",
                         "--csv", tmp_path / "tables")
    assert (code, out) == (2, "")
    assert err == (f"mbody: error: cannot write {str(tmp_path / 'b.npz')!r}: No space left on "
                   "device; nothing was written (the temporary file is removed, and 'b.npz' "
                   "is as it was)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]
    assert old.read_text() == "old"
    monkeypatch.undo()
    code, out, err = run(capsys, "export", PENDULUM, "-o", old, "-o", tmp_path / "b.npz",
                         "--csv", tmp_path / "tables")
    assert code == 0, err
    assert out.splitlines()[:3] == [f"wrote {old}", f"wrote {tmp_path / 'b.npz'}",
                                    f"wrote {tmp_path / 'tables'}/ (M.csv, G.csv, vectors.csv, "
                                    "columns.csv, bodies.csv, info.csv)"]
    assert mbody.load_export(old).coordinates == mbody.load_export(tmp_path / "tables"
                                                                   ).coordinates


def test_a_long_file_name_the_file_system_takes_is_written(tmp_path, capsys):
    """A target name of 250 bytes is legal; its temporary name must fit too (it was the
    target's name twice over: 'File name too long')."""
    name = "y" * 245 + ".html"
    code, _, err = run(capsys, "report", PENDULUM, "-o", tmp_path / name)
    assert code == 0, err
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_a_file_name_too_long_is_refused_before_the_work(tmp_path, capsys):
    target = tmp_path / ("x" * 300 + ".npz")
    code, out, err = run(capsys, "simulate", PENDULUM, "-o", target)
    assert (code, out) == (2, "")
    assert err == f"mbody: error: cannot write {str(target)!r}: File name too long\n"

"""`mbody convert -o OUTPUT` follows the output rules every command shares
(`mbody.util.atomic`, docs/index.md "What every command shares"): a device or a named
pipe is written through, standard output gets the data and stderr the message, a folder
is refused at once (exit 2, with or without --force). Its own extra rule stays: an
existing file is replaced only with --force."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mbody.cli.app import main

MODELS = Path(__file__).resolve().parent.parent / "models"
SOURCE = str(MODELS / "double_pendulum.yaml")
NULL = "/dev/null"


@pytest.mark.skipif(not os.path.exists(NULL), reason="no /dev/null here")
@pytest.mark.parametrize("to", ["yaml", "mjcf"])
def test_a_device_is_written_through(to, capsys):
    """``-o /dev/null --to FORMAT`` converts (as ``simulate -o /dev/null`` does); the
    device is not replaced and no --force is asked for."""
    before = os.stat(NULL)
    assert main(["convert", SOURCE, "--to", to, "-o", NULL]) == 0
    out = capsys.readouterr()
    assert out.out.startswith(f"wrote {NULL} (") and not out.err
    after = os.stat(NULL)
    assert (after.st_ino, after.st_rdev) == (before.st_ino, before.st_rdev)  # still it


@pytest.mark.skipif(not os.path.exists(NULL), reason="no /dev/null here")
def test_a_device_without_to_asks_for_to(capsys):
    """A device has no extension to tell the format: the message says to give --to."""
    assert main(["convert", SOURCE, "-o", NULL]) == 2
    err = capsys.readouterr().err
    assert "cannot tell the format of OUTPUT" in err and "give --to" in err
    assert "Traceback" not in err


@pytest.mark.parametrize("extra", [["--to", "yaml"], ["--to", "mjcf"], [],
                                   ["--to", "yaml", "--force"]])
def test_a_folder_is_refused_at_once(extra, tmp_path, capsys):
    """An existing folder as OUTPUT: one clear error, exit 2, whether or not --force or
    --to is given; nothing is written into it."""
    folder = tmp_path / "out"
    folder.mkdir()
    assert main(["convert", SOURCE, "-o", str(folder), *extra]) == 2
    err = capsys.readouterr().err
    assert "it is a folder; give a file name" in err, err
    assert "exists" not in err and "Traceback" not in err
    assert list(folder.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == [
        "out"]


def test_an_existing_file_still_needs_force(tmp_path, capsys):
    """convert's own rule, kept: a file that is there is replaced only with --force (a
    model file may be someone's only copy)."""
    out = tmp_path / "m.yaml"
    out.write_text("keep")
    assert main(["convert", SOURCE, "-o", str(out)]) == 2
    assert "exists; give --force" in capsys.readouterr().err
    assert out.read_text() == "keep"
    assert main(["convert", SOURCE, "-o", str(out), "--force"]) == 0
    assert out.read_text().startswith("# Converted by mbody")


@pytest.mark.skipif(not os.path.exists("/dev/stdout"), reason="no /dev/stdout here")
def test_standard_output_redirected_to_a_file_is_written_through(tmp_path):
    """``-o /dev/stdout`` with the shell's ``> file``: the data go to standard output
    (the file the shell opened is not one convert replaces), the message to stderr."""
    target = tmp_path / "redirected.yaml"
    target.write_text("the shell truncates this itself\n")
    with open(target, "w") as fh:
        run = subprocess.run([sys.executable, "-m", "mbody", "convert", SOURCE, "--to",
                              "yaml", "-o", "/dev/stdout"], stdout=fh,
                             stderr=subprocess.PIPE, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr
    assert run.stderr.startswith("wrote /dev/stdout (mbody YAML of 'double-pendulum'")
    assert target.read_text().startswith("# Converted by mbody")

"""Every `mbody` command a shipped model file's comments quote runs as written.

A model's header comment is where a new user first reads how to use it, so a command
there must not go stale (an option renamed, a flag that never existed). Two forms are
commands: a comment line of its own, indented after the ``#`` (``#   mbody kinematics
models/x.yaml -o run.npz``), run in order as a user pastes them; and a command in
backquotes in the prose (```mbody check` says ...``), which, when it names no file,
means that command on the model it is written in. A quoted command with an ellipsis
(```mbody solve --known ...```) elides its arguments: it is prose, not run. Each runs as
a user runs it (a subprocess), from a scratch directory where ``models/`` is the
shipped folder, so whatever it writes stays there.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MODELS = sorted((ROOT / "models").rglob("*.yaml"))

OWN_LINE = re.compile(r"^\s*#\s{2,}(mbody\s.*?)\s*$")
QUOTED = re.compile(r"`(mbody\s[^`]*)`")
FILE_ARGUMENT = re.compile(r"\.(ya?ml|xml|urdf|npz)$")


def quoted_commands(path: Path) -> list[list[str]]:
    """The commands `path`'s comments quote, in order, each as its argument list after
    ``mbody`` (a bare one given the model's own path)."""
    own = f"models/{path.relative_to(ROOT / 'models').as_posix()}"
    out: list[list[str]] = []
    for line in path.read_text().splitlines():
        if "#" not in line:
            continue
        comment = line[line.index("#"):]
        m = OWN_LINE.match(comment)
        found = [m.group(1)] if m else QUOTED.findall(comment)
        for text in found:
            if "..." in text or "…" in text:
                continue
            args = shlex.split(text)[1:]
            if not any(FILE_ARGUMENT.search(a) for a in args):
                args.append(own)
            out.append(args)
    return out


COMMANDS = {p.name: quoted_commands(p) for p in MODELS}


def test_the_collector_finds_the_commands_the_files_quote():
    """A test that collected nothing would pass whatever the files say."""
    assert ["kinematics", "models/slider_crank_driven.yaml", "--t-end", "0.1", "--fps",
            "3600", "-o", "run.npz"] in COMMANDS["slider_crank_driven.yaml"]
    assert any(a[0] == "plot" for a in COMMANDS["slider_crank_driven.yaml"])
    assert ["equilibrium", "models/spring_loaded_arm.yaml"] in COMMANDS[
        "spring_loaded_arm.yaml"]
    assert ["check", "models/helical_chain.yaml"] in COMMANDS["helical_chain.yaml"]
    assert COMMANDS["heavy_top.yaml"] == []  # `mbody solve --known ...`: elided


@pytest.mark.parametrize("name", [n for n, c in COMMANDS.items() if c])
def test_every_command_quoted_in_a_models_comments_runs(name, tmp_path):
    (tmp_path / "models").symlink_to(ROOT / "models", target_is_directory=True)
    for args in COMMANDS[name]:
        p = subprocess.run([sys.executable, "-m", "mbody", *args], cwd=tmp_path,
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, f"{name}: mbody {shlex.join(args)}\n{p.stderr}"

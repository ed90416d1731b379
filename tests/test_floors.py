"""Dependency floors: every runtime dependency of pyproject.toml states its oldest version,
tools/lowest_constraints.py pins each to it for .ci/run's lowest-versions job, and the
versions installed here are not older."""

from __future__ import annotations

import importlib.metadata
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TOOL = ROOT / "tools" / "lowest_constraints.py"


def _version(text: str) -> tuple[int, ...]:
    return tuple(int(x) for x in re.findall(r"\d+", text)[:3])


def test_constraints_pin_every_dependency_to_its_floor():
    out = subprocess.run([sys.executable, str(TOOL)], capture_output=True, text=True,
                         check=True).stdout.split()
    pins = dict(line.split("==") for line in out)
    assert set(pins) == {"numpy", "scipy", "networkx", "pyyaml", "matplotlib", "meshcat",
                         "tqdm", "defusedxml", "sympy"}
    assert _version(pins["scipy"]) >= (1, 14)  # Rotation(..., scalar_first=True)
    for name, floor in pins.items():
        installed = importlib.metadata.version(name)
        assert _version(installed) >= _version(floor), (name, installed, floor)


def test_a_dependency_without_a_floor_is_an_error(tmp_path):
    bad = tmp_path / "pyproject.toml"
    bad.write_text('[project]\nname = "x"\ndependencies = ["numpy>=1.26", "scipy"]\n')
    p = subprocess.run([sys.executable, str(TOOL), str(bad)], capture_output=True, text=True)
    assert (p.returncode, p.stdout) == (1, "")
    assert p.stderr == f"{bad}: dependency 'scipy' has no '>=' floor\n"

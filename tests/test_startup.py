"""Start-up: `import mbody` and the `check`, `assemble` and `solve` commands load no module
they do not need (nothing here is timed; tools/bench_startup.py measures the times).

Each case runs in a fresh interpreter and lists the heavy modules in its `sys.modules`, so
an eager import reintroduced anywhere on the path (at the top of a module, or in
`mbody/__init__.py`) fails here.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PENDULUM = ROOT / "models" / "pendulum.yaml"

HEAVY = ("networkx", "matplotlib", "meshcat", "scipy.spatial", "tqdm", "jsonschema",
         "scipy.integrate")
"""Slow to import and not needed by check, assemble or solve (of a model without Euler
angles or rotation matrices, which need scipy.spatial.transform)."""


def loaded(code: str, prefixes: tuple[str, ...] = HEAVY) -> list[str]:
    """The modules among `prefixes` (and their submodules) that `code` leaves loaded in a
    fresh interpreter."""
    probe = (f"{code}\nimport json, sys\nprefixes = {prefixes!r}\n"
             "print(json.dumps(sorted(m for m in sys.modules\n"
             "                        if any(m == p or m.startswith(p + '.') for p in prefixes))))")
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    p = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, env=env, capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout.splitlines()[-1])


def run_commands(*argvs: list[str]) -> str:
    return ("import contextlib, io\nimport mbody.cli\n"
            + "".join(f"with contextlib.redirect_stdout(io.StringIO()):\n"
                      f"    assert mbody.cli.main({argv!r}) == 0\n" for argv in argvs))


def test_import_mbody_loads_no_scipy():
    assert loaded("import mbody", (*HEAVY, "scipy")) == []
    assert loaded("import mbody.cli; mbody.cli.build_parser()", (*HEAVY, "scipy")) == []


@pytest.mark.parametrize("argv", [
    ["check", str(PENDULUM)],
    ["assemble", str(PENDULUM)],
    ["assemble", str(PENDULUM), "--body", "rod"],
    ["solve", str(PENDULUM)],
    ["solve", str(PENDULUM), "--json"],
], ids=lambda argv: " ".join([argv[0], Path(argv[1]).name, *argv[2:]]))
def test_command_loads_no_heavy_module(argv: list[str]):
    assert loaded(run_commands(argv)) == []


def test_all_three_commands_in_one_process():
    argvs = [[cmd, str(PENDULUM)] for cmd in ("check", "assemble", "solve")]
    assert loaded(run_commands(*argvs)) == []


def test_public_names_survive_lazy_loading():
    """Every name in `mbody.__all__` resolves; `assemble`, `animate`, `simulate` and `loads`
    stay the functions after their namesake submodules are imported (by a command)."""
    code = """
import mbody
assert set(mbody.__all__) <= set(dir(mbody))
names = {n: getattr(mbody, n) for n in mbody.__all__}
ns = {}
exec("from mbody import *", ns)
assert all(ns[n] is names[n] for n in mbody.__all__)
import mbody.animate, mbody.assemble, mbody.cli, mbody.loads, mbody.simulate
import mbody.model
assert mbody.cli.main(["check", MODEL]) == 0
for n in ("animate", "assemble", "simulate", "loads"):
    assert callable(getattr(mbody, n)) and getattr(mbody, n) is names[n], n
assert mbody.loads is mbody.model.loads
assert mbody.dynamics.__name__ == "mbody.dynamics"  # submodules as attributes, on demand
""".replace("MODEL", repr(str(PENDULUM)))
    assert loaded(code) == []

"""The package's layout: no import cycles, no needless function-level imports, and the
old flat module paths kept (deprecated) for one release."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_the_import_graph_has_no_cycles_and_no_needless_late_imports():
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "check_imports.py")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    assert " 0 needless), 0 cycle(s)" in p.stdout


def test_the_checker_finds_a_cycle(tmp_path, monkeypatch):
    """The check can fail: a module importing its importer is reported with both lines."""
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import check_imports
    finally:
        sys.path.remove(str(ROOT / "tools"))
    pkg = tmp_path / "mbody"
    (pkg / "a").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a" / "__init__.py").write_text("")
    (pkg / "a" / "x.py").write_text("from mbody.a.y import f\n")
    (pkg / "a" / "y.py").write_text("def f():\n    from mbody.a import x\n    return x\n")
    monkeypatch.setattr(check_imports, "ROOT", tmp_path)
    monkeypatch.setattr(check_imports, "PACKAGE", pkg)
    assert check_imports.main([]) == 1


@pytest.mark.parametrize("old, new", [("dynamics", "solve.dynamics"),
                                      ("validate", "model.validate"),
                                      ("commands.sim", "cli.sim"),
                                      ("export", "io.export")])
def test_an_old_module_path_is_the_new_module_with_a_warning(old, new):
    sys.modules.pop(f"mbody.{old}", None)
    if "." in old:  # its old parent (mbody.commands) is an alias too, with its own warning
        with pytest.warns(DeprecationWarning, match="moved to"):
            importlib.import_module(f"mbody.{old.rpartition('.')[0]}")
    with pytest.warns(DeprecationWarning, match=f"mbody.{old} moved to mbody.{new}"):
        module = importlib.import_module(f"mbody.{old}")
    assert module is importlib.import_module(f"mbody.{new}")
    assert module.__spec__.name == f"mbody.{new}"


def test_the_public_api_has_numpydoc_docstrings():
    """Every object docs/reference.md renders documents its parameters and returns
    (numpydoc's validator), so the generated reference cannot drift from the code."""
    pytest.importorskip("numpydoc")
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "check_docstrings.py")],
                       capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert p.returncode == 0, p.stdout + p.stderr

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
    assert " 0 needless, 0 by a string), 0 cycle(s)" in p.stdout


def _planted(tmp_path, monkeypatch, files: dict[str, str]) -> int:
    """check_imports run on a package of `files` (path -> source) instead of mbody's."""
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import check_imports
    finally:
        sys.path.remove(str(ROOT / "tools"))
    pkg = tmp_path / "mbody"
    for name, text in {"__init__.py": "", **files}.items():
        (pkg / name).parent.mkdir(parents=True, exist_ok=True)
        (pkg / name).write_text(text)
    monkeypatch.setattr(check_imports, "ROOT", tmp_path)
    monkeypatch.setattr(check_imports, "PACKAGE", pkg)
    return check_imports.main([])


def test_the_checker_finds_a_cycle(tmp_path, monkeypatch, capsys):
    """The check can fail: a module importing its importer is reported with both lines."""
    assert _planted(tmp_path, monkeypatch, {
        "a/__init__.py": "", "a/x.py": "from mbody.a.y import f\n",
        "a/y.py": "def f():\n    from mbody.a import x\n    return x\n"}) == 1
    out = capsys.readouterr().out
    assert "mbody/a/x.py:1: mbody.a.x -> mbody.a.y" in out
    assert "mbody/a/y.py:2: mbody.a.y -> mbody.a.x (in a function)" in out


def test_a_display_hook_may_import_the_presentation_layer(tmp_path, monkeypatch, capsys):
    """`_repr_html_` importing mbody.present is by design (listed, not a cycle); the same
    import in another method is a cycle, and an import by a string is refused."""
    files = {"model.py": "class Model:\n    def _repr_html_(self):\n"
                         "        from mbody.present import html\n        return html(self)\n",
             "present.py": "from mbody.model import Model\n\n\ndef html(m): ...\n"}
    assert _planted(tmp_path, monkeypatch, files) == 0
    assert "0 cycle(s)" in capsys.readouterr().out
    files["model.py"] = files["model.py"].replace("_repr_html_", "summary")
    assert _planted(tmp_path, monkeypatch, files) == 1
    assert "1 cycle(s)" in capsys.readouterr().out
    files["model.py"] = ("from importlib import import_module\n\n\nclass Model:\n"
                         "    def _repr_html_(self):\n"
                         "        return import_module('mbody.present').html(self)\n")
    assert _planted(tmp_path, monkeypatch, files) == 1
    assert "imports mbody.present by a string" in capsys.readouterr().out


def test_the_package_does_not_import_its_own_old_paths(tmp_path, monkeypatch, capsys):
    """An alias kept for users' code warns on import: inside mbody it is refused (a
    command importing mbody.io.jsontext had failed under warnings as errors)."""
    files = {"_moved.py": 'MOVED = {"io.jsontext": "util.jsontext"}\n',
             "util/__init__.py": "", "util/jsontext.py": "",
             "cli.py": "def run():\n    from mbody.io import jsontext\n    return jsontext\n"}
    assert _planted(tmp_path, monkeypatch, files) == 1
    assert ("mbody/cli.py:2: mbody.cli imports mbody.io.jsontext, an old path: use "
            "mbody.util.jsontext") in capsys.readouterr().out
    files["cli.py"] = files["cli.py"].replace("mbody.io import", "mbody.util import")
    assert _planted(tmp_path, monkeypatch, files) == 0


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



def test_the_projection_module_moved_into_the_mechanism_module_keeps_its_path():
    """`mbody.simulate.projection` (its own module until both ways of holding a run's
    joints went to `mechanism`): the same module, with a warning, whose names are there."""
    sys.modules.pop("mbody.simulate.projection", None)
    with pytest.warns(DeprecationWarning,
                      match="mbody.simulate.projection moved to mbody.simulate.mechanism"):
        module = importlib.import_module("mbody.simulate.projection")
    assert module is importlib.import_module("mbody.simulate.mechanism")
    for name in ("JointProjection", "ITERATIONS", "STAGE_ITERATIONS", "STAGE_PIVOT_RTOL"):
        assert hasattr(module, name), name

def test_the_public_api_has_numpydoc_docstrings():
    """Every object docs/reference.md renders documents its parameters and returns
    (numpydoc's validator), so the generated reference cannot drift from the code."""
    pytest.importorskip("numpydoc")
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "check_docstrings.py")],
                       capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert p.returncode == 0, p.stdout + p.stderr

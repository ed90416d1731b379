"""The tutorial notebook (docs/notebooks/tutorial.ipynb): stored as tools/make_notebook.py
writes it, and it runs top to bottom in a fresh kernel with the course's results and the
rich displays in its outputs. How long it takes is tools/bench_notebook.py's (no timed
test: the machine's load would be measured, not mbody)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "docs" / "notebooks" / "tutorial.ipynb"


def test_the_stored_notebook_is_what_the_script_writes():
    pytest.importorskip("nbformat")
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "make_notebook.py"), "--check"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    import nbformat

    nb = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not c.get("outputs") and c.get("execution_count") is None
               for c in nb.cells if c.cell_type == "code")  # stored without outputs


def _outputs(cell) -> str:
    """Everything a cell showed, as one string (text, HTML, LaTeX; errors by name)."""
    out = []
    for o in cell.get("outputs", []):
        if o.output_type == "stream":
            out.append(o.text)
        elif o.output_type == "error":
            out.append(f"ERROR {o.ename}: {o.evalue}")
        else:
            out += [v if isinstance(v, str) else str(v) for v in o.data.values()]
    return "\n".join(out)


@pytest.fixture(scope="module")
def executed():
    pytest.importorskip("ipykernel")
    nbclient = pytest.importorskip("nbclient")
    import nbformat

    nb = nbformat.read(NOTEBOOK, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell("import sys; print(sys.executable)"))
    client = nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOK.parent)}})
    # the cell timeout turns a hang into a failure; it is not a speed check
    client.execute(env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    return nb


def test_the_notebook_runs_without_an_error_in_this_python(executed):
    nb = executed
    errors = [_outputs(c) for c in nb.cells if "ERROR" in _outputs(c)]
    assert not errors, errors
    assert Path(_outputs(nb.cells[-1]).strip()).resolve() == Path(sys.executable).resolve()


def test_the_notebook_shows_the_course_results_and_the_displays(executed):
    nb = executed
    code = [c for c in nb.cells if c.cell_type == "code"]
    shown = {c.source.splitlines()[-1]: _outputs(c) for c in code}
    assert "<div class=\"mbody\">" in shown["plate_model"] and "Model 'seed-example-1'" \
        in shown["plate_model"]
    assert "<svg" in shown["plate"] and "Free body" in shown["plate"]
    assert "== plate ==" in shown["print(plate)"] and "0.5 alpha = 20" in shown["print(plate)"]
    # worked example 1: a_G = 5 m/s², α = 40 rad/s²
    assert "a_x = 5 m/s²" in shown["sol"] and "alpha = 40 rad/s²" in shown["sol"]
    assert "α = ΣM_G / I_G = 40 rad/s²" in shown["plate.euler[0]"]
    assert r"0.5\,\alpha &= 20" in shown["plate.euler[0]"]  # an Equation shows as LaTeX
    # worked example 2: ω̇ = (−3, 2, −0.5) rad/s², from the gyroscopic term alone
    assert "mbody: [-3.   2.  -0.5] rad/s²" in shown["body.euler[0]"]
    assert "pivot.Fz" in shown["top.solve()"] and "9.81 N" in shown["top.solve()"]
    assert "constraint (unknown): ['O.Fx', 'O.Fy']" in shown["rod"]
    # the pendulum: α = −7.353 rad/s², pin force (−6.37, 15.94) N
    assert "alpha = -7.3529 rad/s²" in shown["pendulum_sol"]
    assert "-6.3678 N" in shown["pendulum_sol"] and "15.9435 N" in shown["pendulum_sol"]
    assert r"\begin{bmatrix}" in shown["pendulum_sol"]  # the stacked system as LaTeX
    assert shown["double_asm"].count("<svg") == 2  # the two free bodies
    assert "data:image/png;base64," in shown["run"] and "reaction series" in shown["run"]
    assert "<iframe" in shown["animation(run, reactions=True)"]
    assert "double_pendulum.html 0.9 MB" in shown[code[-3].source.splitlines()[-1]]
    export = _outputs(code[-2])
    assert "<ExportedAssembly of 'physical-pendulum'" in export
    assert "α from the export: -7.3529" in export and "from mbody: -7.3529" in export
    assert "<Trajectory of 'double-pendulum': 2 bodies, 31 samples" in export

"""The .mat export in GNU Octave: the round trip docs/exports.md shows, run for real.

mbody writes the file; Octave loads it, finds a row and a column of G by their labels,
and solves the constrained system with the file alone, as the documentation does; the
numbers it prints must be mbody's own. Skipped when `octave` is not on PATH (CI installs
Debian's `octave` package).
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import mbody
import mbody.io.export as ex

ROOT = Path(__file__).resolve().parent.parent
OCTAVE = shutil.which("octave")
pytestmark = pytest.mark.skipif(OCTAVE is None, reason="octave is not on PATH")

SCRIPT = """
S = load('{path}');
i = find(strcmp(S.coordinates, '{row}'));
j = find(strcmp(S.reactions, '{column}'));
printf('row %d col %d G %.17g Q %.17g joint %s\\n', i, j, full(S.G(i, j)), S.Q(i), ...
       S.column_joint{{j}});
U = isnan(S.column_known);
n = numel(S.b);  u = nnz(U);
K = [S.M, -S.G(:, U); S.G(:, U)', sparse(u, u)];
known = S.column_known(~U);
x = K \\ [S.Q - S.b + S.G(:, ~U) * known; S.column_gamma(U)];
printf('%.17g\\n', x);
"""


def _octave(script: str, cwd: Path) -> str:
    (cwd / "check.m").write_text(script, encoding="utf-8")
    p = subprocess.run([OCTAVE, "--no-gui", "--quiet", "--no-window-system", "--norc",
                        "check.m"], capture_output=True, text=True, cwd=cwd, timeout=120)
    assert p.returncode == 0, p.stderr
    return p.stdout


@pytest.mark.parametrize("model, row, column", [
    ("double_pendulum.yaml", "lower.theta", "A.Fx"),
    ("fourbar_spatial.yaml", None, None),
])
def test_octave_finds_labels_and_solves_from_the_mat_file(model, row, column, tmp_path):
    asm = mbody.assemble(mbody.load(ROOT / "models" / model))
    column = column or asm.reactions[-1]
    G = asm.G.toarray()
    row = row or asm.coordinates[int(np.argmax(np.abs(G[:, asm.reactions.index(column)])))]
    ex.write_export(asm, tmp_path / "eqs.mat")
    out = _octave(SCRIPT.format(path="eqs.mat", row=row, column=column), tmp_path)
    head, *numbers = out.split("\n")
    i, j = asm.coordinates.index(row), asm.reactions.index(column)
    words = head.split()
    assert words[:4] == ["row", str(i + 1), "col", str(j + 1)]  # 1-based in Octave
    assert float(words[5]) == G[i, j] != 0  # %.17g: exact
    assert float(words[7]) == asm.Q[i]
    assert words[9] == column.split(".")[0]
    x = np.array([float(v) for v in numbers if v.strip()])
    sol = asm.solve()
    n = len(asm.coordinates)
    np.testing.assert_allclose(x[:n], sol.accelerations, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(x[n:], [sol.reactions[r] for r in asm.reactions],
                               rtol=1e-9, atol=1e-9)

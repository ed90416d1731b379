"""Start-up: `import mbody` and the `check`, `assemble` and `solve` commands load no module
they do not need (nothing here is timed; tools/bench_startup.py measures the times).

Each case runs in a fresh interpreter and lists the heavy modules in its `sys.modules`, so
an eager import reintroduced anywhere on the path (at the top of a module, or in
`mbody/__init__.py`) fails here. The numpy code that stands in for scipy on that path
(rotations from Euler angles and matrices, the blocks of G, the pivoted QR of the rank
test) is compared with scipy at the end.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody

ROOT = Path(__file__).resolve().parent.parent
PENDULUM = ROOT / "models" / "pendulum.yaml"
SHIPPED = sorted((ROOT / "models").glob("*.yaml"))

HEAVY = ("networkx", "matplotlib", "meshcat", "numba", "scipy.sparse", "scipy.spatial",
         "scipy.linalg", "tqdm", "jsonschema", "scipy.integrate", "dask", "distributed",
         "pyarrow")
"""Slow to import and not needed by check, assemble or solve of a shipped model (scipy.linalg
alone costs 0.1-0.2 s, as much as the whole command)."""

NEVER_AT_IMPORT = ("networkx", "matplotlib", "meshcat", "numba", "scipy.spatial", "tqdm",
                   "jsonschema", "scipy.integrate", "dask", "distributed", "pyarrow")
"""Not loaded by resolving the public names either (`mbody.ExportedAssembly` is in
`mbody.export`, which holds scipy.sparse matrices)."""


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


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_model_commands_load_no_heavy_module(path: Path):
    """check, assemble and solve of every shipped model (Euler angles, rotation matrices,
    redundant joints, closed loops), each followed by a look at what it loaded."""
    code = ("import contextlib, io, json, sys\nimport mbody.cli\nnew = {}\n"
            f"prefixes = {HEAVY!r}\n")
    for cmd in ("check", "assemble", "solve"):
        code += (f"with contextlib.redirect_stdout(io.StringIO()):\n"
                 f"    assert mbody.cli.main({[cmd, str(path)]!r}) == 0\n"
                 f"new[{cmd!r}] = sorted(m for m in sys.modules if any(\n"
                 "    m == p or m.startswith(p + '.') for p in prefixes))\n")
    code += "print(json.dumps(new))"
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    p = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout.splitlines()[-1]) == {"check": [], "assemble": [], "solve": []}


DASK = ("dask", "distributed", "pyarrow")
"""What only `mbody sweep` loads (its cluster, its Parquet output)."""


def test_only_the_sweep_loads_dask():
    """Every command's help, and verify, export and jacobian at work, in one process: no
    dask, distributed or pyarrow (the sweep imports them when it runs a cluster)."""
    answers = ROOT / "models" / "answers" / "pendulum.yaml"
    code = (
        "import contextlib, io, tempfile, os\nimport mbody.cli\n"
        "from mbody.cli.app import build_parser\n"
        "names = build_parser()._subparsers._group_actions[0].choices\n"
        "for name in names:\n"
        "    with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
        "        mbody.cli.main([name, '--help'])\n"
        "out = os.path.join(tempfile.mkdtemp(), 'e.json')\n"
        f"for argv in (['verify', {str(PENDULUM)!r}, {str(answers)!r}],\n"
        f"             ['export', {str(PENDULUM)!r}, '-o', out],\n"
        f"             ['jacobian', {str(PENDULUM)!r}]):\n"
        "    with contextlib.redirect_stdout(io.StringIO()):\n"
        "        assert mbody.cli.main(argv) in (0, 1), argv\n")
    assert loaded(code, DASK) == []


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
import mbody.present.animate, mbody.equations.assemble, mbody.cli, mbody.equations.loads
import mbody.simulate, mbody.model
import warnings
with warnings.catch_warnings():  # the old flat paths, kept as aliases for one release
    warnings.simplefilter("ignore", DeprecationWarning)
    import mbody.animate, mbody.assemble, mbody.loads
assert mbody.cli.main(["check", MODEL]) == 0
for n in ("animate", "assemble", "simulate", "loads"):
    assert callable(getattr(mbody, n)) and getattr(mbody, n) is names[n], n
assert mbody.loads is mbody.loading.loads  # the file read, then its pose assembled
assert mbody.solve.dynamics.__name__ == "mbody.solve.dynamics"  # submodules on demand
""".replace("MODEL", repr(str(PENDULUM)))
    assert loaded(code, NEVER_AT_IMPORT) == []


def test_the_package_docstrings_example_runs(monkeypatch):
    """What `help(mbody)` shows first runs as written (from the checkout), and the way it
    gives to import a module of `mbody.simulate`'s folder works."""
    doc = mbody.__doc__ or ""
    lines = [ln[4:] for ln in doc.split("\n\n")[1].splitlines()]
    assert lines and all(ln.strip() for ln in lines)
    monkeypatch.chdir(ROOT)
    ns: dict = {"mbody": mbody}
    exec("\n".join(lines), ns)
    assert ns["sol"].reactions["A.Fx"] == 0.0
    assert "from mbody.simulate import peaks" in doc
    from mbody.simulate import peaks
    assert peaks.__name__ == "mbody.simulate.peaks"


PLAIN_SIMULATE = ("mbody.equations.symbolic", "mbody.equations.assemble", "mbody.equations.fbd",
                  "mbody.equations.generalized", "mbody.equations.coordinates", "sympy",
                  "scipy", "tqdm", "zipfile")
"""What a DOP853 simulate of a model does not need: the symbolic layer and the assembly
around it (the first call of a process imported them through one helper, 10 ms), scipy's
integrators, a progress bar, the zip reader of saved runs."""


@pytest.mark.parametrize("name", ["pendulum", "double_pendulum", "heavy_top",
                                  "spring_mass_damper", "slider_crank_driven"])
def test_a_plain_simulate_imports_only_what_it_needs(name: str):
    """`mbody.simulate` after `mbody.load`, in a fresh process: a jointed mechanism, a
    spinning top, free bodies with a spring, a fully driven mechanism (a kinematic run)."""
    path = ROOT / "models" / f"{name}.yaml"
    code = f"import mbody\nmbody.simulate(mbody.load({str(path)!r}), t_end=0.5)"
    assert loaded(code, PLAIN_SIMULATE) == []


DEFERRED_BY_A_RUN = ("mbody.simulate.kinematic", "mbody.simulate.axes",
                     "mbody.simulate.budget", "mbody.simulate.run_file", "mbody.util.atomic",
                     "mbody.util.npzfile", "mbody.util.jsontext", "mbody.model.yaml_write")
"""What an integrated run of a model read from a YAML file leaves out: the kinematic run,
world axes, what a run over its budget is told, the run file's reader and writer
(tools/check_imports.py, `DEFERRED`; a fresh process's first simulate pays for every
module it imports: about 1 ms for these, docs/performance.md)."""


@pytest.mark.parametrize("name", ["pendulum", "double_pendulum", "heavy_top",
                                  "spring_mass_damper", "torque_free_asymmetric"])
def test_an_integrated_run_leaves_what_only_other_runs_need(name: str):
    path = ROOT / "models" / f"{name}.yaml"
    code = f"import mbody\nmbody.simulate(mbody.load({str(path)!r}), t_end=0.5)"
    assert loaded(code, DEFERRED_BY_A_RUN) == []


def _run_file(tmp: Path) -> Path:
    traj = mbody.simulate(mbody.load(ROOT / "models" / "pendulum.yaml"), t_end=0.5)
    return traj.save(tmp / "run.npz")


WORK_AND_ITS_MODULES = {
    "a fully driven model's run": (
        "mbody.simulate(mbody.load({models}/'slider_crank_driven.yaml'), t_end=0.05)",
        ["mbody.simulate.axes", "mbody.simulate.kinematic"]),
    "world axes": (
        "mbody.simulate(mbody.load({models}/'pendulum.yaml'), t_end=0.5, axes='world')",
        ["mbody.simulate.axes"]),
    "saving a run": (
        "mbody.simulate(mbody.load({models}/'pendulum.yaml'), t_end=0.5).save({tmp}/'r.npz')",
        ["mbody.simulate.run_file", "mbody.util.atomic", "mbody.util.jsontext",
         "mbody.util.npzfile"]),
    "loading a run": (
        "mbody.Trajectory.load({run})",
        ["mbody.simulate.run_file", "mbody.util.atomic", "mbody.util.jsontext",
         "mbody.util.npzfile"]),
    "a run stopped by its step budget": (
        "try:\n    mbody.simulate(mbody.load({models}/'pendulum.yaml'), t_end=5, max_steps=3)\n"
        "except mbody.MbodyError as e:\n    assert 'the step budget' in str(e)\n"
        "else:\n    raise AssertionError('the budget did not stop the run')",
        ["mbody.simulate.budget"]),
    "a model read from a dictionary": (
        "import yaml\nspec = yaml.safe_load(({models}/'pendulum.yaml').read_text())\n"
        "mbody.simulate(mbody.load(spec), t_end=0.5)",
        ["mbody.model.yaml_write", "mbody.util.atomic"]),
}
"""Work that needs deferred modules -> (its code, the deferred modules it imports)."""


@pytest.mark.parametrize("work", list(WORK_AND_ITS_MODULES))
def test_a_deferred_module_is_there_when_its_work_is(work: str, tmp_path: Path):
    """Each piece of work in a fresh process of its own imports the deferred modules it
    needs, and no other."""
    code, expected = WORK_AND_ITS_MODULES[work]
    run = _run_file(tmp_path) if "{run}" in code else None
    code = code.format(models=f"Path({str(ROOT / 'models')!r})", tmp=f"Path({str(tmp_path)!r})",
                       run=repr(str(run)))
    assert loaded("from pathlib import Path\nimport mbody\n" + code,
                  DEFERRED_BY_A_RUN) == expected


# -- numpy in place of scipy on the start-up path: the same numbers ---------------------

SEQUENCES = [a + b + c for a in "xyz" for b in "xyz" for c in "xyz" if a != b != c]


@pytest.mark.parametrize("sequence", SEQUENCES + [q.upper() for q in SEQUENCES])
def test_euler_to_quat_is_scipys_to_the_bit(sequence: str):
    from scipy.spatial.transform import Rotation

    from mbody.util.spatial import euler_to_quat

    rng = np.random.default_rng(sum(map(ord, sequence)))
    angles = np.vstack((rng.uniform(-7, 7, (200, 3)),
                        np.radians(rng.integers(-360, 361, (100, 3))),  # "30 deg" in a file
                        np.diag([0.5, -1.0, 2.0]), np.zeros((1, 3))))
    for a in angles:
        q = Rotation.from_euler(sequence, a).as_quat(scalar_first=True)
        np.testing.assert_array_equal(euler_to_quat(a, sequence), q if q[0] >= 0 else -q)


def test_matrix_to_quat_is_scipys_to_the_bit():
    from scipy.spatial.transform import Rotation

    from mbody.util.spatial import matrix_to_quat

    R = Rotation.random(3000, random_state=1).as_matrix()
    R[::7] = np.round(R[::7], 7)  # typed into a file: off orthogonal, so projected first
    R[::13] = np.round(R[::13], 3)
    R[::11] = np.diag([1.0, -1.0, -1.0])  # turned by pi: the trace is not the largest
    R[::17] = np.eye(3)
    q = Rotation.from_matrix(R).as_quat(scalar_first=True)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    np.testing.assert_array_equal(matrix_to_quat(R), q)
    np.testing.assert_array_equal(matrix_to_quat(R[5]), q[5])
    assert matrix_to_quat(R.reshape(30, 100, 3, 3)).shape == (30, 100, 4)


@pytest.mark.parametrize("path", [p for p in SHIPPED if mbody.load(p).reactions],
                         ids=lambda p: p.stem)
def test_g_block_is_the_sparse_g(path: Path):
    from mbody.equations.joints import g_block

    model = mbody.load(path)
    asm = mbody.assemble(model)
    shown = asm.G.toarray()  # a particle's rotation rows are not shown (they carry nothing)
    G = np.zeros((len(model.all_coordinates), shown.shape[1]))
    G[model.rows] = shown
    whole = g_block(model, asm.columns, np.arange(model.n), np.arange(len(model.reactions)))
    np.testing.assert_array_equal(whole, G)
    assert not np.any(np.signbit(whole) & (whole == 0))  # no -0.0
    rng = np.random.default_rng(0)
    bodies = rng.permutation(model.n)[:2]
    comps = rng.permutation(len(model.reactions))[:5]
    rows = (bodies[:, None] * model.rows_per_body + np.arange(model.rows_per_body)).ravel()
    np.testing.assert_array_equal(g_block(model, asm.columns, bodies, comps),
                                  G[np.ix_(rows, comps)])


def _qr_rank(d: np.ndarray, shape: tuple[int, int]) -> int:
    d = np.abs(d)
    return int(np.sum(d > (d[0] if len(d) else 0.0) * max(shape) * np.finfo(float).eps * 10))


def test_pivoted_qr_is_scipys_without_ties():
    """Same rank as LAPACK's pivoted QR always; the same pivots where no two remaining
    column norms tie (random matrices); the columns it keeps span A."""
    import scipy.linalg

    from mbody.equations.topology import pivoted_qr

    rng = np.random.default_rng(3)
    for trial in range(400):
        m, n = rng.integers(1, 40, 2)
        r = int(rng.integers(1, min(m, n) + 1))
        A = rng.normal(size=(m, r)) @ rng.normal(size=(r, n)) if trial % 2 else \
            (rng.integers(-1, 2, (m, r)) @ rng.integers(-1, 2, (r, n))).astype(float)
        d, piv = pivoted_qr(A)
        _, R, piv_s = scipy.linalg.qr(A, mode="economic", pivoting=True)
        rank = _qr_rank(d, A.shape)
        assert rank == _qr_rank(np.diag(R), A.shape) == np.linalg.matrix_rank(A)
        assert np.linalg.matrix_rank(A[:, piv[:rank]]) == rank
        np.testing.assert_allclose(np.abs(d), np.abs(np.diag(R)), atol=1e-12 * np.abs(d[0]))
        if trial % 2:
            np.testing.assert_array_equal(piv[:rank], piv_s[:rank])


def test_pivoted_qr_breaks_ties_by_column_order():
    """Equal columns: the first is kept, the later ones are redundant, whatever rounding
    says (the spatial four-bar's closing pin carries its redundancy)."""
    from mbody.equations.topology import pivoted_qr, topology

    A = np.array([[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])
    d, piv = pivoted_qr(A)
    assert list(piv[:2]) == [0, 1] and _qr_rank(d, A.shape) == 2
    model = mbody.load(ROOT / "models" / "fourbar_spatial.yaml")
    asm = mbody.assemble(model)
    topo = topology(model, columns=asm.columns)
    assert topo == topology(model, asm.G) == topology(model, asm.G.toarray())
    assert (topo.rank, topo.redundant) == (17, ["O4.Fz", "O4.Mx", "O4.My"])

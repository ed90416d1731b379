"""Exports: round trips are exact for every format, the label maps say the right things,
MATLAB/numpy/JSON tools read the files on their own, and a failed write leaves nothing."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
from randmodels import planar_model, spatial_model

import mbody
import mbody.io.export as ex
from mbody.errors import MbodyTypeError
from mbody.io.export import csvfolder
from mbody.simulate.trajectory import Trajectory

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
FORMATS = ("npz", "mat", "json", "csv")

ODD_NAMES = {
    "model": "odd names #1", "dimension": 3, "gravity": [0, 0, -9.81],
    "bodies": [
        {"name": "link_1", "mass": 1, "inertia": [1, 2, 2], "angular_velocity": [1, 2, 3]},
        {"name": "Zoë&co,x", "mass": 2, "inertia": [1, 1.5, 1], "position": [1, 0, 0]},
        {"name": 'θ-arm%$"', "mass": 1, "inertia": [1, 1, 1], "position": [0, 1, 0]},
    ],
    "joints": [
        {"name": "pin_A", "type": "revolute", "parent": "ground", "child": "link_1",
         "at": [0, 0, 0], "axis": [0, 0, 1]},
        {"name": "u{1}", "type": "universal", "parent": "link_1", "child": "Zoë&co,x",
         "at": [0.5, 0, 0], "axis": [0, 0, 1], "axis2": [0, 1, 0]},
        {"name": "s^2~", "type": "spherical", "parent": "Zoë&co,x", "child": 'θ-arm%$"',
         "at": [1, 1, 0]},
    ],
    "reactions": {"pin_A.Mx": 0.25},
}


def _models():
    return {
        "pendulum": mbody.load(MODELS / "pendulum.yaml"),
        "seed_example_1": mbody.load(MODELS / "seed_example_1.yaml"),
        "seed_example_2": mbody.load(MODELS / "seed_example_2.yaml"),
        "random_spatial": mbody.load(spatial_model(3, n=5, n_joints=7)),
        "random_planar": mbody.load(planar_model(4, n=4, n_joints=5, known=False)),
        "odd_names": mbody.load(ODD_NAMES),
    }


MODEL_CASES = _models()


def _write(asm_or_exp, tmp_path: Path, fmt: str) -> Path:
    if fmt == "csv":
        return ex.write_csv(asm_or_exp, tmp_path / "eqs_csv")
    return ex.write_export(asm_or_exp, tmp_path / f"eqs.{fmt}")


# -- round trips ---------------------------------------------------------------------------
@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("name", list(MODEL_CASES))
def test_round_trip_is_exact(tmp_path, name, fmt):
    asm = mbody.assemble(MODEL_CASES[name])
    path = _write(asm, tmp_path, fmt)
    back = mbody.load_export(path)
    assert ex.exported(asm).differences(back) == []
    # ... and against the in-memory assembly itself, bit for bit.
    assert back.M.shape == asm.M.shape and (back.M != asm.M).nnz == 0
    assert back.G.shape == asm.G.shape and (back.G != asm.G).nnz == 0
    assert np.array_equal(back.b, asm.b) and np.array_equal(back.Q, asm.Q)
    assert back.coordinates == asm.coordinates
    assert back.reactions == asm.reactions
    assert list(back.columns.labels) == asm.reactions
    assert np.array_equal(back.masses, asm.model.mass)
    assert np.array_equal(back.inertias, asm.model.J)
    assert np.array_equal(back.columns.W_e, asm.columns.W_e)
    assert np.array_equal(back.columns.W_P, asm.columns.W_P)
    assert back.conventions == mbody.conventions.conventions(asm.model.dimension)
    assert back.conventions["equation"] == "M vdot + b = Q + G lambda"
    assert back.known == asm.known


@pytest.mark.parametrize("fmt", FORMATS)
def test_reloaded_export_solves_like_the_assembly(tmp_path, fmt):
    """Course worked examples from the reloaded file: a_G = 5, α = 40; ω̇ = (−3, 2, −0.5)."""
    for name, want in (("seed_example_1", [5.0, 0.0, 40.0]),
                       ("seed_example_2", [0, 0, 0, -3.0, 2.0, -0.5])):
        sub = tmp_path / name
        back = mbody.load_export(_write(mbody.assemble(MODEL_CASES[name]), sub, fmt))
        assert back.solve().accelerations == pytest.approx(want, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("fmt", FORMATS)
def test_reloaded_export_solves_for_unknown_reactions(tmp_path, fmt):
    """[[M, −G_U], [G_Uᵀ, 0]] [v̇; λ_U] = [Q − b + G_K λ_K; γ_U] from the file alone.

    Pendulum about its pin: α = −m g (L/2) sin θ / (I_G + m (L/2)²); double pendulum,
    slider-crank (moving, so γ ≠ 0) and heavy top agree with `Assembly.solve`.
    """
    pend = mbody.load_export(_write(mbody.assemble(MODEL_CASES["pendulum"]),
                                    tmp_path / "p", fmt))
    I_O = 2.0 * (0.05**2 + 1.0) / 12 + 2.0 * 0.25
    sol = pend.solve()
    assert sol["rod.theta"] == pytest.approx(-2.0 * 9.81 * 0.5 * 0.5 / I_O, rel=1e-12)
    assert sol.solved == ("O.Fx", "O.Fy")
    for name in ("double_pendulum", "slider_crank", "heavy_top"):
        asm = mbody.assemble(mbody.load(MODELS / f"{name}.yaml"))
        back = mbody.load_export(_write(asm, tmp_path / name, fmt))
        want, got = asm.solve(), back.solve()
        scale = np.abs(want.accelerations).max()
        assert np.abs(got.accelerations - want.accelerations).max() <= 1e-12 * scale
        for k, v in want.reactions.items():
            assert got.reactions[k] == pytest.approx(v, rel=1e-10, abs=1e-10 * scale)
    # A given value replaces the unknown (and its joint is no longer enforced).
    fall = pend.solve(known={"O.Fx": 0.0, "O.Fy": 0.0})
    assert fall["rod.y"] == -9.81 and fall["rod.theta"] == 0.0 and fall.solved == ()


def test_round_trip_with_state_known_values_and_triplet_csv(tmp_path, monkeypatch):
    """A moved state, --known values and the CSV triplet layout (forced small limit)."""
    model = MODEL_CASES["random_planar"]
    st = model.initial
    moved = mbody.State.planar(np.array(st.position[:, :2]) + 0.3,
                               2.0 * np.arctan2(st.quaternion[:, 3], st.quaternion[:, 0]) + 0.7,
                               np.array(st.velocity[:, :2]), np.array(st.omega[:, 2]), t=1.25)
    asm = mbody.assemble(model, moved)
    known = {asm.reactions[0]: -3.5, asm.reactions[-1]: 1e-300}
    exp = ex.exported(asm, known, "a test state")
    monkeypatch.setattr(csvfolder, "CSV_DENSE_LIMIT", 4)
    for fmt in FORMATS:
        back = mbody.load_export(_write(exp, tmp_path / fmt, fmt))
        assert exp.differences(back) == [], fmt
        assert back.t == 1.25 and back.state_source == "a test state"
        assert back.known == known
    header = (tmp_path / "csv" / "eqs_csv" / "M.csv").read_text().splitlines()[0]
    assert header == "row,column,value"


# -- what the label maps say ---------------------------------------------------------------
def test_pendulum_columns_say_joint_bodies_direction_and_sign(tmp_path):
    """Rod of 1 m at 30°, pinned at its top end to ground at the origin."""
    exp = mbody.load_export(ex.write_export(mbody.assemble(MODEL_CASES["pendulum"]),
                                            tmp_path / "p.json"))
    assert exp.coordinates == ["rod.x", "rod.y", "rod.theta"]
    assert exp.reactions == ["O.Fx", "O.Fy"]
    fx, fy = exp.columns["O.Fx"], exp.columns["O.Fy"]
    for col, comp, axis in ((fx, "Fx", [1, 0, 0]), (fy, "Fy", [0, 1, 0])):
        assert (col["joint"], col["type"], col["parent"], col["child"], col["component"],
                col["kind"]) == ("O", "revolute", "ground", "rod", comp, "force")
        assert col["frame"] == pytest.approx(axis, abs=1e-15)
        assert col["point"] == pytest.approx([0, 0, 0], abs=1e-12)
        assert col["known"] is None
        assert col["sign"].startswith(f"+O.{comp} acts on rod") and "on ground" in col["sign"]
    # G's θ row: r × e with r = (−½ sin θ, ½ cos θ) from G to the pin.
    th = math.radians(30)
    assert exp.G.toarray() == pytest.approx(
        np.array([[1, 0], [0, 1], [-0.5 * math.cos(th), -0.5 * math.sin(th)]]), abs=1e-15)
    assert exp.masses.tolist() == [2.0]
    assert exp.inertias[0, 2, 2] == pytest.approx(2.0 * (0.05**2 + 1.0) / 12, rel=1e-14)
    assert exp.Q.tolist() == pytest.approx([0.0, -19.62, 0.0], abs=1e-14)


def test_universal_column_direction_is_axis_cross_axis2_in_world(tmp_path):
    exp = ex.exported(mbody.assemble(MODEL_CASES["odd_names"]))
    mt = exp.columns["u{1}.Mt"]
    assert mt["kind"] == "moment" and mt["parent"] == "link_1" and mt["child"] == "Zoë&co,x"
    assert mt["frame"] == pytest.approx(np.cross([0, 0, 1], [0, 1, 0]).tolist(), abs=1e-15)
    assert exp.columns["pin_A.Mx"]["known"] == 0.25


# -- other tools read the files on their own ----------------------------------------------
def test_scipy_loadmat_reads_sparse_matrices_and_label_cells(tmp_path):
    asm = mbody.assemble(MODEL_CASES["random_spatial"])
    path = ex.write_export(asm, tmp_path / "eqs.mat")
    d = scipy.io.loadmat(path)
    assert sp.issparse(d["M"]) and sp.issparse(d["G"])  # MATLAB sparse on disk
    assert (d["M"] != asm.M).nnz == 0 and (d["G"] != asm.G).nnz == 0
    assert d["b"].shape == (len(asm.coordinates), 1)  # column vectors, as M*vdot + b
    assert [str(c[0][0]) for c in d["coordinates"]] == asm.coordinates
    assert [str(c[0][0]) for c in d["reactions"]] == asm.reactions
    assert str(d["equation"][0]) == "M vdot + b = Q + G lambda"
    assert d["column_frame"].shape == (len(asm.reactions), 3)
    assert str(d["conventions"]["reaction_sign"][0, 0][0]).startswith("the reaction acts on")
    whos = {name: kind for name, _, kind in scipy.io.whosmat(path)}
    assert whos["M"] == "sparse" and whos["G"] == "sparse" and whos["coordinates"] == "cell"


@pytest.mark.parametrize("model", ["double_pendulum.yaml", "pendulum.yaml"])
def test_loadmat_simplify_cells_gives_labels_as_str(model, tmp_path):
    """With simplify_cells=True every label list is an array of plain str (a list of one
    label is squeezed to that str, as docs/exports.md says), the conventions a dict; the
    documented row/column look-up by label reads the right entry of G."""
    asm = mbody.assemble(mbody.load(ROOT / "models" / model))
    path = ex.write_export(asm, tmp_path / "eqs.mat")
    d = scipy.io.loadmat(path, simplify_cells=True)
    exp = ex.load_export(path)
    lists = {"coordinates": asm.coordinates, "reactions": asm.reactions,
             "body_names": list(asm.model.body_names),
             "column_joint": [str(v) for v in exp.columns.joint],
             "column_sign": [str(v) for v in exp.columns.sign]}
    for key, labels in lists.items():
        got = np.atleast_1d(d[key]).tolist()
        assert got == labels and all(type(v) is str for v in got), key
    if len(asm.model.body_names) == 1:
        assert d["body_names"] == asm.model.body_names[0]
    assert isinstance(d["conventions"], dict)
    assert d["conventions"]["reaction_sign"].startswith("the reaction acts on")
    assert d["model"] == asm.model.name and d["dimension"] == asm.model.dimension
    i = list(d["coordinates"]).index(asm.coordinates[-1])
    j = list(np.atleast_1d(d["reactions"])).index(asm.reactions[-1])
    assert d["G"][i, j] == asm.G[len(asm.coordinates) - 1, len(asm.reactions) - 1] != 0


def test_npz_reloads_with_numpy_and_scipy_alone(tmp_path):
    """The documented one call: scipy.sparse.csc_matrix((data, indices, indptr), shape)."""
    asm = mbody.assemble(MODEL_CASES["random_spatial"])
    path = ex.write_export(asm, tmp_path / "eqs.npz")
    with np.load(path, allow_pickle=False) as z:
        M = sp.csc_matrix((z["M_data"], z["M_indices"], z["M_indptr"]), shape=z["M_shape"])
        G = sp.csc_matrix((z["G_data"], z["G_indices"], z["G_indptr"]), shape=z["G_shape"])
        assert (M != asm.M).nnz == 0 and (G != asm.G).nnz == 0
        assert z["coordinates"].tolist() == asm.coordinates
        assert z["column_joint"].tolist() == [
            asm.model.joints[j].name for j in asm.model.reaction_table.joint]
        assert json.loads(str(z["conventions_json"]))["equation"] == "M vdot + b = Q + G lambda"


def test_json_validates_against_the_shipped_schema(tmp_path):
    jsonschema = pytest.importorskip("jsonschema")
    schema = ex.schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    for name, model in MODEL_CASES.items():
        path = ex.write_export(mbody.assemble(model), tmp_path / f"{name}.json")
        doc = json.loads(path.read_text(encoding="utf-8"))
        jsonschema.validate(doc, schema)
    # The schema is not vacuous: broken documents fail.
    for breaks in (lambda d: d.pop("G"), lambda d: d["columns"][0].pop("frame"),
                   lambda d: d["columns"][0].update(kind="torque"),
                   lambda d: d["M"].update(shape=[3]), lambda d: d.update(format="other")):
        bad = json.loads(path.read_text(encoding="utf-8"))
        breaks(bad)
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, schema)


def test_csv_tables_are_labelled(tmp_path):
    folder = ex.write_csv(mbody.assemble(MODEL_CASES["pendulum"]), tmp_path / "t")
    assert sorted(p.name for p in folder.iterdir()) == [
        "G.csv", "M.csv", "bodies.csv", "columns.csv", "info.csv", "vectors.csv"]
    assert (folder / "G.csv").read_text().splitlines()[:2] == [
        "coordinate,O.Fx,O.Fy", "rod.x,1.0,0.0"]
    assert (folder / "vectors.csv").read_text().splitlines()[2] == "rod.y,0.0,-19.62"
    assert '"M vdot + b = Q + G lambda"' in (folder / "info.csv").read_text()


# -- failures -------------------------------------------------------------------------------
def _half_then_fail(path, text=b"PK\x03\x04 half a file"):
    Path(path).write_bytes(text)
    raise OSError(28, "No space left on device")


@pytest.mark.parametrize("fmt", ("npz", "mat", "json"))
def test_a_write_failing_halfway_leaves_no_partial_file(tmp_path, monkeypatch, fmt):
    asm = mbody.assemble(MODEL_CASES["pendulum"])
    target = tmp_path / f"eqs.{fmt}"
    module = {"npz": ex.npz, "mat": ex.mat, "json": ex.jsonfile}[fmt]
    monkeypatch.setattr(module, "write", lambda exp, path: _half_then_fail(path))
    with pytest.raises(OSError, match="No space"):
        ex.write_export(asm, target)
    assert list(tmp_path.iterdir()) == []  # neither the target nor a temporary file
    # An existing export is left as it was.
    monkeypatch.undo()
    ex.write_export(asm, target)
    before = target.read_bytes()
    monkeypatch.setattr(module, "write", lambda exp, path: _half_then_fail(path))
    with pytest.raises(OSError):
        ex.write_export(asm, target)
    assert target.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [target.name]


def test_a_csv_write_failing_halfway_leaves_no_partial_folder(tmp_path, monkeypatch):
    asm = mbody.assemble(MODEL_CASES["pendulum"])
    real = csvfolder._matrix_rows

    def rows_then_fail(A, rows, cols):
        it = real(A, rows, cols)
        yield next(it)
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(csvfolder, "_matrix_rows", rows_then_fail)
    with pytest.raises(OSError):
        ex.write_csv(asm, tmp_path / "out")
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    ex.write_csv(asm, tmp_path / "out")
    before = {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()}
    monkeypatch.setattr(csvfolder, "_matrix_rows", rows_then_fail)
    with pytest.raises(OSError):
        ex.write_csv(mbody.assemble(MODEL_CASES["seed_example_1"]), tmp_path / "out")
    assert {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


@pytest.mark.parametrize("content, message", [
    (None, "no such file"),
    (b"not a zip", "not a readable mbody export"),
])
def test_load_export_rejects_missing_and_foreign_files(tmp_path, content, message):
    path = tmp_path / "x.npz"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(mbody.MbodyError, match=message):
        mbody.load_export(path)


def test_load_export_rejects_other_json_and_suffixes(tmp_path):
    (tmp_path / "a.json").write_text('{"format": "something-else", "version": 1}')
    with pytest.raises(mbody.MbodyError, match="not an mbody export"):
        mbody.load_export(tmp_path / "a.json")
    (tmp_path / "a.txt").write_text("x")
    with pytest.raises(mbody.MbodyError, match="expected .npz, .mat, .json"):
        mbody.load_export(tmp_path / "a.txt")
    with pytest.raises(mbody.MbodyError, match="unknown export format"):
        ex.write_export(mbody.assemble(MODEL_CASES["pendulum"]), tmp_path / "a.xlsx")


@pytest.mark.parametrize("fmt", FORMATS)
def test_an_export_of_a_model_says_to_assemble_it_first(tmp_path, fmt):
    """A `Model` where an `Assembly` goes: a TypeError naming `asm` and the call that makes
    one (before: AttributeError "'Model' object has no attribute 'model'"); nothing is
    written."""
    with pytest.raises(TypeError) as err:
        _write(MODEL_CASES["pendulum"], tmp_path, fmt)
    msg = str(err.value)
    assert msg.startswith("asm must be an Assembly (mbody.assemble(model))")
    assert "got Model" in msg and isinstance(err.value, mbody.MbodyError)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(TypeError, match=r"^asm must be an Assembly .*got str"):
        ex.exported("models/pendulum.yaml")


def test_load_export_of_a_saved_run_says_how_to_read_or_export_it(tmp_path):
    """The reverse of `Trajectory.load` of an export: the run is named as such, with the
    reader and the command that exports one of its samples."""
    run = mbody.simulate(MODEL_CASES["pendulum"], 0.1, 10)
    path = run.save(tmp_path / "run.npz")
    with pytest.raises(mbody.MbodyError) as err:
        mbody.load_export(path)
    msg = str(err.value)
    assert "an mbody trajectory" in msg and "mbody.Trajectory.load" in msg
    assert "mbody export MODEL --state RUN" in msg and "KeyError" not in msg
    np.savez(tmp_path / "other.npz", a=np.zeros(2))
    with pytest.raises(mbody.MbodyError, match="not an mbody export .*no 'format' entry"):
        mbody.load_export(tmp_path / "other.npz")


# -- the command line ------------------------------------------------------------------------
def _mbody(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "mbody.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=120)


def _pendulum_run(tmp_path: Path) -> tuple[Path, np.ndarray]:
    """A hand-made pendulum trajectory: θ_k = 30° + 0.1 k at t_k = 0.25 k (k = 0..4)."""
    t = 0.25 * np.arange(5)
    th = math.radians(30) + 0.1 * np.arange(5)
    pos = np.stack([0.5 * np.sin(th), -0.5 * np.cos(th)], axis=1)[:, None, :]
    traj = Trajectory(t=t, position=pos, velocity=np.zeros((5, 1, 2)),
                      orientation=th[:, None], angular_velocity=np.full((5, 1), 0.4),
                      body_names=("rod",), dimension=2)
    return traj.save(tmp_path / "run.npz"), th


def test_the_assembly_at_a_sample_of_a_run_in_memory_or_on_file(tmp_path):
    """docs/api.md: assembly_from_trajectory(model, run, time) takes the Trajectory itself
    (a notebook has it in memory) or its file: the same sample's assembly either way."""
    run, _ = _pendulum_run(tmp_path)
    model = mbody.load(MODELS / "pendulum.yaml")
    traj = Trajectory.load(run)
    (a, where_a), (b, where_b) = (ex.assembly_from_trajectory(model, r, 0.6) for r in (traj, run))
    assert ex.exported(a).differences(ex.exported(b)) == []
    assert where_a.endswith("sample 2 at t = 0.5 s (nearest to t = 0.6 s)")
    assert where_b == f"trajectory {run}, sample 2 at t = 0.5 s (nearest to t = 0.6 s)"
    # an MbodyTypeError since review R3 (B7), still a TypeError
    with pytest.raises(MbodyTypeError,
                       match="run must be a Trajectory or the path of its .npz file, got State"):
        ex.assembly_from_trajectory(model, traj.state(0), 0.6)  # type: ignore[arg-type]
    assert ".columns>" in repr(ex.exported(a))  # what the repr offers exists
    assert ex.exported(a).columns.records()


def test_cli_export_at_a_trajectory_sample(tmp_path):
    run, th = _pendulum_run(tmp_path)
    r = _mbody("export", MODELS / "pendulum.yaml", "--state", run, "--time", 0.6,
               "-o", tmp_path / "s.npz", "-o", tmp_path / "s.mat", "--csv", tmp_path / "c")
    assert r.returncode == 0, r.stderr
    assert "sample 2 at t = 0.5 s (nearest to t = 0.6 s)" in r.stdout
    model = mbody.load(MODELS / "pendulum.yaml")
    want = ex.exported(mbody.assemble(model, Trajectory.load(run).state(2)))
    for p in (tmp_path / "s.npz", tmp_path / "s.mat", tmp_path / "c"):
        back = mbody.load_export(p)
        assert [d for d in want.differences(back) if d != "state_source"] == []
        assert back.t == 0.5
        # Closed form at θ_2: the θ row of G is (−½ cos θ, −½ sin θ).
        assert back.G.toarray()[2] == pytest.approx(
            [-0.5 * math.cos(th[2]), -0.5 * math.sin(th[2])], rel=1e-13)
        assert back.state.omega[0, 2] == 0.4
        # γ = ω² (r · e) for a pin on ground, r from the mass centre to the pin; φ = 0.
        r = np.array([-0.5 * math.sin(th[2]), 0.5 * math.cos(th[2])])
        assert back.columns.gamma == pytest.approx(0.16 * r, rel=1e-12)
        assert back.columns.phi == pytest.approx([0.0, 0.0], abs=1e-15)


@pytest.mark.parametrize("args, message", [
    (["--time", "1", "-o", "x.npz"], "--time needs --state"),
    ([], "nothing to write"),
    (["-o", "x.xlsx"], "unknown export format"),
    (["--state", "RUN", "--time", "9", "-o", "x.npz"], "outside the trajectory's span"),
    (["--known", "O.Fz=1", "-o", "x.npz"], "no reaction component 'O.Fz'"),
])
def test_cli_export_bad_requests_exit_2_with_one_message(tmp_path, args, message):
    run, _ = _pendulum_run(tmp_path)
    args = [str(run) if a == "RUN" else a for a in args]
    r = _mbody("export", MODELS / "pendulum.yaml", *args, cwd=tmp_path)
    assert r.returncode == 2
    assert message in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "x.npz").exists()


def test_cli_export_rejects_a_trajectory_of_another_model(tmp_path):
    run, _ = _pendulum_run(tmp_path)
    r = _mbody("export", MODELS / "seed_example_1.yaml", "--state", run, "-o",
               tmp_path / "x.json")
    assert r.returncode == 2 and "another model" in r.stderr


def test_cli_export_json_with_known_value(tmp_path):
    r = _mbody("export", MODELS / "pendulum.yaml", "--known", "O.Fx=0", "-o",
               tmp_path / "k.json")
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "k.json").read_text())
    assert [c["known"] for c in doc["columns"]] == [0.0, None]
    assert doc["state"]["source"] == "the model's initial state (t = 0 s)"


def test_cli_export_unwritable_target_is_one_message(tmp_path):
    (tmp_path / "taken.npz").mkdir()
    r = _mbody("export", MODELS / "pendulum.yaml", "-o", tmp_path / "taken.npz")
    assert r.returncode == 2 and "cannot write" in r.stderr and "is a folder" in r.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["taken.npz"]  # no temporary file left
    (tmp_path / "file").write_text("x")
    r = _mbody("export", MODELS / "pendulum.yaml", "--csv", tmp_path / "file")
    assert r.returncode == 2 and "exists and is not a folder" in r.stderr


@pytest.mark.parametrize("name", ["fourbar_spatial", "slider_crank", "gyroscope_gimbals",
                                  "heavy_top", "rotated_full_inertia"])
def test_export_solves_like_the_assembly(name, tmp_path):
    """One constrained solver: an export solves exactly as the assembly it came from,
    redundant joints included (minimum-norm reactions, the same components named)."""
    model = mbody.load(Path(__file__).resolve().parent.parent / "models" / f"{name}.yaml")
    asm = mbody.assemble(model)
    want = asm.solve()
    ex.write_export(asm, tmp_path / "eqs.npz")
    got = mbody.load_export(tmp_path / "eqs.npz").solve()
    assert got.solved == want.solved and got.not_unique == want.not_unique
    assert got.redundant == want.redundant
    np.testing.assert_allclose(got.accelerations, want.accelerations, rtol=1e-12,
                               atol=1e-12 * np.abs(want.accelerations).max())
    a = np.array([want.reactions[r] for r in model.reactions])
    b = np.array([got.reactions[r] for r in model.reactions])
    if len(a):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * np.abs(a).max())


def test_an_assemblys_arrays_cannot_be_edited_in_place():
    """`solve` works from the model and state, an export from M, b, Q and G: an edit in
    place would make the two disagree, so the arrays refuse it (as a Model's do)."""
    asm = mbody.assemble(mbody.load(MODELS / "double_pendulum.yaml"))
    for name in ("b", "Q"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(asm, name)[1] += 100.0
    for name in ("M", "G"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(asm, name).data[0] = 1.0
    assert np.array_equal(ex.exported(asm).solve().accelerations, asm.solve().accelerations)

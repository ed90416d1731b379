"""Trajectory files: round trip, the model carried along, and clear errors for bad files."""

from __future__ import annotations

import dataclasses
import inspect
import json
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.equations.constraints import ConstraintJacobian
from mbody.errors import TrajectoryFileError
from mbody.simulate.run_file import FORMAT, FORMAT_VERSION
from mbody.simulate.trajectory import Trajectory

MODELS = Path(__file__).resolve().parent.parent / "models"


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> tuple[Trajectory, Path]:
    traj = mbody.simulate(mbody.load(MODELS / "satellite_thruster.yaml"), t_end=1.0, fps=20)
    path = tmp_path_factory.mktemp("runs") / "run.npz"
    traj.save(path)
    return traj, path


def test_round_trip(run):
    traj, path = run
    back = Trajectory.load(path)
    for k in ("t", "position", "velocity", "orientation", "angular_velocity", "reactions",
              "mass", "inertia", "gravity"):
        np.testing.assert_array_equal(getattr(back, k), getattr(traj, k))
    for k in ("body_names", "dimension", "model_name", "model_file", "reaction_labels",
              "shapes", "colors", "model_yaml"):
        assert getattr(back, k) == getattr(traj, k), k
    assert back.info == json.loads(json.dumps(traj.info))
    assert set(back.series) == {"kinetic_energy", "potential_energy", "energy",
                                "angular_momentum"}
    np.testing.assert_array_equal(back.series["energy"], traj.series["energy"])
    assert back.shapes == ({"cylinder": {"radius": 1.2, "length": 1.5}},)


def test_planar_round_trip_and_state(tmp_path):
    model = mbody.load(MODELS / "planar_time_varying_force.yaml")
    traj = mbody.simulate(model, t_end=0.5, fps=10)
    traj.save(tmp_path / "p.npz")
    back = Trajectory.load(tmp_path / "p.npz")
    assert back.position.shape == (6, 1, 2) and back.orientation.shape == (6, 1)
    s = back.state(5)
    np.testing.assert_allclose(s.position[0, :2], traj.position[5, 0])
    assert s.t == 0.5 and s.omega[0, 2] == traj.angular_velocity[5, 0]


def test_a_sample_out_of_range_or_a_time_where_an_index_goes(run):
    """state(k) names the sample range (before: numpy's 'index 100 is out of bounds for
    axis 0'); a float is a time: the message points to state_at, which gives the sample
    nearest it, never an interpolation."""
    traj, _ = run   # 21 samples, 0.05 s apart
    with pytest.raises(IndexError) as err:
        traj.state(100)
    assert "sample 100 is out of range" in str(err.value)
    assert "21 samples, 0..20" in str(err.value)
    with pytest.raises(IndexError, match="sample -22 is out of range"):
        traj.state(-22)
    assert traj.state(-21).t == traj.state(0).t == 0.0
    assert traj.state(np.int64(20)).t == traj.t[20]
    with pytest.raises(TypeError) as err:
        traj.state(0.5)
    assert str(err.value).startswith("k must be a sample's index, a whole number 0..20")
    assert ".state_at(0.5)" in str(err.value)
    for time, k in ((0.5, 10), (0.51, 10), (0.53, 11), (1.0, 20)):
        assert traj.nearest_sample(time) == k
        s = traj.state_at(time)
        assert s.t == traj.t[k] and np.array_equal(s.position, traj.state(k).position)
    with pytest.raises(mbody.MbodyError, match=r"outside the trajectory's span \[0, 1\] s"):
        traj.state_at(1.2)
    with pytest.raises(TypeError, match="^time must be a time in seconds"):
        traj.state_at("0.5")


def test_model_travels_with_the_run(run):
    traj, path = run
    model = Trajectory.load(path).model()
    assert model.body_names == ("satellite",) and model.bodies["satellite"].mass == 500
    assert "300*exp(-t/4)" in traj.model_yaml


def test_kinetic_energy_and_momentum_by_hand(run):
    traj, _ = run
    k = 10
    m, J = 500.0, np.diag([400.0, 400, 600])
    v, w = traj.velocity[k, 0], traj.angular_velocity[k, 0]
    assert traj.kinetic_energy()[k] == pytest.approx(0.5 * m * v @ v + 0.5 * w @ J @ w,
                                                     rel=1e-14)
    from mbody.util.spatial import quat_to_matrix

    R = quat_to_matrix(traj.orientation[k, 0])
    H = np.cross(traj.position[k, 0], m * v) + R @ J @ w
    np.testing.assert_allclose(traj.angular_momentum()[k], H, rtol=1e-13)


def test_truncated_file(run, tmp_path):
    _, path = run
    data = path.read_bytes()
    for cut in (10, len(data) // 2, len(data) - 30):
        bad = tmp_path / f"cut{cut}.npz"
        bad.write_bytes(data[:cut])
        with pytest.raises(TrajectoryFileError, match="damaged or truncated"):
            Trajectory.load(bad)


def test_wrong_kinds(run, tmp_path):
    with pytest.raises(TrajectoryFileError, match="YAML model file"):
        Trajectory.load(MODELS / "pendulum.yaml")
    with pytest.raises(TrajectoryFileError, match="no such file"):
        Trajectory.load(tmp_path / "missing.npz")
    with pytest.raises(TrajectoryFileError, match="directory"):
        Trajectory.load(tmp_path)
    other = tmp_path / "other.npz"
    np.savez(other, a=np.zeros(3))
    with pytest.raises(TrajectoryFileError, match="no 'format' entry"):
        Trajectory.load(other)
    tagged = tmp_path / "tagged.npz"
    np.savez(tagged, format=np.array("mbody-assembly"), version=np.array(1))
    with pytest.raises(TrajectoryFileError, match="'mbody-assembly' file"):
        Trajectory.load(tagged)
    newer = tmp_path / "newer.npz"
    np.savez(newer, format=np.array(FORMAT), version=np.array(FORMAT_VERSION + 1))
    with pytest.raises(TrajectoryFileError, match="upgrade mbody"):
        Trajectory.load(newer)
    partial = tmp_path / "partial.npz"
    np.savez(partial, format=np.array(FORMAT), version=np.array(FORMAT_VERSION),
             t=np.zeros(3))
    with pytest.raises(TrajectoryFileError, match="missing position"):
        Trajectory.load(partial)


def test_inconsistent_shapes(run, tmp_path):
    _, path = run
    with np.load(path) as z:
        data = dict(z)
    data["position"] = data["position"][:-1]
    bad = tmp_path / "shapes.npz"
    np.savez(bad, **data)
    with pytest.raises(TrajectoryFileError, match="'position' has shape"):
        Trajectory.load(bad)


def test_save_is_atomic(run, tmp_path, monkeypatch):
    traj, _ = run
    target = tmp_path / "keep.npz"
    target.write_bytes(b"old")

    def fail(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez_compressed", fail)
    with pytest.raises(OSError):
        traj.save(target)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.npz"]


def test_cli_bad_trajectory_exits_2_without_traceback(run, tmp_path, capsys):
    _, path = run
    bad = tmp_path / "cut.npz"
    bad.write_bytes(path.read_bytes()[:100])
    for f in (bad, MODELS / "pendulum.yaml"):
        assert main(["plot", str(f), "-o", str(tmp_path / "x.png")]) == 2
        err = capsys.readouterr().err
        assert err.startswith("mbody: error: ") and str(f) in err and "Traceback" not in err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("cls", [Trajectory, ConstraintJacobian])
def test_the_written_out_init_takes_the_fields_in_order(cls):
    """`Trajectory` and `ConstraintJacobian` write their dataclass __init__ out (the
    generated one costs its compile at every import): it must take exactly the fields, in
    their order, with the same defaults, so that a field added later cannot be missed."""
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    fields = dataclasses.fields(cls)
    assert [p.name for p in params] == [f.name for f in fields]
    for p, f in zip(params, fields, strict=True):
        if f.default is not dataclasses.MISSING:
            assert p.default == f.default, f.name
        elif f.default_factory is not dataclasses.MISSING:
            assert p.default is None, f.name  # None: the field's default_factory
        else:
            assert p.default is inspect.Parameter.empty, f.name
    made = cls(*[object() for f in fields if f.default is dataclasses.MISSING
                 and f.default_factory is dataclasses.MISSING])
    for f in fields:  # each default_factory field made, as the generated __init__ would
        if f.default_factory is not dataclasses.MISSING:
            want = f.default_factory()
            assert type(getattr(made, f.name)) is type(want), f.name
            assert np.shape(getattr(made, f.name)) == np.shape(want), f.name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(made, fields[0].name, 0)


def test_a_run_with_values_set_rebuilds_the_model_it_ran(tmp_path, capsys):
    """`--set` (Model.with_values) changes the model after its text was read: the saved
    run lists the values (info["model_values"]) and `Trajectory.model` sets them again,
    so the rebuilt model runs the same motion."""
    path = tmp_path / "run.npz"
    code = main(["simulate", str(MODELS / "pendulum.yaml"), "--t-end", "1", "--no-progress",
                 "--set", "bodies.rod.mass=4", "-o", str(path)])
    capsys.readouterr()
    assert code == 0
    traj = Trajectory.load(path)
    assert traj.info["model_values"] == [["bodies.rod.mass", 4]]  # the value --set
    model = traj.model()
    assert float(model.mass[0]) == 4.0 == float(traj.mass[0])
    again = mbody.simulate(model, t_end=1)
    np.testing.assert_array_equal(again.position, traj.position)
    plain = mbody.load(MODELS / "pendulum.yaml")
    assert "model_values" not in mbody.simulate(plain, t_end=1).info
    twice = plain.with_values({"bodies.rod.mass": 5}).with_values({"bodies.rod.mass": 3})
    run = mbody.simulate(twice, t_end=0.1)
    assert len(run.info["model_values"]) == 2 and float(run.model().mass[0]) == 3.0


@pytest.mark.parametrize("file", ["robots/two_link_arm.urdf", "robots/two_link_arm.xml"])
def test_a_run_of_an_mjcf_or_urdf_model_carries_its_yaml_form(file):
    """An MJCF or URDF model's run carries the model's YAML form (not the XML, which
    `loads` cannot read): `Trajectory.model` rebuilds it and runs the same motion."""
    model = mbody.load(MODELS / file)
    traj = mbody.simulate(model, 0.5, 10)
    assert traj.model_yaml.startswith("# Converted by mbody") and "<" not in traj.model_yaml
    rebuilt = traj.model()
    assert rebuilt.body_names == model.body_names
    again = mbody.simulate(rebuilt, 0.5, 10)
    # the YAML form writes every number so that it reads back as the same double
    np.testing.assert_allclose(again.position, traj.position, rtol=0, atol=1e-12)


def test_a_run_of_a_text_or_a_dictionary_carries_it():
    """A model given as text (`loads`) or as a dictionary keeps it for its runs."""
    text = (MODELS / "pendulum.yaml").read_text(encoding="utf-8")
    for model in (mbody.loads(text), mbody.load(mbody.load(MODELS / "pendulum.yaml")
                                                .source.read().data)):
        traj = mbody.simulate(model, 0.5, 10)
        again = mbody.simulate(traj.model(), 0.5, 10)
        np.testing.assert_array_equal(again.position, traj.position)

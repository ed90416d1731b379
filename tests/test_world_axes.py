"""Reactions in world axes (`--axes world`, ``axes="world"``) on runs, plots, the report
and exports: the values against each body's Newton-Euler equations written out here,
against `Assembly.solve(axes="world")` at a sample's state, and a run made in joint axes
turned into world axes afterwards against one made in world axes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import mbody
from mbody.simulate.axes import in_world_axes
from mbody.util.spatial import quat_to_matrix

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
EPS = np.finfo(float).eps


def _model(name: str) -> mbody.Model:
    return mbody.load(MODELS / f"{name}.yaml")


def _mbody(*args: str | Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mbody", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)


def newton_euler_residuals(model: mbody.Model, state: mbody.State,
                           world: dict[str, float], couples: dict[str, list[float]],
                           forces: dict[str, list[float]] | None = None
                           ) -> tuple[float, float]:
    """Each body's Newton and Euler equations in world axes with the joints' world forces F
    and moments M (on the child at the joint point; −F, −M on the parent) and the drivers'
    efforts along their axes, the accelerations solved at `state`:

        m a = m g + Σ ±F + forces,    R (J ω̇ + ω × J ω) = Σ ±((P − x_G) × F + M) + couples

    (`couples` and `forces`, at the mass centres: the applied loads, world axes).

    Returns the largest residual of each kind relative to its largest term."""
    asm = mbody.assemble(model, state)
    sol = asm.solve()
    cols = asm.columns
    rt = model.reaction_table
    n = model.n
    planar = model.dimension == 2
    acc = np.asarray(sol.accelerations).reshape(n, -1)
    a = np.zeros((n, 3))
    wdot = np.zeros((n, 3))
    if planar:
        a[:, :2], wdot[:, 2] = acc[:, :2], acc[:, 2]
    else:
        a, wdot = acc[:, :3], acc[:, 3:]
    x = np.asarray(state.position)
    R = quat_to_matrix(np.asarray(state.quaternion))
    w = np.asarray(state.omega)
    J = np.asarray(model.J)
    mass = np.asarray(model.mass)
    g = np.asarray(model.gravity)
    force = mass[:, None] * g
    moment = np.zeros((n, 3))
    force_terms = [np.abs(mass[:, None] * a).max(), np.abs(force).max()]
    moment_terms = []
    index = {b: i for i, b in enumerate(model.body_names)}
    for body, c in couples.items():
        moment[index[body]] += c
    for body, f in (forces or {}).items():
        force[index[body]] += f
    labels = list(model.reactions)

    def act(child: str, parent: str, P: np.ndarray, F: np.ndarray, M: np.ndarray) -> None:
        for body, sign in ((child, 1.0), (parent, -1.0)):
            if body in index:
                i = index[body]
                force[i] += sign * F
                moment[i] += sign * (np.cross(P - x[i], F) + M)
        force_terms.append(float(np.abs(F).max()))
        moment_terms.append(float(np.abs(np.cross(P - x[index[child]], F) + M).max()))

    for j, joint in enumerate(model.joints):
        c = int(np.flatnonzero(rt.joint[:len(labels) - len(rt.driver_names)] == j)[0])
        F = np.array([world.get(f"{joint.name}.F{ax}", 0.0) for ax in "xyz"])
        M = np.array([world.get(f"{joint.name}.M{ax}", 0.0) for ax in "xyz"])
        act(joint.child, joint.parent, cols.W_P[c], F, M)
    for name in rt.driver_names:
        label = next(lab for lab in labels if lab.split(".")[0] == name)
        c = labels.index(label)
        joint = model.joints[int(rt.joint[c])]
        effort = world[label] * cols.W_e[c]
        moving = label.endswith(".M")
        act(joint.child, joint.parent, cols.W_P[c], 0 * effort if moving else effort,
            effort if moving else 0 * effort)
    newton = mass[:, None] * a - force
    Jw = np.einsum("nij,nj->ni", J, w)
    euler_body = np.einsum("nij,nj->ni", J, wdot) + np.cross(w, Jw)
    euler = np.einsum("nij,nj->ni", R, euler_body) - moment
    moment_terms.append(float(np.abs(euler_body).max()))
    return (float(np.abs(newton).max() / max(force_terms)),
            float(np.abs(euler).max() / max(max(moment_terms), 1e-300)))


# -- simulate ------------------------------------------------------------------------------

@pytest.mark.parametrize("name, couples", [
    ("double_pendulum", {}),                          # planar, integrated
    ("fourbar_spatial", {}),                          # spatial, redundant joints
    ("gyroscope_gimbals", {"inner": [0.05, 0, 0]}),   # a 200 rad/s rotor, a world couple
    ("flyball_governor", {}),                         # partly driven: integrated
    ("slider_crank_driven", {}),                      # fully driven: the kinematic run
])
def test_a_world_axes_run_keeps_each_bodys_newton_euler_equations(name, couples):
    """At every tenth sample the stored world forces and moments balance each body's
    m a and R (J ω̇ + ω × J ω), and equal `Assembly.solve(axes="world")` at the sample's
    state. The solve's backward error is below 1e-14 on these models, so both hold to far
    better than 1e-10 of their largest term."""
    model = _model(name)
    if name == "slider_crank_driven":  # without its gas force: gravity alone is applied
        doc = yaml.safe_load((MODELS / f"{name}.yaml").read_text())
        del doc["loads"]
        model = mbody.loads(yaml.safe_dump(doc))
    traj = mbody.simulate(model, 0.5, 40, axes="world")
    assert traj.info["reaction_axes"] == "world"
    labels = traj.reaction_labels
    assert all(lab.rsplit(".", 1)[1] in ("Fx", "Fy", "Fz", "Mx", "My", "Mz", "M", "F")
               for lab in labels)
    scale = float(np.abs(traj.reactions).max())
    for k in range(0, len(traj), 10):
        state = traj.state(k)
        values = dict(zip(labels, traj.reactions[k].tolist(), strict=True))
        newton, euler = newton_euler_residuals(model, state, values, couples)
        assert newton < 1e-10 and euler < 1e-10, (k, newton, euler)
        solved = mbody.assemble(model, state).solve(axes="world")
        assert list(solved.reactions) == list(labels)
        # the same state up to the planar angle's rounding (its quaternion from θ/2)
        tol = 16 * EPS * max(1.0, float(np.abs(traj.orientation).max())) * scale
        assert np.abs(np.array(list(solved.reactions.values())) - traj.reactions[k]).max() \
            <= tol, k


@pytest.mark.parametrize("name, t_end, fps", [
    ("double_pendulum", 10.0, 30),
    ("slider_crank", 2.0, 30),            # planar, a wheel that turns many times
    ("fourbar_spatial", 1.0, 30),
    ("flyball_governor", 1.0, 30),
    ("slider_crank_driven", 0.5, 40),     # samples 0.6 revolution apart
])
def test_a_joint_axes_run_turned_into_world_axes_equals_a_world_axes_run(
        tmp_path, name, t_end, fps):
    """Saved in joint axes, read back and turned into world axes with the model it
    carries, a run equals the same run made in world axes: labels, values (to the
    rounding of a planar angle's quaternion, θ/2 of a large θ), peaks and energy check."""
    model = _model(name)
    joint = mbody.simulate(model, t_end, fps)
    assert joint.info["reaction_axes"] == "joint"
    joint.save(tmp_path / "run.npz")
    turned = in_world_axes(mbody.Trajectory.load(tmp_path / "run.npz"))
    world = mbody.simulate(model, t_end, fps, axes="world")
    assert turned.info["reaction_axes"] == "world"
    assert turned.reaction_labels == world.reaction_labels
    scale = float(np.abs(world.reactions).max())
    # not the joint-frame values: some joint frame turns with its parent
    assert turned.reaction_labels != joint.reaction_labels or \
        np.abs(turned.reactions - joint.reactions).max() > 1e-3 * scale
    angle = float(np.abs(world.orientation).max()) if model.dimension == 2 else 1.0
    np.testing.assert_allclose(turned.reactions, world.reactions, rtol=0,
                               atol=16 * EPS * max(1.0, angle) * scale)
    if "peaks" in world.info:
        assert [p["label"] for p in turned.info["peaks"]] == \
            [p["label"] for p in world.info["peaks"]]
        for key in ("energy_balance_residual", "power_balance_residual", "driver_work"):
            assert turned.info[key] == world.info[key] == joint.info[key], key
    # drivers' efforts are kept as they are
    for lab in joint.reaction_labels:
        if lab.split(".")[0] in (model.drivers.names if model.drivers else ()):
            np.testing.assert_array_equal(
                world.reactions[:, world.reaction_labels.index(lab)],
                joint.reactions[:, joint.reaction_labels.index(lab)])
    assert in_world_axes(world) is world  # already in world axes: as it is


def test_a_pin_in_world_axes_is_the_same_force_whatever_the_parent_turns():
    """The double pendulum's pin A is along its parent's (the upper rod's) frame in
    joint axes, so its components turn with that rod, yet |F| is the same in both axes
    and the world components are the joint ones turned by the rod's angle."""
    model = _model("double_pendulum")
    joint = mbody.simulate(model, 2.0, 20)
    world = in_world_axes(joint)
    jl, wl = joint.reaction_labels, world.reaction_labels
    Fj = joint.reactions[:, [jl.index("A.Fx"), jl.index("A.Fy")]]
    Fw = world.reactions[:, [wl.index("A.Fx"), wl.index("A.Fy")]]
    turn = joint.orientation[:, 0] - joint.orientation[0, 0]  # upper's, from the file's
    c, s = np.cos(turn), np.sin(turn)
    # the joint frame is world-aligned at the file's pose, then turns with the parent
    rotated = np.stack((c * Fj[:, 0] - s * Fj[:, 1], s * Fj[:, 0] + c * Fj[:, 1]), axis=1)
    scale = float(np.abs(Fw).max())
    assert np.abs(rotated - Fw).max() < 1e-13 * scale
    assert np.abs(np.linalg.norm(Fj, axis=1) - np.linalg.norm(Fw, axis=1)).max() \
        < 1e-13 * scale


def test_turning_a_run_into_world_axes_needs_its_model():
    model = _model("double_pendulum")
    traj = mbody.simulate(model, 0.2, 20)
    bare = mbody.Trajectory(traj.t, traj.position, traj.velocity, traj.orientation,
                            traj.angular_velocity, traj.body_names, traj.dimension,
                            reaction_labels=traj.reaction_labels, reactions=traj.reactions)
    with pytest.raises(mbody.MbodyError, match="does not carry its model"):
        in_world_axes(bare)
    assert np.array_equal(in_world_axes(bare, model).reactions, in_world_axes(traj).reactions)
    with pytest.raises(mbody.MbodyError, match="not those of the model"):
        in_world_axes(traj, _model("triple_pendulum"))
    with pytest.raises(mbody.MbodyError, match="axes must be 'joint' or 'world'"):
        mbody.simulate(model, 0.2, 20, axes="body")
    # an imported model's run keeps no YAML to rebuild it from: given, it converts
    arm = mbody.load(MODELS / "robots" / "two_link_arm.xml")
    run = mbody.simulate(arm, 0.2, 20)
    with pytest.raises(mbody.MbodyError, match="imported model.*pass the model"):
        in_world_axes(run)
    world = mbody.simulate(arm, 0.2, 20, axes="world")
    np.testing.assert_allclose(in_world_axes(run, arm).reactions, world.reactions, rtol=0,
                               atol=1e-13 * np.abs(world.reactions).max())


def test_simulate_and_plot_from_the_command_line_in_world_axes(tmp_path):
    """`simulate --axes world` saves world-axes reactions (the summary says so); `plot
    --axes world` of a joint-axes run draws the converted run; `plot --axes joint` of a
    world-axes run is refused with the way out; the figures' titles say the axes."""
    from mbody.present.plot import plot_trajectory

    run_w, run_j = tmp_path / "w.npz", tmp_path / "j.npz"
    p = _mbody("simulate", "models/double_pendulum.yaml", "--t-end", "1", "--axes",
               "world", "-o", run_w)
    assert p.returncode == 0, p.stderr
    assert "reactions stored in world axes" in p.stdout
    w = mbody.Trajectory.load(run_w)
    assert w.info["reaction_axes"] == "world" and w.reaction_labels[:2] == ("O.Fx", "O.Fy")
    assert _mbody("simulate", "models/double_pendulum.yaml", "--t-end", "1", "-o",
                  run_j).returncode == 0
    j = mbody.Trajectory.load(run_j)
    np.testing.assert_allclose(in_world_axes(j).reactions, w.reactions, rtol=0,
                               atol=1e-13 * np.abs(w.reactions).max())
    for run, extra in ((run_j, ("--axes", "world")), (run_w, ()), (run_j, ())):
        out = tmp_path / f"{run.stem}{len(extra)}.png"
        p = _mbody("plot", run, "-o", out, *extra)
        assert p.returncode == 0, p.stderr
        assert out.stat().st_size > 10_000
    p = _mbody("plot", run_w, "-o", tmp_path / "x.png", "--axes", "joint")
    assert p.returncode == 2 and "world axes" in p.stderr and "Traceback" not in p.stderr
    assert not (tmp_path / "x.png").exists()
    for traj, words in ((in_world_axes(j), "world axes"), (j, "joint axes")):
        fig = plot_trajectory(traj)
        titles = [a.get_title() for a in fig.axes]
        assert any(t.startswith("joint reaction forces, " + words)
                   for t in titles), titles
        assert fig.get_suptitle().endswith("reactions in " + words)


def test_plot_of_a_driven_run_in_world_axes(tmp_path):
    """A kinematic run saved in joint axes, plotted with --axes world: the drivers'
    figure says world axes; the bearing loads |F| are the same in both."""
    from mbody.present.drive_plot import plot_driven

    run = tmp_path / "run.npz"
    assert _mbody("kinematics", "models/slider_crank_driven.yaml", "-o", run).returncode == 0
    p = _mbody("plot", run, "-o", tmp_path / "a.png", "--axes", "world")
    assert p.returncode == 0, p.stderr
    joint = mbody.Trajectory.load(run)
    world = in_world_axes(joint)
    fig = plot_driven(world)
    assert "reactions in world axes" in fig.get_suptitle()
    assert any("world axes" in a.get_title() for a in fig.axes)
    bearing_j = next(a for a in plot_driven(joint).axes if a.get_title().startswith("bearing"))
    bearing_w = next(a for a in fig.axes if a.get_title().startswith("bearing"))
    for lj, lw in zip(bearing_j.lines, bearing_w.lines, strict=True):
        assert lj.get_label() == lw.get_label()
        y = np.asarray(lj.get_ydata())
        assert np.abs(y - np.asarray(lw.get_ydata())).max() < 1e-12 * y.max()
    j = json.loads(_mbody("kinematics", "models/slider_crank_driven.yaml", "--json").stdout)
    assert j["reaction_axes"] == "joint"


def test_the_same_state_drawn_at_another_angle_gives_the_same_world_axes_values():
    """The issue's complaint: the driven slider-crank's file drawn with its crank at 30 deg
    and at 60 deg (joint frames world-aligned at the file's pose) gives other joint-frame
    values for the crank pin A at the same crank angle, and the same world-axes values.
    One sample a degree: the first file's sample k + 30 is the second's sample k. Both
    runs close their loops to 1e-12 of the size (CLOSE_RTOL), so they agree to that."""
    from mbody.simulate.kinematic import kinematic_run

    doc = yaml.safe_load((MODELS / "slider_crank_driven.yaml").read_text())
    del doc["loads"]  # the gas law is written in time from the 30 deg start
    at30 = mbody.loads(yaml.safe_dump(doc))
    doc["bodies"][0].update(angle="60 deg", position=[0.0125, 0.0217])
    doc["bodies"][1].update(angle="-16 deg", position=[0.102, 0.0217])
    doc["bodies"][2].update(position=[0.18, 0])
    at60 = mbody.loads(yaml.safe_dump(doc))
    fps = 3600.0  # 600 rpm: one degree a sample
    runs = {}
    for axes in ("joint", "world"):
        a = kinematic_run(at30, 0.05, fps, axes=axes)
        b = kinematic_run(at60, 0.05, fps, axes=axes)
        k = len(a) - 30
        np.testing.assert_allclose(a.orientation[30:, 0], b.orientation[:k, 0], rtol=0,
                                   atol=1e-12)
        runs[axes] = (a.reaction_labels, a.reactions[30:], b.reactions[:k])
    labels, a, b = runs["joint"]
    A = [labels.index("A.Fx"), labels.index("A.Fy")]
    assert np.abs(a[:, A] - b[:, A]).max() > 0.1 * np.abs(a[:, A]).max()
    labels, a, b = runs["world"]
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-11 * np.abs(a).max())


# -- report ---------------------------------------------------------------------------------

def _table(page: str, table_id: str) -> list[list[str]]:
    import re

    m = re.search(rf'<table class="solution" id="{table_id}">(.*?)</table>', page, re.S)
    assert m, f"no table {table_id}"
    return [[re.sub(r"<[^>]+>", "", c) for c in re.findall(r"<t[dh]>(.*?)</t[dh]>", row)]
            for row in re.findall(r"<tr>(.*?)</tr>", m.group(1))]


@pytest.mark.parametrize("name, couples", [("slider_crank", {"crank": [0, 0, -60]}),
                                           ("gyroscope_gimbals", {"inner": [0.05, 0, 0]})])
def test_the_report_in_world_axes(tmp_path, name, couples):
    """`mbody report --axes world`: the reactions table is `Assembly.solve(axes="world")`
    to the 6 digits it prints, under a heading that says world axes, and those values
    balance each body (Newton-Euler) to that printing; the accelerations are those of
    the joint-axes page."""
    from mbody.present.report import report_html

    model = _model(name)
    if name == "slider_crank":  # its gas force is left out here, its couple kept (t = 0)
        doc = yaml.safe_load((MODELS / f"{name}.yaml").read_text())
        doc["loads"] = [ld for ld in doc["loads"] if ld["type"] != "force"]
        model = mbody.loads(yaml.safe_dump(doc))
        assert not model.forces.names or all(model.forces.couple)
    page = report_html(model, axes="world")
    assert "<h3>Joint reactions in world axes</h3>" in page
    rows = _table(page, "reactions")
    assert rows[0] == ["reaction", "value", "unit", "acts", "status"]
    sol = mbody.assemble(model).solve(axes="world")
    assert [r[0] for r in rows[1:]] == list(sol.reactions)
    got = np.array([float(r[1]) for r in rows[1:]])
    want = np.array(list(sol.reactions.values()))
    np.testing.assert_allclose(got, want, rtol=5e-6, atol=1e-10 * np.abs(want).max())
    assert all(r[2] == ("N·m" if ".M" in r[0] else "N") for r in rows[1:])
    assert all(r[3].startswith("on ") and r[4] == "solved" for r in rows[1:])
    newton, euler = newton_euler_residuals(model, model.initial,
                                           dict(zip(sol.reactions, got.tolist(),
                                                    strict=True)), couples)
    assert newton < 1e-5 and euler < 1e-5  # 6 significant digits printed
    assert _table(page, "accelerations") == _table(report_html(model), "accelerations")
    out = tmp_path / "r.html"
    p = _mbody("report", MODELS / f"{name}.yaml", "--axes", "world", "-o", out)
    assert p.returncode == 0, p.stderr
    assert "Joint reactions in world axes" in out.read_text()


# -- exports ---------------------------------------------------------------------------------

JACK = {"model": "jack", "dimension": 3, "gravity": [0, 0, -9.81],
        "bodies": [{"name": "nut", "mass": 50.0, "inertia": [0.03, 0.03, 0.02],
                    "position": [0, 0, 0.2], "angular_velocity": [0, 0, 4.0],
                    "velocity": [0, 0, 4.0 * 0.005 / (2 * np.pi)]}],
        "loads": [{"name": "turn", "type": "torque", "body": "nut", "torque": [0, 0, 3.0]}],
        "joints": [{"name": "H", "type": "helical", "parent": "ground", "child": "nut",
                    "at": [0, 0, 0.2], "axis": [0, 0, 1], "pitch": 0.005}]}
"""A nut on a vertical screw (tests/test_new_joint_types.py's screw jack): one helical
joint, whose axial wrench Wz is a force along the screw and −(pitch/2π) Wz about it."""


def _export_models() -> list[tuple[str, mbody.Model]]:
    out = [(name, _model(name)) for name in ("slider_crank_driven", "fourbar_spatial",
                                              "point_pendulum", "practice_1_translation")]
    return out + [("jack", mbody.loads(yaml.safe_dump(JACK)))]


def _write(exp, tmp_path: Path, fmt: str) -> Path:
    from mbody.io import export as ex

    if fmt == "csv":
        return ex.write_csv(exp, tmp_path / "csv")
    return ex.write_export(exp, tmp_path / f"eqs.{fmt}")


@pytest.mark.parametrize("fmt", ["npz", "mat", "json", "csv"])
def test_an_export_in_world_axes_round_trips_and_solves_like_the_assembly(tmp_path, fmt):
    """Every format writes the map T and its labels and reads them back bit for bit; the
    reloaded export's solve in world axes is `Assembly.solve(axes="world")` (the same
    components summed, in another order: to rounding); T λ equals the world series
    of `mbody.equations.world` for any λ (it is that sum's matrix)."""
    from mbody.equations.world import world_reaction_series
    from mbody.io import export as ex

    rng = np.random.default_rng(25)
    for name, model in _export_models():
        asm = mbody.assemble(model)
        exp = ex.exported(asm, axes="world")
        back = ex.load_export(_write(exp, tmp_path / name, fmt))
        assert back.differences(exp) == [], name
        assert back.T is not None and back.world_reactions == exp.world_reactions
        assert back.shape["T"] == (len(exp.world_reactions), len(model.reactions))
        m = len(model.reactions)
        lam = rng.standard_normal((3, m))
        labels, series = world_reaction_series(model, np.repeat(asm.columns.W_e[None], 3, 0),
                                               lam)
        assert list(labels) == back.world_reactions
        np.testing.assert_allclose((back.T @ lam.T).T, series, rtol=0,
                                   atol=1e-14 * max(1.0, np.abs(series).max(initial=0)))
        if not m:
            assert back.T.shape == (0, 0)
            continue
        want = asm.solve(axes="world")
        got = back.solve(axes="world")
        assert got.axes == "world" and list(got.reactions) == list(want.reactions)
        a, b = np.array(list(want.reactions.values())), np.array(list(got.reactions.values()))
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-13 * np.abs(a).max())
        assert back.solve().reactions == asm.solve().reactions  # joint axes as before


def test_a_screw_jacks_world_axes_from_its_export():
    """The helical joint's axial wrench Wz: world H.Fz = Wz (the screw pushes the nut up)
    and H.Mz = −(pitch/2π) Wz, with Wz = m (z̈ + g) (tests/test_new_joint_types.py)."""
    from mbody.io import export as ex

    model = mbody.loads(yaml.safe_dump(JACK))
    exp = ex.exported(mbody.assemble(model), axes="world")
    assert exp.world_reactions == ["H.Fx", "H.Fy", "H.Fz", "H.Mx", "H.My", "H.Mz"]
    h = 0.005 / (2 * np.pi)
    wz = exp.T.toarray()[:, exp.reactions.index("H.Wz")]
    assert wz == pytest.approx([0, 0, 1, 0, 0, -h], abs=1e-15)
    sol = exp.solve(axes="world")
    m, J, tau = 50.0, 0.02, 3.0
    Wz = m * (h * (tau - m * 9.81 * h) / (m * h * h + J) + 9.81)
    assert sol.reactions["H.Fz"] == pytest.approx(Wz, rel=1e-12)
    assert sol.reactions["H.Mz"] == pytest.approx(-h * Wz, rel=1e-12)


def test_the_map_with_scipy_alone_gives_forces_that_balance_each_body(tmp_path):
    """What coursework does with the npz file and no mbody: solve the joint-frame system
    by hand, then world = T λ: those forces satisfy each body's Newton-Euler equations."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from mbody.io import export as ex

    model = _model("slider_crank")
    path = ex.write_export(mbody.assemble(model), tmp_path / "eqs.npz", axes="world")
    z = np.load(path, allow_pickle=False)

    def mat(name: str) -> sp.csc_matrix:
        return sp.csc_matrix((z[f"{name}_data"], z[f"{name}_indices"], z[f"{name}_indptr"]),
                             shape=tuple(z[f"{name}_shape"]))

    M, G, T = mat("M"), mat("G"), mat("T")
    n, m = M.shape[0], G.shape[1]
    K = sp.bmat([[M, -G], [G.T, None]]).tocsc()
    x = spla.spsolve(K, np.concatenate((z["Q"] - z["b"], z["column_gamma"])))
    world = dict(zip(map(str, z["world_reactions"]), (T @ x[n:]).tolist(), strict=True))
    assert list(world) == list(mbody.assemble(model).solve(axes="world").reactions)
    newton, euler = newton_euler_residuals(model, model.initial, world, {"crank": [0, 0, -60]},
                                           forces={"piston": [-4000, 0, 0]})
    assert newton < 1e-10 and euler < 1e-10
    assert m == len(model.reactions)


def test_exports_without_the_map_and_version_1_files_still_read(tmp_path):
    """An export not asked for world axes holds no map (and says how to get one); a file
    written by the version 1 layout reads as before."""
    from mbody.io import export as ex

    asm = mbody.assemble(_model("double_pendulum"))
    exp = ex.exported(asm)
    assert exp.T is None and exp.world_reactions == [] and "T" not in exp.shape
    with pytest.raises(mbody.MbodyError, match="--axes world"):
        exp.solve(axes="world")
    with pytest.raises(mbody.MbodyError, match="axes must be"):
        ex.exported(asm, axes="body")
    # version 1 files, as the previous layout wrote them (the same fields, version 1)
    npz = ex.write_export(exp, tmp_path / "old.npz")
    arrays = dict(np.load(npz, allow_pickle=False))
    assert int(arrays["version"]) == ex.VERSION == 2 and "T_data" not in arrays
    arrays["version"] = np.array(1)
    np.savez(tmp_path / "v1.npz", **arrays)
    doc = json.loads(ex.write_export(exp, tmp_path / "old.json").read_text())
    assert "world" not in doc
    doc["version"] = 1
    (tmp_path / "v1.json").write_text(json.dumps(doc))
    folder = ex.write_csv(exp, tmp_path / "v1csv")
    assert not (folder / "T.csv").exists()
    info = (folder / "info.csv").read_text().replace("version,2", "version,1")
    (folder / "info.csv").write_text(info)
    for path in (tmp_path / "v1.npz", tmp_path / "v1.json", folder):
        old = ex.load_export(path)
        assert old.differences(exp) == [] and old.T is None, path
        np.testing.assert_array_equal(old.solve().accelerations, asm.solve().accelerations)
    # a version 1 file cannot hold a map: one that does was edited
    doc["world"] = ex.to_json(ex.exported(asm, axes="world"))["world"]
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    with pytest.raises(mbody.MbodyError, match="version 1 export holds no world-axes map"):
        ex.load_export(tmp_path / "bad.json")


def test_the_json_export_with_its_map_validates_against_the_schema(tmp_path):
    jsonschema = pytest.importorskip("jsonschema")
    from mbody.io import export as ex

    schema = ex.schema()
    doc = ex.to_json(ex.exported(mbody.assemble(_model("slider_crank_driven")), axes="world"))
    jsonschema.validate(doc, schema)
    assert doc["world"]["reactions"][-1] == "motor.M"
    bad = json.loads(json.dumps(doc))
    bad["world"]["T"]["shape"] = [3]
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(bad, schema)
    bad = json.loads(json.dumps(doc))
    bad["world"]["T"]["shape"] = [len(doc["world"]["reactions"]) + 1, len(doc["reactions"])]
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(mbody.MbodyError, match="world-axes map T is 11x9; expected 10x9"):
        ex.load_export(tmp_path / "bad.json")


def test_export_world_axes_from_the_command_line_at_a_runs_sample(tmp_path):
    """`mbody export MODEL --state RUN --time T --axes world`: T at the sample's state
    turns the export's own joint-frame solve into the world-axes run's values there."""
    from mbody.io import export as ex

    run = tmp_path / "run.npz"
    assert _mbody("simulate", "models/fourbar_planar.yaml", "--t-end", "0.5", "-o",
                  run).returncode == 0
    p = _mbody("export", "models/fourbar_planar.yaml", "--state", run, "--time", "0.3",
               "--axes", "world", "-o", tmp_path / "e.json", "-o", tmp_path / "e.mat",
               "--csv", tmp_path / "csv")
    assert p.returncode == 0, p.stderr
    assert "T.csv" in p.stdout and ", T 8x8 (" in p.stdout and "world axes = T lambda" in p.stdout
    world = in_world_axes(mbody.Trajectory.load(run))
    k = int(np.argmin(np.abs(world.t - 0.3)))
    for path in (tmp_path / "e.json", tmp_path / "e.mat", tmp_path / "csv"):
        got = ex.load_export(path).solve(axes="world")
        assert list(got.reactions) == list(world.reaction_labels)
        # the run's own solve at the same state (its quaternions from the stored angles,
        # a few radians: rounding)
        np.testing.assert_allclose(list(got.reactions.values()), world.reactions[k],
                                   rtol=0, atol=1e-13 * np.abs(world.reactions).max())
    p = _mbody("export", "models/fourbar_planar.yaml", "--axes", "sideways", "-o",
               tmp_path / "x.npz")
    assert p.returncode == 2 and "Traceback" not in p.stderr


def test_the_notebook_shows_a_world_axes_solution_and_run_as_such():
    """A world-axes `Solution` in a notebook says world axes and gives each joint the
    status of its components (a redundant four-bar: solved and not-unique ones mixed)."""
    import html
    import re

    from mbody.present.rich import solution_html, trajectory_html

    model = _model("fourbar_spatial")
    sol = mbody.assemble(model).solve(axes="world")
    page = html.unescape(solution_html(sol))
    assert "each joint's force and moment on its child, world axes" in page
    rows = re.findall(r"<tr><td>([^<]+)</td><td[^>]*>[^<]+</td><td>([^<]+)</td></tr>", page)
    assert [r[0] for r in rows] == list(sol.reactions)
    joint = mbody.assemble(model).solve()
    for label, status in rows:
        mine = {lab for lab in joint.solved if lab.split(".")[0] == label.split(".")[0]}
        free = mine & set(joint.not_unique)
        assert status == ("not unique" if free == mine else "partly solved" if free
                          else "solved"), label
    run = mbody.simulate(_model("double_pendulum"), 0.1, 20, axes="world")
    assert "O.Fx, O.Fy, A.Fx, A.Fy (world axes)" in trajectory_html(run)

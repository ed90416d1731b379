"""A run's figures at its samples, computed in C (`_core.conservation`, `_core.unit_samples`,
the step-rate marks of `_core.dop853_sampled`), against the numpy they replaced.

The compiled figures sum the same terms in another order, so they may differ from numpy's
in the last bits: a sum of N terms of size S carries a rounding error below N S 2⁻⁵² in
either; the tolerances below are 1e-12 of the terms' scale, some thousand times that for
the sizes here (at most 8 bodies, 4 springs).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest
from randmodels import planar_model, spatial_model
from scipy.spatial.transform import Rotation

import mbody
from mbody.equations.workspace import workspace
from mbody.kernel import _core
from mbody.simulate.mechanism import ANGULAR_MOMENTUM_ABOUT, conserved_figures, sample_figures

MODELS = Path(__file__).resolve().parent.parent / "models"
simulation = importlib.import_module("mbody.simulate.simulation")
RTOL = 1e-12


def random_samples(model: mbody.Model, K: int, rng: np.random.Generator) -> np.ndarray:
    """K random states in the core's layout: unit quaternions (planar: turns about z, with
    the carried angle), anything for the rest (the figures do not ask for closed joints)."""
    n = model.n
    Y = np.zeros((K, workspace(model).state_size))
    Y[:, :3 * n] = rng.normal(size=(K, 3 * n))
    Y[:, 7 * n:13 * n] = rng.normal(size=(K, 6 * n))
    if model.dimension == 2:
        theta = rng.uniform(-9, 9, (K, n))
        q = np.zeros((K, n, 4))
        q[..., 0], q[..., 3] = np.cos(theta / 2), np.sin(theta / 2)
        Y[:, 13 * n:] = theta
        for k in (2,):  # a planar state's out-of-plane parts are 0 (the core keeps them so)
            Y[:, k:3 * n:3] = 0.0
            Y[:, 7 * n + k:10 * n:3] = 0.0
        Y[:, 10 * n:13 * n].reshape(K, n, 3)[..., :2] = 0.0
    else:
        q = Rotation.random(K * n, random_state=rng).as_quat(scalar_first=True).reshape(K, n, 4)
    Y[:, 3 * n:7 * n] = q.reshape(K, -1)
    return Y


def numpy_figures(model: mbody.Model, Y: np.ndarray, about: str, lengths: np.ndarray | None):
    """T, V, H and the relative changes of E, p, H as simulate computed them in numpy (the
    body rotations from scipy here)."""
    K, n = len(Y), model.n
    x = Y[:, :3 * n].reshape(K, n, 3)
    v = Y[:, 7 * n:10 * n].reshape(K, n, 3)
    w = Y[:, 10 * n:13 * n].reshape(K, n, 3)
    q = Y[:, 3 * n:7 * n].reshape(K, n, 4)
    m, J, g = np.asarray(model.mass), np.asarray(model.J), np.asarray(model.gravity)
    Jw = np.einsum("iab,kib->kia", J, w)
    T = (0.5 * m * np.einsum("kia,kia->ki", v, v) + 0.5 * np.einsum("kia,kia->ki", w, Jw)
         ).sum(axis=1)
    V = -np.einsum("kia,a,i->k", x, g, m)
    sp = model.springs
    if len(sp.names):
        V = V + 0.5 * np.sum(sp.stiffness * (lengths - sp.rest_length) ** 2, axis=1)
    E = T + V
    mv = m[:, None] * v
    p = mv.sum(axis=1)
    R = Rotation.from_quat(q.reshape(-1, 4), scalar_first=True).as_matrix().reshape(K, n, 3, 3)
    spin = np.einsum("kiab,kib->kia", R, Jw)
    if about == "spins":
        terms = spin
    else:
        r, u = x, v
        if about == "mass centre":
            M = m.sum()
            r = x - (np.einsum("i,kia->ka", m, x) / M)[:, None]
            u = v - (p / M)[:, None]
        terms = np.concatenate((np.cross(r, m[:, None] * u), spin), axis=1)
    H = terms.sum(axis=1)

    def change(series, parts):
        scale = np.max(np.linalg.norm(parts, axis=2).sum(axis=1))
        return 0.0 if scale <= 0 else np.max(np.linalg.norm(series - series[0], axis=1)) / scale

    e_scale = max(abs(E[0]), np.max(np.abs(T)))
    spin_rate = np.abs(w[..., 2]) if model.dimension == 2 else np.linalg.norm(w, axis=2)
    return {"T": T, "V": V, "H": H, "p0": p[0], "spin_peak": spin_rate.max(axis=0),
            "energy": np.max(np.abs(E - E[0])) / e_scale if e_scale > 0 else 0.0,
            "momentum": change(p, mv), "angular": change(H, terms),
            "T_scale": np.max(np.abs(T)) + np.max(np.abs(V)),
            "H_scale": np.max(np.linalg.norm(terms, axis=2).sum(axis=1)),
            "p_scale": np.max(np.linalg.norm(mv, axis=2).sum(axis=1))}


def assert_figures_equal(c, ref) -> None:
    np.testing.assert_allclose(c.kinetic_energy, ref["T"], rtol=0, atol=RTOL * ref["T_scale"])
    np.testing.assert_allclose(c.potential_energy, ref["V"], rtol=0,
                               atol=RTOL * ref["T_scale"])
    np.testing.assert_allclose(c.angular_momentum, ref["H"], rtol=0,
                               atol=RTOL * ref["H_scale"])
    np.testing.assert_allclose(c.momentum_initial, ref["p0"], rtol=0,
                               atol=RTOL * ref["p_scale"])
    np.testing.assert_allclose(c.spin_peak, ref["spin_peak"], rtol=RTOL, atol=0)
    # each change is already relative to its scale
    assert abs(c.energy_drift - ref["energy"]) <= RTOL
    assert abs(c.momentum_drift - ref["momentum"]) <= RTOL
    assert abs(c.angular_momentum_drift - ref["angular"]) <= RTOL


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("about", sorted(ANGULAR_MOMENTUM_ABOUT))
@pytest.mark.parametrize("dimension", [2, 3])
def test_conserved_figures_equal_numpy_on_random_models(seed: int, about: str,
                                                        dimension: int):
    build = planar_model if dimension == 2 else spatial_model
    model = mbody.load(build(seed, n=3 + seed % 4, n_springs=seed % 4, known=False))
    rng = np.random.default_rng(100 + seed)
    Y = random_samples(model, 40, rng)
    t = np.linspace(0.0, 1.0, len(Y))
    lengths = (sample_figures(model, workspace(model).file_unknowns, t, Y, reactions=False,
                              lengths=True).lengths if len(model.springs.names) else None)
    ref = numpy_figures(model, Y, about, lengths)
    assert ref["energy"] > 0 and ref["angular"] > 0  # random states: nothing conserved
    assert_figures_equal(conserved_figures(model, Y, about, lengths), ref)


def test_conserved_figures_of_one_sample_and_of_rest():
    """One sample: no change; a model at rest without gravity: every scale 0, every
    change 0 (as numpy's code said: nothing to be relative to)."""
    model = mbody.load(spatial_model(3, n=2, n_springs=0, known=False, gravity=False))
    Y = random_samples(model, 1, np.random.default_rng(1))
    c = conserved_figures(model, Y, "world origin")
    assert (c.energy_drift, c.momentum_drift, c.angular_momentum_drift) == (0.0, 0.0, 0.0)
    Y[:, :3 * model.n] = 0.0
    Y[:, 7 * model.n:13 * model.n] = 0.0
    c = conserved_figures(model, np.repeat(Y, 3, axis=0), "mass centre")
    assert not c.kinetic_energy.any() and not c.angular_momentum.any()
    assert (c.energy_drift, c.momentum_drift, c.angular_momentum_drift) == (0.0, 0.0, 0.0)


def test_conserved_figures_refuse_missing_lengths_and_bad_sizes():
    model = mbody.load(spatial_model(0, n=2, n_springs=1, known=False))
    Y = random_samples(model, 3, np.random.default_rng(0))
    with pytest.raises(ValueError, match="lengths"):
        conserved_figures(model, Y, "spins")
    with pytest.raises(ValueError, match="Y"):
        conserved_figures(model, Y[:, :-1], "spins", np.zeros((3, 1)))
    with pytest.raises(ValueError, match="kind"):
        _core.conservation(np.ones(1), np.eye(3).ravel(), np.zeros(3), np.zeros(0),
                           np.zeros(0), None, np.zeros(13), False, 3, np.zeros(1),
                           np.zeros(1), np.zeros(3), np.zeros(6), np.zeros(1))


@pytest.mark.parametrize("K", [5, 6])
@pytest.mark.parametrize("about", sorted(ANGULAR_MOMENTUM_ABOUT))
@pytest.mark.parametrize("dimension", [2, 3])
def test_sample_passes_take_each_sample_as_alone(K: int, about: str, dimension: int):
    """The passes work on two samples at once (src/samples.c), the last of an odd count
    paired with itself: each sample's T, V, H, peak spin and normalised quaternion are
    those of the same pass over that sample alone, to the last bit (a lane never sees the
    other)."""
    build = planar_model if dimension == 2 else spatial_model
    model = mbody.load(build(2, n=3, n_springs=1, known=False))
    n = model.n
    Y = random_samples(model, K, np.random.default_rng(K))
    t = np.zeros(K)
    lengths = sample_figures(model, workspace(model).file_unknowns, t, Y, reactions=False,
                             lengths=True).lengths
    whole = conserved_figures(model, Y, about, lengths)
    alone = [conserved_figures(model, Y[k:k + 1], about, lengths[k:k + 1]) for k in range(K)]
    for k, c in enumerate(alone):
        assert whole.kinetic_energy[k] == c.kinetic_energy[0]
        assert whole.potential_energy[k] == c.potential_energy[0]
        assert (whole.angular_momentum[k] == c.angular_momentum[0]).all()
    assert (whole.spin_peak == np.max([c.spin_peak for c in alone], axis=0)).all()
    if dimension == 2:  # the parts a planar state does not have are not read
        junk = Y.copy()
        junk[:, 2:3 * n:3] = junk[:, 7 * n + 2:10 * n:3] = 5.0
        junk[:, 10 * n:13 * n].reshape(K, n, 3)[..., :2] = -7.0
        other = conserved_figures(model, junk, about, lengths)
        assert (other.kinetic_energy == whole.kinetic_energy).all()
        assert (other.angular_momentum == whole.angular_momentum).all()
        assert (other.spin_peak == whole.spin_peak).all()
    bad = Y.copy()
    bad[K // 2, 7 * n] = np.nan  # one sample's velocity: its figures, the drifts, NaN
    c = conserved_figures(model, bad, about, lengths)
    assert np.isnan(c.kinetic_energy[K // 2]) and np.isnan(c.energy_drift)
    others = np.arange(K) != K // 2
    assert (c.kinetic_energy[others] == whole.kinetic_energy[others]).all()
    none = conserved_figures(model, Y[:0], about, lengths[:0])
    assert (none.energy_drift, none.momentum_drift, none.angular_momentum_drift) == (0, 0, 0)
    assert not none.spin_peak.any() and not none.momentum_initial.any()
    Y[:, 3 * n:7 * n] *= 1.25  # quaternions off the unit sphere
    rows = [Y[k:k + 1].copy() for k in range(K)]
    _core.unit_samples(Y, n, dimension == 2)
    for k, row in enumerate(rows):
        _core.unit_samples(row, n, dimension == 2)
        assert (Y[k] == row[0]).all()


@pytest.mark.parametrize("dimension", [2, 3])
def test_unit_samples_equal_numpy(dimension: int):
    """Unit quaternions and the planar angles on their branch, as simulate did in numpy
    (`keep_planar_angles`): the same to a unit in the last place."""
    from mbody.simulate.trajectory import keep_planar_angles

    build = planar_model if dimension == 2 else spatial_model
    model = mbody.load(build(4, n=5, known=False))
    n = model.n
    rng = np.random.default_rng(7)
    Y = random_samples(model, 50, rng)
    Y[:, 3 * n:7 * n] *= rng.uniform(0.5, 1.5, (50, 4 * n)) if dimension == 3 else \
        np.repeat(rng.uniform(0.5, 1.5, (50, n)), 4, axis=1)
    if dimension == 2:
        Y[:, 13 * n:] += 2 * np.pi * rng.integers(-3, 4, (50, n)) + rng.normal(0, 1e-3, (50, n))
    ref = Y.copy()
    q = ref[:, 3 * n:7 * n].reshape(50, n, 4)
    norm = np.linalg.norm(q, axis=2)
    err = float(np.max(np.abs(norm - 1.0)))
    q /= norm[..., None]
    if dimension == 2:
        keep_planar_angles(ref, n)
    got = _core.unit_samples(Y, n, dimension == 2)
    assert got == pytest.approx(err, rel=1e-14)
    np.testing.assert_allclose(Y, ref, rtol=4e-16, atol=4e-16 * 30)  # angles up to ~30 rad


@pytest.mark.parametrize("name", ["pendulum", "double_pendulum", "heavy_top",
                                  "spring_mass_damper", "torque_free_asymmetric",
                                  "fourbar_planar", "spinning_disc_bearings"])
def test_simulate_figures_equal_the_numpy_of_its_trajectory(name: str):
    """A whole run: its series and drift figures equal numpy's from the stored trajectory
    (kinetic energy and angular momentum as `Trajectory` computes them, the potential as
    `potential_energy` does)."""
    model = mbody.load(MODELS / f"{name}.yaml")
    traj = mbody.simulate(model, t_end=1.0, fps=30)
    info = traj.info
    T = traj.kinetic_energy()
    V = simulation.potential_energy(model, traj)
    scale = np.max(np.abs(T)) + np.max(np.abs(V))
    np.testing.assert_allclose(traj.series["kinetic_energy"], T, rtol=0, atol=RTOL * scale)
    np.testing.assert_allclose(traj.series["potential_energy"], V, rtol=0, atol=RTOL * scale)
    E = T + V
    e_scale = max(abs(E[0]), np.max(np.abs(T)))
    assert abs(info["energy_drift"] - np.max(np.abs(E - E[0])) / e_scale) <= RTOL
    if info["angular_momentum_kind"] == "total, about the world origin":
        H = traj.angular_momentum()
        np.testing.assert_allclose(traj.series["angular_momentum"], H, rtol=0,
                                   atol=RTOL * max(1.0, np.max(np.abs(H))))
    p = np.einsum("i,kia->ka", traj.mass, traj.spatial()[2])
    np.testing.assert_allclose(info["momentum_initial"], p[0], rtol=0,
                               atol=RTOL * max(1.0, np.max(np.abs(p))))


def test_the_cores_marks_give_the_windows_python_gave():
    """The step-rate windows noted by the core as it steps equal those of a run that
    returns to Python at each window (a wall-time budget keeps that), and so does
    everything else."""
    model = mbody.load(MODELS / "double_pendulum.yaml")
    marked = mbody.simulate(model, t_end=3.0, fps=20)
    windowed = mbody.simulate(model, t_end=3.0, fps=20, max_wall=1e6)
    assert marked.info["step_rate"] == windowed.info["step_rate"]
    assert marked.info["steps"] == windowed.info["steps"]
    np.testing.assert_array_equal(marked.position, windowed.position)
    np.testing.assert_array_equal(marked.reactions, windowed.reactions)


def test_a_collapsing_step_rate_is_still_seen_through_the_marks():
    """The slow-down warning comes from the windows: with the marks, as before."""
    chirp = (MODELS / "planar_time_varying_force.yaml").read_text()
    traj = mbody.simulate(mbody.loads(chirp), t_end=2.0, fps=30)
    again = mbody.simulate(mbody.loads(chirp), t_end=2.0, fps=30, max_wall=1e6)
    assert traj.info["step_rate"] == again.info["step_rate"]
    assert traj.info["warnings"] == again.info["warnings"]


def test_the_core_times_its_own_integration():
    traj = mbody.simulate(mbody.load(MODELS / "heavy_top.yaml"), t_end=1.0)
    info = traj.info
    assert 0 < info["integration_time_s"] <= info["wall_time_s"]
    scipy_run = mbody.simulate(mbody.load(MODELS / "pendulum.yaml"), t_end=0.5,
                               method="RK45")
    assert scipy_run.info["integration_time_s"] == scipy_run.info["wall_time_s"]


def test_spin_warning_looks_past_a_nan_peak():
    """A body's peak spin NaN ahead of a fast one: the fast one is still warned of (the
    early test on the fastest body alone must not take the NaN for the fastest)."""
    model = mbody.load(MODELS / "torque_free_asymmetric.yaml")
    traj = mbody.simulate(model, t_end=2.0, fps=1)
    w = float(np.linalg.norm(traj.angular_velocity, axis=2).max())
    assert w / (2 * np.pi) > 0.5  # faster than half a turn a frame at 1 fps
    assert simulation._spin_warning(traj, np.array([w])) is not None
    assert simulation._spin_warning(traj, np.array([np.nan, w])) is not None
    assert simulation._spin_warning(traj, np.array([w / 10])) is None

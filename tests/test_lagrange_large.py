"""Generalized coordinates and the linearisation of large models: hanging chains of
hundreds of rods, against closed forms and the Newton-Euler solve, and what long work
says while it runs.

- The coordinates the compiled core proves independent (`_independent`: each row's
  distance from the others, 1/|B⁻¹ e_i|) are those choose()'s own dense tests take, on
  every shipped model, chains and ladders; the distances equal numpy's inverse's.
- A 300-rod chain at a moving state: the accelerations of M q'' = f (T q'' + a0) are the
  Newton-Euler solve's, within the error the equations' own rounding model allows.
- An 80-rod chain hanging: its first-order system (160 rows) is past
  `CORE_SPECTRUM_LIMIT`, so its spectrum is LAPACK's: the frequencies equal the closed
  form's (small oscillations in the rods' absolute angles: M and K by hand, eigh) within
  the linearisation's bounds, and the core's own spectrum of the same system within the
  eigenvalues' bounds, modes and verdict alike.
- Progress: the core's stages in order, an exception in the callback stops it, bars on
  standard error once a second has passed; the text of a large model is bounded.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from test_linearize import frequency_bounds

import mbody
import mbody.equations.coordinates as coordinates
import mbody.solve.linearize as linearize_module
from mbody.equations.coordinates import choose, columns, held_rows, size
from mbody.equations.generalized import generalized
from mbody.equations.workspace import workspace
from mbody.kernel import _core
from mbody.present.lagrange import generalized_text, too_many_to_write
from mbody.present.modes import modes_text
from mbody.solve.equilibrium import find_equilibrium
from mbody.solve.linearize import ROUNDING, linearize
from mbody.util import progress as progress_module

ROOT = Path(__file__).resolve().parent.parent
L, MASS, INERTIA, G = 0.1, 1.0, 0.001, 9.81
"""The chains' rods: length (m), mass (kg), inertia about the mass centre (kg m^2),
gravity (m/s^2)."""


def chain(n: int, angle: float = 0.0, rate: float = 0.0) -> mbody.Model:
    """`chain_yaml`'s model."""
    return mbody.loads(chain_yaml(n, angle, rate))


def chain_yaml(n: int, angle: float = 0.0, rate: float = 0.0) -> str:
    """n rods hanging in a chain, every one at `angle` from the downward vertical and
    turning at `rate` as one rigid body about the top pin."""
    s, c = float(np.sin(angle)), float(np.cos(angle))
    bodies, joints = [], []
    for i in range(n):
        gx, gy = float((i + 0.5) * L * s), float(-(i + 0.5) * L * c)
        bodies.append(f"  - {{name: l{i}, mass: {MASS}, inertia: {INERTIA}, "
                      f"position: [{gx!r}, {gy!r}], angle: {angle!r}, "
                      f"velocity: [{-rate * gy!r}, {rate * gx!r}], angular_velocity: {rate!r}}}")
        joints.append(f"  - {{name: j{i}, type: revolute, parent: "
                      f"{'ground' if i == 0 else f'l{i - 1}'}, child: l{i}, "
                      f"at: [{float(i * L * s)!r}, {float(-i * L * c)!r}]}}")
    return (f"model: chain-{n}\ndimension: 2\ngravity: [0, {-G}]\nbodies:\n"
            + "\n".join(bodies) + "\njoints:\n" + "\n".join(joints) + "\n")


def ladder(kind: str) -> mbody.Model:
    import sys

    sys.path.insert(0, str(ROOT / "tools"))
    from bench_ladder import ladder_spec

    return mbody.load(ladder_spec(5, kind))


def models() -> list[tuple[str, mbody.Model]]:
    out = [(p.stem, mbody.load(p)) for p in sorted((ROOT / "models").glob("*.yaml"))]
    out += [("chain", chain(40, 0.2, 0.5))]
    out += [(f"ladder-{k}", ladder(k)) for k in ("planar", "spatial", "spatial-redundant")]
    return out


# -- the coordinates ---------------------------------------------------------------------


def test_the_proved_coordinates_are_those_the_dense_tests_take(monkeypatch):
    proved = 0
    calls: list[tuple] = []

    def refused(*args) -> bool:
        calls.append(args)
        return False

    for name, model in models():
        fast = choose(model)
        calls.clear()
        monkeypatch.setattr(coordinates, "_independent", refused)
        dense = choose(model)
        named = choose(model, None, fast.labels[::-1])  # the labels' branch, its own order
        monkeypatch.undo()
        named_fast = choose(model, None, fast.labels[::-1])
        assert len(calls) == 2, name
        assert (fast.labels, fast.dof, list(fast.held.U)) == \
            (dense.labels, dense.dof, list(dense.held.U)), name
        assert (named.labels, named.dof) == (named_fast.labels, named_fast.dof), name
        proved += coordinates._independent(model, model.initial, fast.held, list(fast.items))
    assert proved >= 30  # the proof holds for nearly all (not Bricard's redundant loop)


@pytest.mark.parametrize("name", ["double_pendulum", "fourbar_planar", "gyroscope_gimbals",
                                  "slider_crank_driven"])
def test_independence_distances_are_those_of_the_inverse(name):
    model = mbody.load(ROOT / "models" / f"{name}.yaml")
    cs = choose(model)
    cols = columns(model)
    scale = np.where(cols % 6 >= 3, 1.0 / size(model), 1.0)
    rows = np.empty((len(cs), len(cols)))
    ws = workspace(model)
    y = ws.pack_state(model.initial)
    ws.core.coordinate_rows(0.0, y, cs.Iq, cols, rows, np.empty(len(cs)))
    B = np.vstack((held_rows(model, model.initial, cs.held.U), rows)) * scale
    B /= np.linalg.norm(B, axis=1)[:, None]
    out = np.empty(len(B) + 1)
    ws.solver(cs.held).independence(0.0, y, cs.Iq, cols, scale, out)
    expected = 1.0 / np.linalg.norm(np.linalg.inv(B), axis=0)
    cond = np.linalg.cond(B)
    np.testing.assert_allclose(out[:-1], expected, rtol=100 * cond * np.finfo(float).eps)
    assert out[-1] > 0.0


# -- a large chain's equations -------------------------------------------------------------


def test_a_long_chains_accelerations_are_the_solves():
    model = chain(300, 0.3, 0.8)
    g = generalized(model)
    assert g.coordinates == [f"j{i}.angle" for i in range(300)]
    acc = mbody.assemble(model).solve().accelerations
    qdd = g.accelerations()
    # the equations' own rounding model (linearize.ROUNDING: one evaluation of f errs by
    # 10 eps of its terms over the projection's pivot ratio), carried through M^-1 and T
    df = ROUNDING * g.f_scale / g.rank
    bound = np.abs(g.T) @ (np.abs(np.linalg.inv(g.M)) @ df) + 1e3 * np.finfo(float).eps * \
        np.abs(acc).max()
    assert np.all(np.abs(g.body_accelerations(qdd) - acc) <= bound)
    assert np.abs(g.T.T @ mbody.assemble(model).G.toarray()).max() < 1e-12 * np.abs(g.T).max()


# -- a large chain's modes -------------------------------------------------------------------


def hanging_chain_frequencies(n: int) -> np.ndarray:
    """Small oscillations of n rods hanging, in their absolute angles: a rod's mass centre
    moves by sum_{j<i} L phi_j + a phi_i (a = L/2), so M_jk = sum_i m c_ij c_ik + I delta_jk
    (c_ij = L, a, 0 for j <, =, > i) and K = diag(m g (a + L (n - 1 - j)))."""
    a = L / 2
    c = np.tril(np.full((n, n), L), -1) + a * np.eye(n)
    M = MASS * c.T @ c + INERTIA * np.eye(n)
    K = np.diag(MASS * G * (a + L * (n - 1 - np.arange(n))))
    return np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True))


def test_a_hanging_chains_frequencies_by_lapack_and_by_the_core(monkeypatch):
    n = 80
    model = chain(n)
    lin = linearize(model)
    assert 2 * n > linearize_module.CORE_SPECTRUM_LIMIT  # LAPACK's spectrum
    assert lin.steady and lin.stable is True
    omega = hanging_chain_frequencies(n)
    assert len(lin.frequencies) == n
    # the bound from K's errors, plus the rounding of the eigenvalues of the first-order
    # system A (a backward error of nz eps |A| times each one's condition number, from its
    # left and right vectors) and eigh's
    w, left, right = scipy.linalg.eig(lin.A, left=True, right=True)
    kappa = np.linalg.norm(right, axis=0) * np.linalg.norm(left, axis=0) / np.abs(
        np.einsum("ij,ij->j", left.conj(), right))
    rounding = np.array([kappa[np.argmin(np.abs(w - m.eigenvalue))] for m in lin.oscillations])
    rounding *= len(lin.A) * np.finfo(float).eps * np.linalg.norm(lin.A, 2)
    bound = frequency_bounds(lin) + rounding + 1e-12 * omega
    assert np.all(np.abs(lin.frequencies - omega) <= bound)
    assert np.all(bound <= 1e-6 * omega)
    # the core's own QR iteration on the same first-order system
    monkeypatch.setattr(linearize_module, "CORE_SPECTRUM_LIMIT", 10 * n)
    core = linearize(model)
    for lam, err in zip(lin.eigenvalues, lin.eigenvalue_errors, strict=True):
        k = np.argmin(np.abs(core.eigenvalues - lam))
        assert abs(core.eigenvalues[k] - lam) <= err + core.eigenvalue_errors[k]
    np.testing.assert_array_equal(lin.eigenvalue_errors > 0, True)
    assert [m.kind for m in core.modes] == [m.kind for m in lin.modes]
    assert core.stable is lin.stable and core.tolerance == lin.tolerance
    for a, b in zip(core.oscillations, lin.oscillations, strict=True):
        assert abs(a.frequency - b.frequency) <= 2 * lin.tolerance
        # the shapes, the largest entry 1, of simple modes: within the eigenvalues'
        # relative accuracy over their separation, here far below 1e-6
        np.testing.assert_allclose(a.shape, b.shape, atol=1e-6)


def test_a_chains_equilibrium_and_its_squared_frequencies():
    # Newton's steps take K alone from the core (no first-order system, no spectrum)
    model = chain(30, 0.2)
    found = find_equilibrium(model)
    assert found.found and found.stable is True
    # straight down: every rod's angle 0
    assert np.abs(found.state.position[:, 0]).max() < 1e-8
    np.testing.assert_allclose(np.sqrt(found.stiffness), hanging_chain_frequencies(30),
                               rtol=1e-6)


# -- progress --------------------------------------------------------------------------------


def test_the_cores_stages_are_reported_in_order_and_a_callback_can_stop_it():
    model = chain(20, 0.1)
    cs = linearize_module.free_coordinates(model)
    ws = workspace(model)
    at = linearize_module._offsets(len(cs.cols), len(cs))
    seen: list[tuple[int, int, int]] = []

    def run(callback) -> None:
        ws.solver(cs.held).linearize(0.0, ws.pack_state(model.initial), cs.held.lam, cs.Iq,
                                     cs.cols, cs.scales, cs.quasi_int,
                                     linearize_module._skip(model, cs),
                                     linearize_module._PARAMS, np.empty(at.end), callback)

    run(lambda *r: seen.append(r))
    stages = [s for s, _, _ in seen]
    assert stages == sorted(stages)
    assert set(stages) == set(range(_core.STAGES))
    k = len(cs)
    assert [d for s, d, t in seen if s == _core.STAGE_STIFFNESS] == list(range(k))
    assert {t for s, _, t in seen if s == _core.STAGE_STIFFNESS} == {k}

    class Stop(Exception):
        pass

    def stop(stage, done, total):
        if stage == _core.STAGE_STIFFNESS and done == 3:
            raise Stop
    with pytest.raises(Stop):
        run(stop)


def test_progress_bars_say_what_is_computed(monkeypatch, capsys):
    monkeypatch.setattr(progress_module, "DELAY", 0.0)
    model = chain(30, 0.1)
    linearize(model, progress=True)
    err = capsys.readouterr().err
    for words in ("choosing the coordinates", "stiffness K = -df/dq", "first-order system",
                  "eigenvalues"):
        assert f"linearize chain-30: {words}" in err, err
    mbody.assemble(model).generalized(progress=True)
    assert "generalized chain-30: projecting the equations: T (90 x 30), M, f" in \
        capsys.readouterr().err
    linearize(model)  # not asked for: nothing
    assert capsys.readouterr().err == ""


def test_quick_work_prints_no_bar(capsys):
    linearize(mbody.load(ROOT / "models" / "double_pendulum.yaml"), progress=True)
    assert capsys.readouterr().err == ""


# -- bounded text ----------------------------------------------------------------------------


def test_the_text_of_many_coordinates_leaves_out_their_square():
    model = mbody.load(ROOT / "models" / "triple_pendulum.yaml")
    g = generalized(model)
    full, short = generalized_text(g), generalized_text(g, max_written=2)

    def equation(line: str) -> bool:
        return line.startswith("  ") and "''" in line

    assert sum(map(equation, full.splitlines())) == 3
    assert "(3 equations of up to 3 terms each: not written out above 2 coordinates; -o " \
        "FILE.npz, .mat or .json exports M, f and T)" in short
    kept = [line for line in full.splitlines() if not equation(line)]
    assert [line for line in short.splitlines() if "equations of up to" not in line] == kept
    assert too_many_to_write(3, 2) and not too_many_to_write(3)
    lin = linearize(model, mbody.equilibrium(model))
    assert "mode 1:" in modes_text(lin) and "mode 1:" not in modes_text(lin, max_shapes=2)
    assert "shapes: not written out above 2 coordinates (an amplitude per coordinate for " \
        "each of 3 modes); --json gives them" in modes_text(lin, max_shapes=2)

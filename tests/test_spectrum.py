"""The compiled core's spectrum (kernel.h: mb_spectrum) against numpy's LAPACK eig, and on
the structures a linearisation has: double eigenvalues of a symmetric body (two
independent mode shapes), a free coordinate's Jordan block, an all-zero system."""

from __future__ import annotations

import numpy as np
import pytest

from mbody.kernel import _core

EPS = np.finfo(float).eps


def spectrum(A: np.ndarray, dA: float = 1e-12, tol: float = 1e-6):
    n = len(A)
    out = np.empty(3 * n + 2 * n * n)
    assert _core.spectrum(np.ascontiguousarray(A, dtype=float), dA, tol, out) == 0
    return (out[:2 * n].view(complex), out[2 * n:2 * n + 2 * n * n].view(complex).reshape(n, n),
            out[2 * n + 2 * n * n:])


def lapack_bounds(A: np.ndarray, dA: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Sorted eigenvalues and the bounds from inv(V)'s rows (the definition)."""
    w, V = np.linalg.eig(A)
    order = np.lexsort((w.imag, w.real))
    w, V = w[order], V[:, order]
    cond = np.linalg.norm(np.linalg.inv(V), axis=1)  # |y_i| with y_i^H x_i = 1, |x_i| = 1
    floor = 1e3 * EPS * np.abs(A).sum(axis=1).max()
    return w, np.maximum(np.minimum(cond * dA, tol), floor)


@pytest.mark.parametrize("seed", range(40))
def test_random_matrices_match_lapack(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 20))
    # rows and columns of mixed scales, as positions and rates in different units
    A = rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-2, 2, size=n)[:, None] \
        * 10.0 ** rng.uniform(-2, 2, size=n)[None, :]
    w, V, err = spectrum(A, 1e-10, 1e-3)
    w0, err0 = lapack_bounds(A, 1e-10, 1e-3)
    scale = np.abs(A).sum(axis=1).max()
    cond = np.linalg.cond(np.linalg.eig(A)[1])
    # each eigenvalue within its backward-stable perturbation (n eps |A| kappa)
    assert np.abs(w - w0).max() <= 100 * n * EPS * scale * cond
    # unit vectors with A v = lambda v to rounding of |A|
    assert np.allclose(np.linalg.norm(V, axis=0), 1.0, rtol=0, atol=1e-13)
    assert np.abs(A @ V - V * w).max() <= 100 * n * EPS * scale * cond
    # the bounds are the same definition: first-order, so equal to the conditions' rounding
    assert np.allclose(err, err0, rtol=1e-6 * cond, atol=0)


def test_sorted_by_real_then_imaginary_part() -> None:
    rng = np.random.default_rng(7)
    w, _, _ = spectrum(rng.normal(size=(12, 12)))
    key = list(zip(w.real, w.imag, strict=True))
    assert key == sorted(key)


def test_double_pair_has_two_independent_shapes() -> None:
    """A spherical pendulum's two equal frequencies: four eigenvectors, rank 4."""
    omega = 3.0
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-omega**2 * np.eye(2), np.zeros((2, 2))]])
    w, V, err = spectrum(A)
    assert np.allclose(np.sort(w.imag), [-omega, -omega, omega, omega], atol=1e-14)
    assert np.linalg.matrix_rank(V) == 4
    assert np.abs(A @ V - V * w).max() <= 1e-14


def test_jordan_block_gets_the_whole_tolerance() -> None:
    """A free coordinate (q' = u, u' = 0): a double zero with one vector; its first-order
    bound is infinite, so it gets `tol`, the bound of a double eigenvalue."""
    w, _, err = spectrum(np.array([[0.0, 1.0], [0.0, 0.0]]), 1e-12, 1e-6)
    assert np.all(w == 0) and np.all(err == 1e-6)


def test_empty_and_zero() -> None:
    w, V, err = spectrum(np.zeros((0, 0)))
    assert w.shape == (0,) and V.shape == (0, 0) and err.shape == (0,)
    w, V, err = spectrum(np.zeros((3, 3)))
    assert np.all(w == 0) and np.allclose(np.abs(V), np.eye(3))


def test_rejects_a_non_square_matrix() -> None:
    with pytest.raises(ValueError, match="square"):
        _core.spectrum(np.zeros(5), 0.0, 0.0, np.zeros(10))


def test_modes_of_a_double_pendulum_are_its_two_oscillations() -> None:
    """mb_modes on a spectrum with two undamped pairs: one mode per pair, by frequency,
    real shapes with their largest entry 1 (the in-phase and the anti-phase swing)."""
    M = np.array([[2.0, 0.5], [0.5, 1.0]])
    K = np.array([[30.0, 0.0], [0.0, 10.0]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), np.zeros((2, 2))]])
    n = len(A)
    spec = np.empty(3 * n + 2 * n * n)
    assert _core.spectrum(A, 1e-12, 1e-6, spec) == 0
    out = np.empty(_core.MODE_W * n + 2 * n * 2)
    m = _core.modes(spec, 2, np.arange(2, dtype=np.int64), out)
    assert m == 2
    rows = out[:_core.MODE_W * m].reshape(m, _core.MODE_W)
    shapes = out[_core.MODE_W * n:_core.MODE_W * n + 2 * m * 2].view(complex).reshape(m, 2)
    lam2, vecs = np.linalg.eig(np.linalg.solve(M, K))  # omega^2 and shapes, independently
    order = np.argsort(lam2)
    assert np.allclose(rows[:, _core.MODE_FREQUENCY], np.sqrt(lam2[order]), rtol=1e-12)
    assert np.all(rows[:, _core.MODE_KIND] == _core.MODE_OSCILLATION)
    assert np.all(shapes.imag == 0) and np.allclose(np.abs(shapes).max(axis=1), 1.0)
    for c, j in enumerate(order):
        ref = vecs[:, j] / vecs[np.argmax(np.abs(vecs[:, j])), j]
        assert np.allclose(shapes[c].real, ref, atol=1e-12)

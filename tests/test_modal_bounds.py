"""The eigenvalues' error bounds from the modes of K's symmetric part
(`mbody.solve.modal_bounds`).

- They are bounds: K, D and M perturbed within the entrywise errors the bounds assume move
  each eigenvalue (found independently: scipy's QZ on the perturbed pencil) by no more
  than its bound; on one degree of freedom the bound is nearly reached (it is not loose
  by construction).
- They decide a 150-rod hanging chain: the first-order system's bounds (‖M⁻¹‖ (‖δK‖ +
  ‖δD‖)) exceed its eigenvalues, these are below 1e-3 of each, so every mode is an
  oscillation and the verdict stable, the frequencies those of the closed form within
  their bounds; ``mbody modes`` says so.
- Where the derivation does not hold (K's symmetric part indefinite) there is no modal
  bound, and the first-order system's stay.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from test_lagrange_large import chain, chain_yaml, hanging_chain_frequencies

from mbody.cli.app import main
from mbody.solve.linearize import linearize
from mbody.solve.modal_bounds import modal_bounds


def _first_order_eigenvalues(M: np.ndarray, D: np.ndarray, K: np.ndarray) -> np.ndarray:
    """The roots μ of det(μ² M + μ D + K), by QZ on the companion pencil (scipy)."""
    k = len(M)
    Z, eye = np.zeros((k, k)), np.eye(k)
    A = np.block([[Z, eye], [-K, -D]])
    B = np.block([[eye, Z], [Z, M]])
    return scipy.linalg.eigvals(A, B)


def _problem(k: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random symmetric positive definite M and K, M ill conditioned (a chain's kind:
    cumulative lever arms)."""
    c = np.tril(rng.uniform(0.5, 1.5, (k, k)))
    M = c.T @ c + 1e-3 * np.eye(k)
    q = rng.normal(size=(k, k))
    K = q @ q.T + k * np.eye(k)
    return M, K


def _within(eigenvalues: np.ndarray, bounds: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """For each computed eigenvalue, its distance to the nearest true one over its
    bound."""
    return np.array([np.min(np.abs(truth - w)) / b for w, b in zip(eigenvalues, bounds,
                                                                    strict=True)])


def test_one_degree_of_freedom_nearly_reaches_its_bound():
    """m x'' + k x = 0 with k off by e: ω = √(k/m) moves by e / (2 m ω) to first order;
    the bound is that, and the true change is within it."""
    m, k, e = 2.0, 50.0, 1e-4
    M, K = np.array([[m]]), np.array([[k]])
    zero = np.zeros((1, 1))
    w = np.array([1j, -1j]) * np.sqrt(k / m)
    bounds = modal_bounds(M, K, np.array([[e]]), zero, zero, 0.0, w)
    assert bounds is not None
    for shift in (e, -e):
        truth = np.array([1j, -1j]) * np.sqrt((k + shift) / m)
        ratio = _within(w, bounds, truth)
        assert np.all(ratio <= 1.0) and np.all(ratio >= 0.99)


@pytest.mark.parametrize("seed", range(6))
def test_perturbations_within_the_errors_stay_within_the_bounds(seed):
    """K (not symmetrically), D and M (symmetrically) perturbed by random signs times
    the errors the bounds assume: every eigenvalue moves by at most its bound, and by a
    sizeable part of it for some (the bound is not vacuous)."""
    rng = np.random.default_rng(seed)
    k = 12
    M, K = _problem(k, rng)
    D = np.zeros((k, k))
    K_err = 1e-4 * np.abs(K).max() * rng.uniform(0.2, 1.0, (k, k))
    D_err = 1e-4 * np.sqrt(np.abs(K).max()) * rng.uniform(0.2, 1.0, (k, k))
    m_rel = 1e-6
    w = _first_order_eigenvalues(M, D, K)
    bounds = modal_bounds(M, K, K_err, D, D_err, m_rel, w)
    assert bounds is not None
    s = np.sqrt(np.diag(M))
    worst = 0.0
    for _ in range(20):
        E_M = rng.uniform(-1, 1, (k, k)) * m_rel * np.outer(s, s)
        E_M = np.triu(E_M) + np.triu(E_M, 1).T  # a mass matrix stays symmetric
        truth = _first_order_eigenvalues(M + E_M, rng.uniform(-1, 1, (k, k)) * D_err,
                                         K + rng.choice([-1.0, 1.0], (k, k)) * K_err)
        ratio = _within(w, bounds, truth)
        assert np.all(ratio <= 1.0), ratio.max()
        worst = max(worst, float(ratio.max()))
    assert worst > 0.05  # measured 0.16 to 0.24 of the bound over these seeds


def test_a_close_pair_shares_its_discs_and_stays_within_them():
    """Two frequencies closer than their errors: their discs overlap, each bound spans
    the pair's union, and perturbations move them no further."""
    rng = np.random.default_rng(3)
    M = np.eye(3)
    K = np.diag([1.0, 1.0 + 1e-6, 4.0])
    K_err = np.full((3, 3), 1e-5)
    zero = np.zeros((3, 3))
    w = _first_order_eigenvalues(M, zero, K)
    bounds = modal_bounds(M, K, K_err, zero, zero, 0.0, w)
    assert bounds is not None
    close = np.abs(np.abs(w.imag) - 1.0) < 1e-3
    assert np.all(bounds[close] > 1e-6 / 2)  # wider than the pair's separation in ω
    for _ in range(50):
        truth = _first_order_eigenvalues(M, zero, K + rng.uniform(-1, 1, (3, 3)) * K_err)
        assert np.all(_within(w, bounds, truth) <= 1.0)


def test_an_indefinite_stiffness_has_no_modal_bound():
    M = np.eye(2)
    K = np.diag([1.0, -1.0])  # an inverted pendulum's direction: a real pair ±1
    zero = np.zeros((2, 2))
    assert modal_bounds(M, K, 1e-9 * np.ones((2, 2)), zero, zero, 0.0,
                        np.array([1.0, -1.0, 1j, -1j])) is None


def test_a_150_rod_chain_oscillates_in_every_mode_and_is_stable(tmp_path, capsys):
    n = 150
    lin = linearize(chain(n))
    assert lin.steady and lin.stable is True
    # the first-order system's own bound, ‖M⁻¹‖ (‖δK‖ + ‖δD‖), is past every eigenvalue
    assert lin.dA > np.abs(lin.eigenvalues).min()
    assert [m.kind for m in lin.modes] == ["oscillation"] * n
    errors = lin.eigenvalue_errors
    assert np.all(errors < 1e-3 * np.abs(lin.eigenvalues))  # measured: at most 1.2e-4
    # the frequencies are the closed form's (absolute angles, M and K by hand, eigh)
    # within their bounds: each oscillation's eigenvalue +iω and its bound
    omega = hanging_chain_frequencies(n)
    upper = lin.eigenvalues.imag > 0
    order = np.argsort(lin.eigenvalues[upper].imag)
    bound = errors[upper][order]
    assert np.all(np.abs(lin.frequencies - omega) <= bound)
    # and an independent solve of the same M and K (scipy's eigh)
    independent = np.sqrt(scipy.linalg.eigh(0.5 * (lin.K + lin.K.T), lin.M,
                                            eigvals_only=True))
    assert np.all(np.abs(lin.frequencies - independent) <= bound)
    # the command says so
    path = tmp_path / "chain150.yaml"
    path.write_text(chain_yaml(n))
    capsys.readouterr()
    assert main(["modes", str(path), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "stable: no eigenvalue has a positive real part" in out
    assert "neutral" not in out

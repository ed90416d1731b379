"""docs/images/fourbar_chain_crossing.png: the four-bar chain's accelerations through
its flat position, solved by mbody and compared with the exact parallel motion.

    python tools/make_singular_figure.py

For crank angles θ from 1e-13 to 1e-1 rad on either side of flat (θ = 0), at 2 rad/s,
the relative error of `mbody.assemble(model).solve()` (every body's accelerations)
against the one-angle ODE of the parallel motion (tests/fourbar_chain.py), and the same
error for the plain Schur-complement solve that mbody used before (eigen-decomposition
of S with a relative tolerance of 1e-10 on its eigenvalues), computed here from the same
G, M and γ.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from fourbar_chain import FourbarChain  # noqa: E402
from mbody.solve.kkt import ConstrainedSystem, block_solve  # noqa: E402

import mbody  # noqa: E402
from mbody.equations.constraints import gamma  # noqa: E402

CHAIN = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)


def schur_eigen(model) -> np.ndarray:
    """The former solve: λ = S⁺ (γ − Gᵀ M⁻¹ r) with S's eigenvalues cut at 1e-10."""
    asm = mbody.assemble(model)
    unknowns = model.plan.file_unknowns
    system = ConstrainedSystem(model, asm.columns, unknowns)
    G = system.G.toarray() if hasattr(system.G, "toarray") else np.asarray(system.G)
    r6 = asm._Q6 - asm._b6
    a0 = block_solve(model, np.arange(model.n), r6).ravel()
    H = np.stack([block_solve(model, np.arange(model.n), G[:, k].reshape(-1, 6)).ravel()
                  for k in range(G.shape[1])], axis=1)
    S = G.T @ H
    w, V = np.linalg.eigh(0.5 * (S + S.T))
    keep = w > 1e-10 * w[-1]
    rhs = gamma(model, asm.state, asm.columns) - G.T @ a0
    lam = V[:, keep] @ ((V[:, keep].T @ rhs) / w[keep])
    acc = (a0 + H @ lam).reshape(-1, 6)
    return acc[:, [0, 1, 5]].ravel()


def main() -> None:
    mags = np.logspace(-13, -1, 49)
    thetas = np.concatenate((-mags[::-1], mags))
    new, old = [], []
    for th in thetas:
        model = mbody.loads(CHAIN.yaml(float(th), 2.0))
        exact = CHAIN.accelerations(float(th), 2.0)
        scale = np.abs(exact).max()
        new.append(np.abs(mbody.assemble(model).solve().accelerations - exact).max() / scale)
        old.append(np.abs(schur_eigen(model) - exact).max() / scale)
    floor = 1e-17
    fig, ax = plt.subplots(figsize=(7.5, 4.0), dpi=110)
    x = np.sign(thetas) * (np.log10(np.abs(thetas)) + 14)
    ax.semilogy(x, np.maximum(old, floor), "o-", ms=3, color="#c0504d",
                label="before: Schur complement, eigenvalues cut at 1e-10")
    ax.semilogy(x, np.maximum(new, floor), "o-", ms=3, color="#1f77b4",
                label="mbody: null-space solve on G's geometry")
    ticks = [-13, -11, -9, -7, -5, -3, -1]
    pos = [np.log10(10.0 ** t) + 14 for t in ticks]
    ax.set_xticks([-p for p in pos[::-1]] + pos)
    ax.set_xticklabels([f"-1e{t}" for t in ticks[::-1]] + [f"1e{t}" for t in ticks],
                       rotation=45, fontsize=8)
    ax.set_xlabel("crank angle θ from the flat position (rad, log scale each side)")
    ax.set_ylabel("relative error of the accelerations")
    ax.axhline(1e-9, color="grey", lw=0.8, ls="--")
    ax.set_title("Four-bar chain (3 loops) through its flat position, 2 rad/s")
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    out = ROOT / "docs" / "images" / "fourbar_chain_crossing.png"
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

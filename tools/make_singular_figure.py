"""docs/images/fourbar_chain_crossing.png: the four-bar chain's accelerations through
its flat position, solved by mbody and compared with the exact parallel motion.

    python tools/make_singular_figure.py [--out PATH]

For crank angles θ from 1e-13 to 1e-1 rad on either side of flat (θ = 0), at 2 rad/s,
the relative error of `mbody.assemble(model).solve()` (every body's accelerations, the
compiled core's solve) against the one-angle ODE of the parallel motion
(tests/fourbar_chain.py), and the same error for the plain Schur-complement solve that
mbody used before (eigen-decomposition of S with a relative tolerance of 1e-10 on its
eigenvalues), computed here in numpy from the same M, G, Q − b and γ as the assembly
gives them.
"""

from __future__ import annotations

import argparse
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

import mbody  # noqa: E402
from mbody.equations.workspace import workspace  # noqa: E402
from mbody.util.atomic import atomic_path  # noqa: E402

CHAIN = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)


def schur_eigen(model) -> np.ndarray:
    """The former solve: λ_U = S⁺ (γ_U − G_Uᵀ M⁻¹ r), S = G_Uᵀ M⁻¹ G_U with its
    eigenvalues cut at 1e-10 of the largest, r = Q − b + G_K λ_K; v̇ = M⁻¹ (r + G_U λ_U)
    (the model's coordinates, as `Solution.accelerations`)."""
    asm = mbody.assemble(model)
    unknowns = workspace(model).file_unknowns
    G = asm.G.toarray()
    GU, GK = G[:, unknowns.U], G[:, ~unknowns.mask]
    M = asm.M.toarray()
    r = asm.Q - asm.b + GK @ unknowns.lam[~unknowns.mask]
    a0 = np.linalg.solve(M, r)
    H = np.linalg.solve(M, GU)
    S = GU.T @ H
    w, V = np.linalg.eigh(0.5 * (S + S.T))
    keep = w > 1e-10 * w[-1]
    rhs = asm.jacobian().gamma[unknowns.U] - GU.T @ a0
    lam = V[:, keep] @ ((V[:, keep].T @ rhs) / w[keep])
    return a0 + H @ lam


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path,
                    default=ROOT / "docs" / "images" / "fourbar_chain_crossing.png",
                    help="the picture (default: the docs' docs/images/"
                    "fourbar_chain_crossing.png)")
    args = ap.parse_args(argv)
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
    out = args.out
    with atomic_path(out, suffix=".png") as tmp:  # never a half-written picture
        fig.savefig(tmp)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

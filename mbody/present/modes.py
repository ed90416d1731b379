"""What ``mbody modes`` prints: the linearisation's modes as a table (eigenvalue, natural
frequency in rad/s and Hz, damping ratio), their shapes, and the verdict."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from mbody.equations.symbolic.printing import num

if TYPE_CHECKING:
    from mbody.solve.linearize import Linearization, Mode

DIGITS = 6
MAX_SHAPES = 200
"""Most coordinates whose mode shapes are written out (a line per mode, an amplitude per
coordinate: k² numbers); ``mbody modes --json`` gives every one."""


def _eigenvalue(m: Mode) -> str:
    lam = m.eigenvalue
    if m.kind == "oscillation":
        re = f"{num(lam.real, DIGITS)} " if lam.real else ""
        return f"{re}±{num(lam.imag, DIGITS)}i"
    return num(lam.real, DIGITS)


def moves(lin: Linearization) -> bool:
    """Whether the state linearised about moves (a velocity or a rate not 0): without a
    verdict, `--equilibrium` would then drop that motion, not only find rest."""
    return bool(np.any(lin.state.velocity) or np.any(lin.state.omega))


def verdict(lin: Linearization) -> str:
    """One line: stable, unstable (which mode grows, its time constant) or no verdict."""
    if not len(lin.coordinates):
        return ("no free coordinate: the drivers prescribe every degree of freedom, so "
                "nothing oscillates about this motion (mbody kinematics MODEL gives it)")
    if lin.stable is None:
        return ("no verdict: the state is not an equilibrium or a steady motion; the "
                "eigenvalues are those of the tangent system at this instant "
                + ("(a steady motion is one whose coordinates' rates stay constant: a top's "
                   "precession written with gimbals, revolute joints, not a ball joint, "
                   "whose body-axis rates turn as it precesses; mbody modes --equilibrium "
                   "would drop the motion and linearise about rest)" if moves(lin) else
                   "(mbody modes --equilibrium linearises about the static equilibrium "
                   "nearest it)"))
    neutral = sum(1 for m in lin.modes if m.kind == "neutral")
    extra = (f"; {neutral} neutral mode{'s' if neutral != 1 else ''} (λ = 0: a free or "
             "cyclic motion)") if neutral else ""
    if lin.stable:
        return (f"stable: no eigenvalue has a positive real part (beyond its error, at most "
                f"{lin.eigenvalue_errors.max():.2g} 1/s){extra}")
    grows = [(k + 1, m) for k, m in enumerate(lin.modes) if m.eigenvalue.real > 0]
    k, m = grows[-1]
    return (f"unstable: mode {k} grows (λ = {_eigenvalue(m)} 1/s: e-folding in "
            f"{num(1.0 / m.eigenvalue.real, 4)} s){extra}")


def modes_text(lin: Linearization, about: str = "", max_shapes: int = MAX_SHAPES) -> str:
    """The table, the shapes (up to `max_shapes` coordinates) and the verdict (`about`: how
    the state was chosen)."""
    model = lin.model
    out = [f"model '{model.name}': linearised about "
           + (about or f"the state at t = {lin.state.t:g} s")]
    out.append(f"coordinates: {', '.join(lin.coordinates) or 'none'}"
               + (f" (left out, symmetries of the motion: {', '.join(lin.left_out)})"
                  if lin.left_out else ""))
    out.append("")
    if not len(lin.coordinates):  # no table to show (review R7-14): the verdict says why
        out.append(verdict(lin))
        out.extend(f"warning: {w}" for w in lin.warnings)
        return "\n".join(out)
    head = (f"{'mode':>4s}  {'kind':11s}  {'eigenvalue (1/s)':>22s}  {'ω_n (rad/s)':>12s}  "
            f"{'f_n (Hz)':>10s}  {'ζ':>8s}")
    out.append(head)
    out.append("-" * len(head))
    for k, m in enumerate(lin.modes, start=1):
        w = num(m.frequency, DIGITS) if np.isfinite(m.frequency) else "-"
        f = num(m.frequency_hz, DIGITS) if np.isfinite(m.frequency) else "-"
        z = num(m.damping_ratio, 4) if np.isfinite(m.damping_ratio) else "-"
        out.append(f"{k:4d}  {m.kind:11s}  {_eigenvalue(m):>22s}  {w:>12s}  {f:>10s}  "
                   f"{z:>8s}")
    moving = [(k, m) for k, m in enumerate(lin.modes, start=1) if m.kind != "neutral"]
    if moving and len(lin.coordinates) > max_shapes:
        out.append("")
        out.append(f"shapes: not written out above {max_shapes} coordinates (an amplitude "
                   f"per coordinate for each of {len(moving)} modes); --json gives them")
    elif moving:
        out.append("")
        out.append("shapes (each coordinate's amplitude, the largest 1; complex: "
                   "magnitude∠phase in degrees):")
        for k, m in moving:
            parts = []
            for label, a in zip(lin.coordinates, m.shape, strict=True):
                if a == 0:
                    continue
                if abs(a.imag) > 1e-12:
                    parts.append(f"{label} {num(abs(a), 4)}∠{num(np.degrees(np.angle(a)), 4)}")
                else:
                    parts.append(f"{label} {num(a.real, 4)}")
            out.append(f"  mode {k}: " + ", ".join(parts))
    out.append("")
    out.append(verdict(lin))
    out.extend(f"warning: {w}" for w in lin.warnings)
    return "\n".join(out)

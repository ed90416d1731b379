"""What ``mbody lagrange`` prints: the equations in generalized coordinates, in numbers
(`generalized_text`, `generalized_latex`) and in symbols (`symbolic_text`,
`symbolic_latex`), and a LaTeX document of either."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from mbody.equations.symbolic.printing import latex_symbol, latex_text, num

if TYPE_CHECKING:
    import sympy

    from mbody.equations.generalized import Generalized
    from mbody.equations.symbolic.lagrange import SymbolicLagrange

DIGITS = 6
MAX_WRITTEN = 200
"""Most coordinates whose equations are written out (text and LaTeX): each row of M has a
term per coordinate, so a model of two thousand bodies would print four million terms
nobody reads; the exports (-o) hold every number."""


def _row(coef: np.ndarray, names: list[str], rhs: float) -> str:
    terms = ""
    for c, name in zip(coef, names, strict=True):
        if c == 0.0:
            continue
        mag = num(abs(c), DIGITS)
        body = name if mag == "1" else f"{mag}*{name}"
        terms += (f"-{body}" if c < 0 else body) if not terms else \
            f" {'-' if c < 0 else '+'} {body}"
    return f"{terms or '0'} = {num(rhs, DIGITS)}"


NOISE = 1e-12
"""A printed number below this fraction of the terms that make it is rounding: shown 0."""


def cleaned(g: Generalized) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(q, M, f, q'') with rounding noise set to 0, for printing: an off-diagonal M_kl
    below `NOISE` √(M_kk M_ll) (M is positive definite), f below `NOISE` of its terms
    (`Generalized.f_scale`), q'' below `NOISE` of |M⁻¹| f_scale, q below `NOISE` rad (or
    of the model's size)."""
    d = np.sqrt(np.abs(np.diag(g.M)))
    M = np.where(np.abs(g.M) <= NOISE * np.outer(d, d), 0.0, g.M)
    f = np.where(np.abs(g.f) <= NOISE * g.f_scale, 0.0, g.f)
    cs = g.coordinate_set
    q = np.where(np.abs(g.q) <= NOISE * cs.scales, 0.0, g.q)
    qdd = g.accelerations() if not g.efforts else np.full(len(f), np.nan)
    scale = np.abs(np.linalg.inv(g.M)) @ g.f_scale if len(f) else qdd
    qdd = np.where(np.abs(qdd) <= NOISE * scale, 0.0, qdd)
    return q, M, f, qdd


def generalized_text(g: Generalized, max_written: int = MAX_WRITTEN) -> str:
    """The equations ``M q'' = f`` at the state, with the coordinates, their values and
    rates, what each is, the accelerations they give and f split by source; with more
    than `max_written` coordinates, every line but the equations (their k² terms)."""
    model = g.model
    cs = g.coordinate_set
    q_shown, M_shown, f_shown, qdd_shown = cleaned(g)
    k = len(g.f)
    how = f"a spanning tree: {', '.join(cs.tree)}" if cs.tree else "as chosen"
    out = [f"model '{model.name}' at t = {g.state.t:g} s: {k} generalized coordinate"
           f"{'s' if k != 1 else ''} ({how})"]
    width = max([len(c) for c in g.coordinates] + [len("coordinate")])
    out.append(f"  {'coordinate':{width}s}  {'value':>14s}  {'rate':>16s}  meaning")
    for c, q, qd in zip(cs.items, q_shown, g.qdot, strict=True):
        value = "(quasi)" if c.quasi else f"{num(q, DIGITS)} {c.unit}"
        out.append(f"  {c.label:{width}s}  {value:>14s}  {num(qd, DIGITS) + ' ' + c.rate_unit:>16s}"
                   f"  {c.meaning}")
    if g.efforts:
        out.append("  driven: " + ", ".join(f"{c} by {e} (its effort acts on that row)"
                                            for e, c in g.efforts.items()))
    held = [r for r, h in zip(model.reactions, cs.held.mask, strict=True) if h]
    out.append("")
    out.append("M q'' = f: the Newton-Euler rows multiplied by T^T, where v = T q' + v_e; the "
               f"reactions drop out (T^T G = 0 for {len(held)} held component"
               f"{'s' if len(held) != 1 else ''})")
    names = [c.acceleration_label for c in cs.items]
    effort_rows = {r: e for e, r in g.coordinate_set.efforts}
    if k > max_written:
        out.append(f"  ({k} equations of up to {k} terms each: not written out above "
                   f"{max_written} coordinates; -o FILE.npz, .mat or .json exports M, f and T)")
    for i in range(k if k <= max_written else 0):
        row = _row(M_shown[i], names, float(f_shown[i]))
        if i in effort_rows:
            row += f" + {effort_rows[i]}"
        out.append(f"  {row}")
    if not g.efforts:
        out.append("")
        out.append("so: " + ", ".join(f"{n} = {num(a, DIGITS)}" for n, a in
                                      zip(names, qdd_shown, strict=True)))
    out.append("")
    out.append("f by source (in the coordinates' order):")
    noise = 1e-12 * g.f_scale  # rounding of the terms that make f
    for name, part in g.forces.items():
        part = np.where(np.abs(part) <= noise, 0.0, part)
        if np.any(part):
            out.append(f"  {name}: " + ", ".join(num(x, DIGITS) for x in part))
    out.extend(f"warning: {w}" for w in g.warnings)
    return "\n".join(out)


def coordinate_latex(label: str, order: int = 0, quasi: bool = False) -> str:
    """A coordinate's LaTeX: θ for an angle, s for a displacement, x, y for a body's
    position, ω for a quasi-velocity; `order` dots (a quasi-velocity is already a rate)."""
    source, _, what = label.rpartition(".")
    sub = latex_text(source)
    if what.startswith("w") and what[1:].isdigit():
        base, sub = r"\omega", f"{sub},{what[1:]}"
        order = max(order - 1, 0)
    elif what in ("angle", "theta", "angle1", "angle2"):
        base = r"\theta"
        if what in ("angle1", "angle2"):
            sub = f"{sub},{what[-1]}"
    elif what == "displacement":
        base = "s"
    else:
        base = what
    dots = {0: "", 1: r"\dot", 2: r"\ddot"}[order]
    return f"{dots}{{{base}}}_{{\\text{{{sub}}}}}" if dots else f"{base}_{{\\text{{{sub}}}}}"


def generalized_latex(g: Generalized) -> str:
    """``M q'' = f`` at the state as a LaTeX ``aligned`` block (numbers); see
    `too_many_to_write` for a large model."""
    cs = g.coordinate_set
    names = [coordinate_latex(c.label, 2, c.quasi) for c in cs.items]
    effort_rows = {r: e for e, r in cs.efforts}
    _, M_shown, f_shown, _ = cleaned(g)
    rows = []
    for i in range(len(g.f)):
        lhs = ""
        for c, name in zip(M_shown[i], names, strict=True):
            if c == 0.0:
                continue
            mag = num(abs(c), DIGITS)
            body = name if mag == "1" else f"{mag}\\,{name}"
            lhs += (f"-{body}" if c < 0 else body) if not lhs else \
                f" {'-' if c < 0 else '+'} {body}"
        rhs = num(float(f_shown[i]), DIGITS)
        if i in effort_rows:
            rhs += f" + {latex_symbol(effort_rows[i])}"
        rows.append(f"{lhs or '0'} &= {rhs}")
    return "\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}"


def too_many_to_write(k: int, max_written: int = MAX_WRITTEN) -> str:
    """Why the equations of `k` coordinates are not written as LaTeX ('' when they are)."""
    if k <= max_written:
        return ""
    return (f"the equations of {k} coordinates (up to {k} terms each) are too many for a "
            f"document: --latex writes at most {max_written}; -o FILE.npz, .mat or .json "
            "exports M, f and T")


def _symbol_latex(name: str) -> str:
    """LaTeX of a symbol of the symbolic Lagrange equations."""
    for suffix, order in (("_ddot", 2), ("_dot", 1)):
        if name.endswith(suffix) and "." in name:
            return coordinate_latex(name[:-len(suffix)], order)
    if "." in name:
        source, _, what = name.rpartition(".")
        if what in ("angle", "displacement", "theta", "x", "y", "angle1", "angle2"):
            return coordinate_latex(name)
        return latex_symbol(name)
    head, _, rest = name.partition("_")
    if head in ("m", "I") and rest:
        return f"{head}_{{\\text{{{latex_text(rest)}}}}}"
    if head in ("k", "c") and rest:
        return f"{head}_{{\\text{{{latex_text(rest)}}}}}"
    if head == "L0" and rest:
        return f"L_{{0,\\text{{{latex_text(rest)}}}}}"
    return latex_symbol(name)


def _sym_text(sym: SymbolicLagrange, e: sympy.Expr) -> str:
    import sympy

    return sympy.sstr(sym.shown(e))


def _sym_latex(sym: SymbolicLagrange, e: sympy.Expr) -> str:
    import sympy

    shown = sym.shown(e)
    names = {s: _symbol_latex(s.name) for s in shown.free_symbols}
    return sympy.latex(shown, symbol_names=names)


def _primes(sym: SymbolicLagrange) -> dict:
    """The rates' and accelerations' symbols as text writes them: O.angle', O.angle''."""
    import sympy

    out = {s: sympy.Symbol(f"{c}'") for s, c in zip(sym.qdot, sym.coordinates, strict=True)}
    out.update({s: sympy.Symbol(f"{c}''") for s, c in zip(sym.qddot, sym.coordinates,
                                                            strict=True)})
    return out


def symbolic_text(sym: SymbolicLagrange) -> str:
    """One equation per coordinate (its row of M times q'', in the coordinates' order, =
    its f), then the symbols' values."""
    k = len(sym.q)
    primes = _primes(sym)
    out = [f"model '{sym.model}': Lagrange's equations M(q) q'' = f(q, q') in symbols "
           f"({k} coordinate{'s' if k != 1 else ''}: {', '.join(sym.coordinates)})"]
    for i, label in enumerate(sym.coordinates):
        lhs = " + ".join(f"({_sym_text(sym, sym.M[i, j])})*{label_j}''"
                         for j, label_j in enumerate(sym.coordinates) if sym.M[i, j] != 0)
        rhs = _sym_text(sym, sym.f[i].xreplace(primes))
        efforts = [e for e, r in sym.efforts.items() if r == i]
        out.append(f"[{label}]")
        out.append(f"  {lhs or '0'}")
        out.append(f"    = {rhs}" + "".join(f" + {e}" for e in efforts))
    out.append("")
    out.append("where " + ", ".join(f"{s} = {num(v, DIGITS)}" for s, v in
                                    sorted(sym.values.items(), key=lambda kv: kv[0].name)))
    return "\n".join(out)


def symbolic_latex(sym: SymbolicLagrange) -> str:
    """The equations as the body of an ``align*`` environment (each row of M times q''
    in the coordinates' order)."""
    rows = []
    for i in range(len(sym.q)):
        lhs = " + ".join(
            "\\left(" + _sym_latex(sym, sym.M[i, j]) + "\\right) "
            + _symbol_latex(sym.qddot[j].name)
            for j in range(len(sym.q)) if sym.M[i, j] != 0)
        rhs = _sym_latex(sym, sym.f[i]) + "".join(
            f" + {latex_symbol(e)}" for e, r in sym.efforts.items() if r == i)
        rows.append(f"{lhs or '0'} &= {rhs}")
    return " \\\\\n".join(rows)


def latex_document(title: str, body: str, values: str = "") -> str:
    """A standalone LaTeX document around display math `body`."""
    return ("\\documentclass{article}\n\\usepackage{amsmath}\n\\usepackage[margin=2cm]"
            "{geometry}\n\\begin{document}\n\\section*{" + latex_text(title) + "}\n"
            "\\begin{align*}\n" + body + "\n\\end{align*}\n" + values
            + "\\end{document}\n")


def generalized_document(g: Generalized, sym: SymbolicLagrange | None = None) -> str:
    """``mbody lagrange MODEL --latex``: the equations (in symbols when `sym` is given)."""
    if sym is not None:
        values = ", ".join(f"${_symbol_latex(s.name)} = {num(v, DIGITS)}$" for s, v in
                           sorted(sym.values.items(), key=lambda kv: kv[0].name))
        return latex_document(f"{g.model.name}: Lagrange's equations", symbolic_latex(sym),
                              f"where {values}.\n\n")
    body = generalized_latex(g).replace("\\begin{aligned}\n", "").replace(
        "\n\\end{aligned}", "")
    return latex_document(f"{g.model.name}: equations in generalized coordinates at "
                          f"t = {g.state.t:g} s", body)

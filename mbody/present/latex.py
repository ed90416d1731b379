"""LaTeX for the equations: each body's Newton-Euler pair and the stacked system.

    body_latex(asm.bodies["rod"])   # \\begin{aligned} ... \\end{aligned} for one body
    stacked_latex(asm)              # M v̇ + b = Q + G λ with numbers (block form if large)
    document(asm)                   # a complete article (amsmath) that pdflatex compiles

Symbols: a_x, a_y, a_z mass-centre accelerations (world axes); α (planar) or ω̇_1..3
(body axes) angular accelerations; a reaction ``A.Fx`` is written F^{A}_{x} (moments
M^{A}_{x}, the universal joint's M^{A}_{t}). Names are escaped for LaTeX.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

import numpy as np

from mbody import conventions as cv
from mbody.equations.assemble import Assembly
from mbody.equations.fbd import REACTION, BodyEquations, Equation
from mbody.util.formatting import quiet

MAX_FULL = 12
"""Matrices with more rows or columns than this are shown in block form."""
TERMS_PER_LINE = 4
"""Right-hand-side terms per line of a body's equation before it continues below."""
MAX_BODIES = 200
"""Body sections in a document unless bodies are chosen (a longer one is not read)."""

_ACC = {"a_x": "a_{x}", "a_y": "a_{y}", "a_z": "a_{z}", "alpha": r"\alpha",
        "alpha_1": r"\dot{\omega}_{1}", "alpha_2": r"\dot{\omega}_{2}",
        "alpha_3": r"\dot{\omega}_{3}"}
_SPECIAL = {"\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&",
            "#": r"\#", "^": r"\textasciicircum{}", "_": r"\_", "%": r"\%",
            "~": r"\textasciitilde{}", "<": r"\textless{}", ">": r"\textgreater{}",
            "|": r"\textbar{}", '"': "{''}"}


def escape(text: str) -> str:
    """Text safe inside LaTeX text mode (or ``\\text{}``).

    Specials are escaped; letters of Latin-1 pass through (pdflatex reads UTF-8); any
    other non-ASCII character is written as its code point, e.g. ``[U+03B8]``.
    """
    out = []
    for ch in str(text):
        if ch in _SPECIAL:
            out.append(_SPECIAL[ch])
        elif ord(ch) < 128 or (ord(ch) < 256 and ch.isalpha()):
            out.append(ch)
        else:
            out.append(f"[U+{ord(ch):04X}]")
    return "".join(out)


def number(x: float, digits: int = 6) -> str:
    """A float as LaTeX: 6 significant digits, ``1.5\\times10^{-7}`` for exponents."""
    s = f"{quiet(float(x)):.{digits}g}"  # rounding noise from rotations as 0
    if s in ("-0", "0"):
        return "0"
    m = re.fullmatch(r"(-?[\d.]+)e([+-])0*(\d+)", s)
    if m:
        mant, sign, exp = m.groups()
        return f"{mant}\\times10^{{{'-' if sign == '-' else ''}{exp}}}"
    return s


def reaction_symbol(label: str) -> str:
    """``A.Fx`` -> ``F^{\\text{A}}_{x}``; ``U.Mt`` -> ``M^{\\text{U}}_{t}``."""
    joint, _, comp = label.partition(".")
    return f"{comp[0]}^{{\\text{{{escape(joint)}}}}}_{{{comp[1:]}}}"


def _term(coef: float, symbol: str, first: bool) -> str:
    if number(coef) == "0":  # zero, or rounding noise from rotations
        return ""
    mag = abs(coef)
    body = symbol if mag == 1 else f"{number(mag)}\\,{symbol}"
    if first:
        return f"-{body}" if coef < 0 else body
    return f" {'-' if coef < 0 else '+'} {body}"


def equation_latex(eq: Equation, per_line: int = TERMS_PER_LINE) -> str:
    """One row ``Σ M_rk a_k + b_r &= Q_r + Σ G_rc λ_c`` (``&`` before the equals sign).

    A right-hand side with many reaction terms continues on further aligned lines,
    `per_line` terms each, so that a body with many joints stays readable.

    Parameters
    ----------
    eq : Equation
        One row of a body's Newton-Euler pair (``asm.bodies[name].equations[k]``).
    per_line : int
        Right-hand-side terms per line before the equation continues below.

    Returns
    -------
    str
        One or more lines of an ``aligned`` environment (math mode), joined by ``\\\\``;
        the last has no line end.
    """
    left = ""
    for name, coef in eq.lhs.items():
        left += _term(coef, _ACC.get(name, escape(name)), not left)
    left = left or "0"
    if eq.gyro != 0 and number(eq.gyro) != "0":
        left += f" {'-' if eq.gyro < 0 else '+'} {number(abs(eq.gyro))}"
    terms = [number(eq.rhs)] if (number(eq.rhs) != "0" or not eq.reactions) else []
    for label, coef in eq.reactions.items():
        if term := _term(coef, reaction_symbol(label), not terms):
            terms.append(term)
    lines = ["".join(terms[i:i + per_line]) for i in range(0, len(terms), per_line)]
    return f"{left} &= " + " \\\\\n&\\quad ".join(lines or ["0"])


def body_latex(eq: BodyEquations) -> str:
    """One body's Newton-Euler pair as an ``aligned`` block (math mode, no delimiters).

    Planar: m a_x, m a_y (world axes), then I_G α. Spatial: Newton in world axes, then
    Euler's equations J ω̇ + ω × (J ω) about the mass centre in body axes.

    Parameters
    ----------
    eq : BodyEquations
        One body's equations, ``asm.bodies[name]``.

    Returns
    -------
    str
        ``\\begin{aligned} ... \\end{aligned}``, to put inside display math.
    """
    rows = [r"&\text{Newton (world axes):} \\"]
    rows += [rf"{equation_latex(e)} \\" for e in eq.newton]
    spin = "about $G$" if eq.fbd.dimension == cv.PLANAR else "about $G$, body axes"
    rows += [rf"&\text{{Euler ({spin}):}} \\"]
    rows += [rf"{equation_latex(e)} \\" for e in eq.euler]
    rows[-1] = rows[-1].removesuffix(r" \\")
    return "\\begin{aligned}\n" + "\n".join(rows) + "\n\\end{aligned}"


def free_body_latex(eq: BodyEquations) -> str:
    """The body's forces split into applied (known) and constraint (unknown) ones."""
    f = eq.fbd
    applied = [escape(x.name) for x in f.forces if x.kind != REACTION]
    known = [rf"${reaction_symbol(x.label)} = {number(x.value)}$" for x in f.forces
             if x.kind == REACTION and x.value is not None]
    unknown = [f"${reaction_symbol(x.label)}$" for x in f.forces if x.unknown]
    lines = [rf"Mass ${number(f.mass)}$~kg; "
             + ("a particle: no rotational inertia, Newton's rows only." if not eq.euler
                else rf"$I_G = {number(f.inertia[2, 2])}$~kg\,m$^2$." if f.dimension == cv.PLANAR
                else r"$J = " + _matrix(np.asarray(f.inertia), "pmatrix") + r"$~kg\,m$^2$ "
                "(body axes).")]
    lines.append(r"Applied forces (known): " + (", ".join(applied) or "none") + ".")
    if known:
        lines.append(r"Reactions with known values: " + ", ".join(known) + ".")
    lines.append(r"Constraint forces (unknown): " + (", ".join(unknown) or "none") + ".")
    return "\n\n".join(lines)


def _matrix(A: np.ndarray, env: str = "bmatrix") -> str:
    rows = [" & ".join(number(v) for v in r) for r in np.atleast_2d(A)]
    return f"\\begin{{{env}}}" + r" \\ ".join(rows) + f"\\end{{{env}}}"


def _column(items: Iterable[str]) -> str:
    return r"\begin{bmatrix}" + r" \\ ".join(items) + r"\end{bmatrix}"


def _acc_symbols(asm: Assembly) -> list[str]:
    return [f"{_ACC[cv.ACCELERATION_NAMES[r]]}^{{\\text{{{escape(b)}}}}}"
            for b, r in (c.rsplit(".", 1) for c in asm.coordinates)]


def stacked_latex(asm: Assembly, max_full: int = MAX_FULL) -> str:
    """``M v̇ + b = Q + G λ`` in numbers (display math, no delimiters).

    When M has at most `max_full` rows and G at most `max_full` columns, every matrix is
    written out; otherwise M is shown as its first diagonal blocks and G as the pattern
    of non-zero (body, joint) blocks, since a page cannot hold the numbers.

    Parameters
    ----------
    asm : Assembly
        The equations at one state (`assemble`).
    max_full : int
        Largest number of rows of M and columns of G written out in full.

    Returns
    -------
    str
        LaTeX for display math (no ``\\[ \\]`` around it).
    """
    N, m = len(asm.coordinates), len(asm.reactions)
    if max(N, m) <= max_full:
        lhs = (_matrix(asm.M.toarray()) + _column(_acc_symbols(asm))
               + ("" if not np.any(asm.b) else " + " + _column(number(v) for v in asm.b)))
        rhs = _column(number(v) for v in asm.Q)
        if m:
            rhs += (" + " + _matrix(asm.G.toarray())
                    + _column(reaction_symbol(r) for r in asm.reactions))
        return f"{lhs}\n= {rhs}"
    return _block_form(asm, max_full)


def _block_form(asm: Assembly, max_full: int) -> str:
    model = asm.model
    names = list(model.body_names)
    k = model.rows_per_body
    shown = names[:2]
    M = asm.M.tocsr()
    parts = [r"M = \operatorname{diag}(" + ", ".join(
        rf"M_{{\text{{{escape(b)}}}}}" for b in shown)
        + (r", \dots" if len(names) > len(shown) else "") + ")"]
    rows = [model.body_rows(i) if model.has_particles else np.arange(i * k, (i + 1) * k)
            for i in range(len(shown))]
    parts += [rf"M_{{\text{{{escape(b)}}}}} = "
              + _matrix(M[rows[i]][:, rows[i]].toarray())
              for i, b in enumerate(shown)]
    # G: which body's rows each joint's columns touch (a block pattern, truncated).
    jt = model.reaction_table
    if len(jt.labels):
        joints = [j.name for j in model.joints][:max_full]
        bodies = names[:max_full]
        pat = np.zeros((len(bodies), len(joints)), dtype=bool)
        for c in range(len(jt.labels)):
            j = jt.joint[c]
            for b in (jt.child[c], jt.parent[c]):
                if 0 <= b < len(bodies) and j < len(joints):
                    pat[b, j] = True
        head = " & ".join(rf"\text{{{escape(j)}}}" for j in joints)
        body_rows = [rf"\text{{{escape(b)}}} & " + " & ".join(
            r"\times" if v else r"\cdot" for v in pat[i]) for i, b in enumerate(bodies)]
        more = []
        if len(model.joints) > len(joints) or model.n > len(bodies):
            more = [rf"\text{{(first {len(bodies)} bodies, {len(joints)} joints)}}"]
        parts.append(r"G\ \text{blocks (}\times = \text{non-zero)}:\ \begin{array}{r|"
                     + "c" * len(joints) + "} & " + head + r" \\ \hline "
                     + r" \\ ".join(body_rows + more) + r"\end{array}")
    size = (rf"\text{{{len(asm.coordinates)} rows, {len(asm.reactions)} reaction "
            r"unknowns}")
    return ("\\begin{gathered}\n" + r"M \dot{v} + b = Q + G\lambda,\quad " + size
            + " \\\\\n" + " \\\\\n".join(parts) + "\n\\end{gathered}")


def document(asm: Assembly, title: str | None = None, bodies: Iterable[str] | None = None,
             max_full: int = MAX_FULL, max_bodies: int = MAX_BODIES) -> str:
    """A complete LaTeX document: conventions, each body's free body and Newton-Euler
    pair, then the stacked system.

    Parameters
    ----------
    asm : Assembly
        The equations at one state (`assemble`).
    title : str, optional
        The document's title (default "Newton-Euler equations of" the model's name).
    bodies : iterable of str, optional
        The bodies that get a section, by name (default: the first `max_bodies` bodies in
        stacking order).
    max_full : int
        Largest number of rows of M and columns of G written out in full (see
        `stacked_latex`).
    max_bodies : int
        Most body sections when `bodies` is not given (a longer document is not read).

    Returns
    -------
    str
        The source of an article (amsmath, graphicx) that pdflatex compiles.
    """
    model = asm.model
    names = list(model.body_names[:max_bodies] if bodies is None else bodies)
    title = title or f"Newton-Euler equations of {model.name}"
    planar = model.dimension == cv.PLANAR
    rows = ", ".join(cv.PLANAR_ROWS if planar else cv.SPATIAL_ROWS)
    out = [
        r"\documentclass[11pt]{article}",
        r"\usepackage[margin=2cm]{geometry}",
        r"\usepackage{amsmath}",
        r"\usepackage{graphicx}",
        r"\setcounter{MaxMatrixCols}{40}",
        # Shrink a display to the line width only when it is wider (never enlarge it).
        r"\newcommand{\fitbox}[1]{\resizebox{\ifdim\width>\linewidth\linewidth\else"
        r"\width\fi}{!}{#1}}",
        rf"\title{{{escape(title)}}}",
        r"\author{}",
        r"\date{}",
        r"\begin{document}",
        r"\maketitle",
        r"\section*{Conventions}",
        (rf"{'Planar' if planar else 'Spatial'} model, {model.n} "
         rf"bod{'y' if model.n == 1 else 'ies'}, rows per body: {escape(rows)}"
         + (" (a particle: its translations only)" if model.has_particles else "") + ". "
         r"Newton rows are $m\,a_G$ in world axes; Euler rows are "
         + (r"$I_G\,\alpha$ about the mass centre." if planar else
            r"$J\dot{\omega} + \omega\times(J\omega)$ about the mass centre in body axes.")
         + r" A reaction $R$ acts on the joint's child as $+R$ at the joint point and on "
         r"its parent as $-R$, along the axes of the joint frame (fixed to the parent). "
         r"The stacked system is $M\dot{v} + b = Q + G\lambda$."),
    ]
    if np.any(model.gravity):
        g = model.gravity[:2] if planar else model.gravity
        out.append(r"Gravity $g = (" + ", ".join(number(v) for v in g)
                   + r")$~m/s$^2$ (world).")
    for name in names:
        eq = asm.bodies[name]
        out += [rf"\section*{{Body {escape(name)}}}", free_body_latex(eq),
                _display(body_latex(eq))]
    if len(names) < model.n:
        out.append(rf"({model.n - len(names)} more bodies not shown; choose bodies with "
                   r"\texttt{--body NAME}.)")
    out += [r"\section*{Stacked system}", _display(stacked_latex(asm, max_full)),
            r"\end{document}", ""]
    return "\n".join(out)


def _display(math: str) -> str:
    return "\\[\n\\fitbox{$\\displaystyle\n" + math + "\n$}\n\\]"

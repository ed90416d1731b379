"""The symbolic rows as text and LaTeX: numbers, symbols' LaTeX, a row's terms joined,
the gyroscopic term as a textbook writes it, and the values lines under a body's rows.

The rows' ``text``, ``latex`` and ``document`` methods (`mbody.equations.symbolic.rows`)
call these. sympy is imported only to print a term's factors.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mbody import joint_types
from mbody.equations.symbolic.terms import BODY_AXES, GYROSCOPIC, WORLD_AXES, Term

if TYPE_CHECKING:
    from mbody.equations.symbolic.rows import SymbolicBody, SymbolicRow

_UNITS = {"m": "kg", "I": "kg m^2", "g": "m/s^2", "w": "rad/s", "F": "N", "M": "N m",
          "T": "N"}
_LATEX_TEXT = {"\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&",
               "#": r"\#", "^": r"\textasciicircum{}", "_": r"\_", "%": r"\%",
               "~": r"\textasciitilde{}", "<": r"\textless{}", ">": r"\textgreater{}",
               "|": r"\textbar{}", '"': "{''}"}


def num(x: float, digits: int) -> str:
    """`x` in `digits` significant digits; an integral value without a point."""
    x = float(x)
    if x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x) if digits >= 17 else f"{x:.{digits}g}"


def latex_number(x: float, digits: int) -> str:
    """`num` in LaTeX: an exponent written ``\\times10^{k}``."""
    s = num(x, digits)
    if "e" in s:
        mant, _, exp = s.partition("e")
        return rf"{mant}\times10^{{{int(exp)}}}"
    return s


def latex_text(text: str) -> str:
    """`text` safe inside LaTeX text mode (``\\text{}``): specials escaped.

    Parameters
    ----------
    text : str
        A model, body or load name.

    Returns
    -------
    str
    """
    return "".join(_LATEX_TEXT.get(ch, ch) if ord(ch) < 128 or ch.isalpha() else
                   f"[U+{ord(ch):04X}]" for ch in str(text))


def latex_symbol(name: str) -> str:
    """The LaTeX of a symbol name: ``alpha_1`` -> ``\\dot{\\omega}_{1}``, ``O.Fx`` ->
    ``F^{\\text{O}}_{x}``, ``F_push_x`` -> ``F^{\\text{push}}_{x}``, ``I_12`` -> ``I_{12}``.

    Parameters
    ----------
    name : str
        A symbol of the vocabulary (see `mbody.equations.symbolic`).

    Returns
    -------
    str
    """
    fixed = {"alpha": r"\alpha", "w": r"\omega", "I_G": "I_G", "m": "m", "g": "g"}
    if name in fixed:
        return fixed[name]
    if "." in name:  # a reaction label
        joint, _, comp = name.rpartition(".")
        return f"{comp[0]}^{{\\text{{{latex_text(joint)}}}}}_{{{latex_text(comp[1:])}}}"
    head, _, rest = name.partition("_")
    if head in ("alpha", "w", "a", "I") and rest:
        base = {"alpha": r"\dot{\omega}", "w": r"\omega", "a": "a", "I": "I"}[head]
        return f"{base}_{{{rest}}}"
    load, _, comp = rest.rpartition("_")
    if head in ("F", "M") and comp in WORLD_AXES + BODY_AXES and load:
        return f"{head}^{{\\text{{{latex_text(load)}}}}}_{{{comp}}}"
    return f"{head}^{{\\text{{{latex_text(rest)}}}}}"  # M_<couple> (planar), T_<spring>


def _factor_text(term: Term, latex: bool) -> str:
    import sympy

    if latex:
        names = {s: latex_symbol(s.name) for s in term.shown.free_symbols}
        return sympy.latex(term.shown, order="none", symbol_names=names)
    return sympy.sstr(term.shown, order="none")


def join_terms(terms: tuple[Term, ...], digits: int, latex: bool) -> str:
    """The terms as one side of a row, signs between them (text, or LaTeX)."""
    out = ""
    for term in terms:
        factor = _factor_text(term, latex)
        if len(term.factors) == 1 and isinstance(term.factors[0], _add_type()):
            factor = rf"\left({factor}\right)" if latex else f"({factor})"
        mag = abs(term.coefficient)
        number = latex_number(mag, digits) if latex else num(mag, digits)
        body = factor if number == "1" else (f"{number}\\,{factor}" if latex else
                                             f"{number}*{factor}")
        negative = term.coefficient < 0
        if not out:
            out = f"-{body}" if negative else body
        else:
            out += f" {'-' if negative else '+'} {body}"
    return out


def _add_type() -> type:
    import sympy

    return sympy.Add


def gyro_text(row: SymbolicRow, digits: int) -> str:
    """This row of b = ω × Jω, written the way round a textbook writes it: the row's
    gyroscopic terms with their signs turned: (I_3 - I_2)*w_2*w_3, w_2*h_3 - w_3*h_2."""
    import sympy

    terms = []
    for t in row.right:
        if t.part != GYROSCOPIC:
            continue
        first, *rest = t.factors
        if len(rest) == 2:  # principal: -(I_k - I_l) w_k w_l = (I_l - I_k) w_k w_l
            a, b = first.args
            terms.append(Term(t.coefficient, (sympy.Add(-b, -a, evaluate=False), *rest),
                              t.part, t.key))
        else:  # w_l h_k - w_k h_l  ->  w_k h_l - w_l h_k
            terms.append(Term(-t.coefficient, t.factors, t.part, t.key))
    terms.sort(key=lambda t: t.coefficient < 0)
    return join_terms(tuple(terms), digits, False) or "0"


def inertia_words(form: str) -> str:
    """What a body's inertia symbols are, in words, for its inertia form."""
    return {"planar": "mass m, moment of inertia I_G about the mass centre",
            "principal": "mass m, principal moments I_1, I_2, I_3 (body axes)",
            "tensor": "mass m, inertia tensor entries I_jk (body axes, I_jk = I_kj; "
                      "zero entries left out)",
            "particle": "mass m (a particle: Newton's rows only)"}[form]


def _unit(name: str) -> str:
    if "." in name:  # a reaction label: a force component or a moment
        return joint_types.unit(name)
    return _UNITS.get(name.partition("_")[0], "")


def _family(name: str) -> str:
    """Which line of the values a symbol goes on: the body, its spin, a load, a reaction."""
    if "." in name:
        return "reactions"
    head, _, rest = name.partition("_")
    if head in ("m", "g", "I"):
        return "body"
    if head == "w":
        return "spin"
    return rest.rpartition("_")[0] if head in ("F", "M") and rest.count("_") else rest


def value_lines(body: SymbolicBody, digits: int) -> list[str]:
    """The values of the body's symbols at this state (how they are made, where they vary
    or come from a spring), then the unknown reactions: a few lines under the rows."""
    lines: dict[str, list[tuple[str, str]]] = {}
    for name, v in body.values.items():
        unit, how = _unit(name), body.definitions.get(name)
        if how is not None:
            at = "" if name.startswith("T_") else f" at t = {body.t:g} s"
            item = f"{name} = {how} = {num(v, digits)}"
            lines.setdefault(name, []).append((item, f"{unit}{at}"))
        else:
            known = " (known)" if "." in name else ""
            lines.setdefault(_family(name), []).append(
                (f"{name} = {num(v, digits)}", f"{unit}{known}"))
    order = {"body": 0, "spin": 1, "reactions": 3}
    out = []
    for _, items in sorted(lines.items(), key=lambda kv: order.get(kv[0], 2)):
        text = ""  # a run of values with one unit writes the unit once, at its end
        for k, (item, unit) in enumerate(items):
            last = k + 1 == len(items) or items[k + 1][1] != unit
            text += item + (f" {unit}".rstrip() + ("; " if not last or k + 1 < len(items)
                                                   else "") if last else ", ")
        out.append("  " + text.rstrip("; "))
    if body.unknowns:
        out.append("  unknown: " + ", ".join(body.unknowns))
    return (["values:"] + out) if out else []

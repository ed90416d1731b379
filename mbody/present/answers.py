"""The report's "Your equations" section: a student's answers beside the expected rows.

One table row per equation in file order: the equation as written, the verdict, the row
it was compared with and the explanation; then the rows no correct equation gave. Plain
HTML with its own few styles, so that `mbody.present.report` only appends it.
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mbody.answers.verify import Verification

_STYLE = """
table.answers td { vertical-align: top; }
table.answers code { white-space: pre-wrap; }
.verdict-ok { color: #1b7a32; font-weight: bold; }
.verdict-bad { color: #b3261e; font-weight: bold; }
"""


def _e(s: object) -> str:
    return html.escape(str(s), quote=True)


def answers_section(v: Verification) -> str:
    """The section as one HTML string (id ``answers``).

    Parameters
    ----------
    v : Verification
        What `mbody.verify` found for the student's equations.

    Returns
    -------
    str
        A ``<section>`` element: a table of the equations beside the expected rows, the
        rows not covered and a one-line summary.
    """
    n = len(v.checks)
    who = f" by {_e(v.student)}" if v.student else ""
    out = [f'<section id="answers"><style>{_STYLE}</style><h2>Your equations</h2>',
           f"<p>{v.correct} of {n} equation{'s' if n != 1 else ''}{who} "
           f"(<code>{_e(v.answers_file)}</code>) are rows of the model's Newton-Euler "
           f"equations, checked to a relative tolerance of {v.tol:g} on each coefficient; "
           f"{v.rows - len(v.uncovered)} of the {v.rows} rows of the bodies answered are "
           "covered.</p>",
           '<table class="answers"><tr><th>#</th><th>body</th><th>your equation</th>'
           "<th>verdict</th><th>expected row</th><th>why</th></tr>"]
    for c in v.checks:
        verdict = "verdict-ok" if c.correct else "verdict-bad"
        expected = (f"<code>{_e(c.expected)}</code><br><span class=\"muted\">{_e(c.row)}"
                    "</span>" if c.expected else "")
        out.append(f"<tr><td>{c.index}</td><td>{_e(c.body)}</td><td><code>{_e(c.eq)}"
                   f"</code></td><td class=\"{verdict}\">{_e(c.diagnosis)}</td>"
                   f"<td>{expected}</td><td>{_e(c.explanation)}</td></tr>")
    out.append("</table>")
    if v.uncovered:
        out.append("<h3>Rows no correct equation gave</h3><table class=\"answers\">"
                   "<tr><th>row</th><th>expected</th></tr>")
        out += [f"<tr><td>{_e(u.row)}</td><td><code>{_e(u.expected)}</code></td></tr>"
                for u in v.uncovered]
        out.append("</table>")
    out.append("</section>")
    return "".join(out)

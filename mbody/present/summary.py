"""A class's answers as one HTML page (``mbody verify ... --summary class.html``): one row
per answers file, each wrong equation's diagnosis, then the class's most frequent
mistakes with what each means. Self-contained, escaped, offline."""

from __future__ import annotations

from mbody.answers.summary import MISTAKES_HEADER, ClassSummary, mistake_text
from mbody.answers.verify import MEANINGS
from mbody.present.html import STYLE, Markup, e, table, tag


def class_summary_html(summary: ClassSummary) -> str:
    """The page (module doc).

    Parameters
    ----------
    summary : ClassSummary
        From `mbody.answers.summary.grade`.

    Returns
    -------
    str
        A whole HTML document.
    """
    rows = []
    for g in summary.graded:
        wrong = Markup("".join(tag("div", mistake_text(c), title=c.meaning)
                               for c in g.wrong))
        rows.append([g.file, g.student, g.equations, g.correct,
                     wrong if g.wrong else "", g.error])
    files = table(["file", "student", "equations", "correct", "mistakes", "error"], rows,
                  numeric=(2, 3))
    mistakes = table(list(MISTAKES_HEADER),
                     [[m.diagnosis, m.row, m.equations, m.students, MEANINGS[m.diagnosis]]
                      for m in summary.mistakes], numeric=(2, 3))
    head = "\n".join(e(line) for line in summary.text().splitlines()[:1])
    title = f"Answers for model '{summary.model}'"
    body = tag("div", tag("h1", title), tag("p", Markup(head)), tag("h2", "By file"), files,
               tag("h2", "The class's most frequent mistakes"),
               mistakes if summary.mistakes else tag("p", "none: every equation is correct"),
               class_="mbody")
    return ("<!DOCTYPE html>\n" + str(tag("html", tag("head", tag("meta", charset="utf-8"),
                                                     tag("title", title),
                                                     tag("style", Markup(STYLE))),
                                          tag("body", body), lang="en")) + "\n")

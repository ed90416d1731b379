"""A class's answers as one HTML page (``mbody verify ... --summary class.html``): one row
per answers file (its counts, the rows asked for and given, each wrong equation's
diagnosis, the entries that could not be read), then the class's most frequent mistakes
with what each means. Self-contained, escaped, offline."""

from __future__ import annotations

from mbody.answers.summary import COVERAGE_HEADER, MISTAKES_HEADER, ClassSummary, mistake_text
from mbody.answers.verify import MEANINGS
from mbody.present.html import STYLE, Markup, table, tag


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
        problems = g.verification.errors if g.verification else ()
        error = Markup("".join(tag("div", str(i)) for i in problems)) if problems else \
            g.error
        rows.append([g.file, g.student, g.equations, g.correct, wrong if g.wrong else "",
                     g.covered, g.asked, g.duplicates, g.values, error])
    files = table(["file", "student", "equations", "correct", "mistakes",
                   *COVERAGE_HEADER, "error"], rows, numeric=(2, 3, 5, 6, 7))
    mistakes = table(list(MISTAKES_HEADER),
                     [[m.diagnosis, m.row, m.equations, m.students, MEANINGS[m.diagnosis]]
                      for m in summary.mistakes], numeric=(2, 3))
    head = [tag("p", line) for line in summary.text().splitlines()[:2]]
    title = f"Answers for model '{summary.model}'"
    body = tag("div", tag("h1", title), *head, tag("h2", "By file"), files,
               tag("h2", "The class's most frequent mistakes"),
               mistakes if summary.mistakes else tag("p", "none: every equation is correct"),
               class_="mbody")
    return ("<!DOCTYPE html>\n" + str(tag("html", tag("head", tag("meta", charset="utf-8"),
                                                     tag("title", title),
                                                     tag("style", Markup(STYLE))),
                                          tag("body", body), lang="en")) + "\n")

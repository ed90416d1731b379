"""Checking a student's equations: `verify(model, answers) -> Verification`.

The course asks a tool to *check* a free body and its equations, not to write them.
Each equation of an answers file is read by a small safe parser (`parse`), given the
model's numbers for the names it uses (`vocabulary`, `linear`), and compared up to scale
with the body's true Newton-Euler rows (`rows`, `compare`); a wrong one is matched
against the course's misconceptions, each built as a variant of a true row
(`diagnose`). `verify` ties it together; `load` reads the answers file.
"""

from mbody.answers.diagnose import DIAGNOSES
from mbody.answers.load import Answers, AnswersError, answers_from_data, read_answers
from mbody.answers.verify import Check, Uncovered, Verification, verify

__all__ = ["DIAGNOSES", "Answers", "AnswersError", "Check", "Uncovered", "Verification",
           "answers_from_data", "read_answers", "verify"]

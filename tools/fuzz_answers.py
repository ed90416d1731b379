"""Structure-aware fuzzer of answers files: mutated and generated equations through verify.

    python tools/fuzz_answers.py [-n 10000] [--seed 0] [--jobs N] [--heavy-every 100]
                                 [--hang 60] [--only I]

Each case (number i of the run, reproducible from --seed and i alone) pairs a shipped
model with an answers file: one of models/answers/ (with its model), or equations
generated from any shipped model's true rows, written as a student writes them (numbers
rounded to 3 to 17 figures, terms on either side, the row scaled, sometimes a course
mistake made in numbers: a term left out, a sign flipped, a coefficient 1 % off). Then it
changes the file one to three times, knowing the format:

- in an equation: a number made awkward (huge, tiny, below the smallest double, 400
  digits, '1e', '1_000'); an operator inserted, replaced or dropped; a name misspelt,
  swapped for another (a textbook spelling, another body's reaction, '__import__'); a
  unicode character (subscripts, Greek, combining marks, zero-width, fullwidth digits,
  emoji); nesting (parentheses, functions, signs, power towers, up to hundreds of
  levels); a long flat sum or product; factors of 1e100*1e100*... or 1e-200*1e-200; the
  sides swapped, emptied or doubled; a function of an unknown, a product of unknowns;
  the text cut or padded past 2000 characters;
- in the YAML: a body misspelt or not a name, an equation that is not text, a key
  dropped, added or misspelt, entries duplicated (up to thousands), the list replaced
  by something else, an odd `student`, a top level that is not a mapping; the document
  written in block or flow style, equations double-quoted, single-quoted or plain; then,
  sometimes, the text damaged as tools/fuzz.py damages a model (tabs, lines dropped or
  swapped, cut short, stray characters, CRLF, BOM, bad bytes, aliases).

It runs ``mbody verify MODEL ANSWERS`` and ``... --json`` through ``mbody.cli.main`` in
this process (tools/fuzz.py's `run_command`: output captured, numpy's RuntimeWarnings as
errors), and on every --heavy-every'th case that verify judged, ``mbody report --answers``
too. Each command is classified by tools/fuzz.py's `classify`, with what an answers file
adds: judged (exit 0 or 1: every equation got a verdict; exit 0 only when all are correct;
--json is strict JSON, NaN and Infinity refused), clean error (exit 2: one message, every
problem in the answers located file:line:column), crash (exit 70, a traceback, a warning,
an unlocated problem, JSON that is not strict) or hang (tools/fuzz.py's watchdog). The
counts are printed at the end with the first crashes and hangs in full (``--only I``
reruns one).
"""

from __future__ import annotations

import copy
import json
import os
import random
import re
import shutil
import sys
import tempfile
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import yaml

TOOLS = Path(__file__).resolve().parent
ROOT = TOOLS.parent
for _p in (ROOT, TOOLS):  # run from a checkout without installing; tools/fuzz.py
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

import fuzz  # noqa: E402
from fuzz import ACCEPTED, CLEAN, CRASH, HANG, Outcome, Raw  # noqa: E402

MODELS = ROOT / "models"
ANSWERS = MODELS / "answers"
JUDGED = ACCEPTED
"""verify read every equation and gave each a verdict (tools/fuzz.py's 'accepted')."""


# -- the inputs --------------------------------------------------------------------------------

@dataclass(frozen=True)
class Base:
    """A model of models/ and, for a shipped answers file, its data (else None: generate)."""

    model: str
    answers: dict | None


def _bases() -> list[Base]:
    shipped = [Base(p.name, yaml.safe_load(p.read_text(encoding="utf-8")))
               for p in sorted(ANSWERS.glob("*.yaml"))]
    return shipped + [Base(p.name, None) for p in sorted(MODELS.glob("*.yaml"))]


@dataclass(frozen=True)
class Sheet:
    """What generation and mutation know of a model: each body's true rows and names."""

    bodies: tuple[str, ...]
    rows: tuple[tuple[str, object], ...]  # (body, TrueRow)
    names: dict[str, tuple[str, ...]]  # body -> its vocabulary's names
    reactions: tuple[str, ...]


@cache
def sheet(model_name: str) -> Sheet:
    import mbody
    from mbody.answers.rows import body_rows
    from mbody.answers.vocabulary import vocabulary

    model = mbody.load(MODELS / model_name)
    asm = mbody.assemble(model)
    rows, names = [], {}
    for b in model.body_names:
        rows += [(b, r) for r in body_rows(asm, b).rows if r.row.unknowns]
        names[b] = tuple(vocabulary(model, asm.state, b).names)
    return Sheet(tuple(model.body_names), tuple(rows), names, tuple(model.reactions))


def written(rng: random.Random, row, mistake: bool) -> tuple[str, str]:
    """A true row as a student writes it (and what was done)."""
    terms = [(k, v) for k, v in row.coef.items() if v != 0.0]
    did = "row"
    if mistake and terms:
        j = rng.randrange(len(terms))
        key, v = terms[j]
        kind = rng.choice(["drop", "sign", "off"])
        if kind == "drop" and len(terms) > 1:
            del terms[j]
        elif kind == "sign":
            terms[j] = (key, -v)
        else:
            terms[j] = (key, v * 1.01)
        did = f"row, {kind} {key}"
    scale = rng.choice([1.0, 1.0, -1.0, 2.5, 0.1, 1e-3, 1e3, 1e-150, 1e90])
    fmt = rng.choice(["g", ".4g", ".6g", ".10g", "r"])
    left, right = [], []
    for key, v in terms:
        c = v * scale
        side = left if rng.random() < 0.6 else right
        if side is right:
            c = -c
        number = repr(c) if fmt == "r" else format(c, fmt)
        if key == "1":
            side.append(f"({number})")
        elif number in ("1", "1.0") and rng.random() < 0.7:
            side.append(key)
        else:
            side.append(f"{number}*{key}" if rng.random() < 0.5 else f"({number})*{key}")
    rng.shuffle(left)
    rng.shuffle(right)
    return f"{' + '.join(left) or '0'} = {' + '.join(right) or '0'}", did


def generated(rng: random.Random, s: Sheet) -> tuple[dict, str]:
    """An answers document of a few of the model's rows written by a student."""
    if not s.rows:
        return {"equations": [{"body": s.bodies[0], "eq": "m*a_x = 0"}]}, "one"
    entries, did = [], []
    for _ in range(rng.choice([1, 1, 2, 3, 4, 6])):
        body, r = rng.choice(s.rows)
        eq, what = written(rng, r.row, mistake=rng.random() < 0.4)
        entries.append({"body": body, "eq": eq})
        did.append(what)
    doc: dict = {"equations": entries}
    if rng.random() < 0.3:
        doc = {"student": rng.choice(["a student", "É. Ñ", 42, ""]), **doc}
    return doc, "generated: " + ", ".join(did)


_NUMBER = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_NAME = re.compile(r"[^\W\d]\w*(?:\.[^\W\d]\w*)?")
NUMBERS = ["0", "0.0", "1e100", "1e101", "1e308", "1e309", "1e400", "1e-100", "1e-170",
           "1e-300", "1e-320", "5e-324", "1e-400", "2.2250738585072014e-308", ".5", "5.",
           "1e", "1e+", "00012", "1_000", "1,5", "0x1F", "inf", "nan", "9" * 400,
           "123456789" * 30, "1.7976931348623157e308", "4.9e-324", "-0"]
UNICODE = ["α", "ω", "θ", "ω₁", "₁", "₂", "₃", "²", "³", "−", "·", "×", "⋅", "√", "°", "′",
           "\u0307", "\u0301", "\u200b", "\u202e", "\u00a0", "\u2028", "１", "２", "😀", "ℝ",
           "ſ", "\u212a", "ﬁ", "Ω", "µ", "İ", "ω̇", "θ̈", "∂", "∑", "½", "⁻¹", "𝑎", "ⅈ"]
NAMES = ["a_x", "a_y", "a_z", "alpha", "alpha_1", "alpha_3", "w", "w_1", "w_3", "theta",
         "m", "g", "I_G", "I_1", "I_3", "I_11", "I_12", "I_O", "pi", "t", "omega_1", "w1",
         "ω_1", "α", "ax", "theta_ddot", "omega1_dot", "omega_dot", "mg", "x", "sin", "exp",
         "e", "__import__", "a_x.__class__", "O.Fx", "O.Fx.y", "A.Mz", "ground.Fx", "Fx",
         "nan", "inf", "λ", "F_push_x", "T_spring", "I_xx", "w_x", "M_1", "rod", "_",
         "a" * 300]
FUNCTIONS = ["sin", "cos", "tan", "sqrt", "exp", "log", "abs", "max", "eval", "getattr"]
OPERATORS = ["+", "-", "*", "/", "^", "**", "=", "(", ")", "//", "==", "<", ";", ",", "'",
             "[", "{", ".", "!", "%", "&", "@", "\\", "#", ":", '"', "`", "|"]
LARGE = ["1e100*1e100*1e100*1e100", "1e100*1e100*1e100", "1e-200*1e-200", "1e100^4",
         "exp(700)", "exp(710)", "1e-170", "1e100/1e-100/1e-100", "(1e100*1e100+2-1e100*1e100)",
         "0*(1e100*1e100*1e100*1e100)", "1e-300/1e300", "2^1024", "2^-1075", "10^308"]


def _sub(rng: random.Random, text: str, pattern: re.Pattern[str], new) -> tuple[str, str]:
    spots = list(pattern.finditer(text))
    if not spots:
        return text, ""
    m = rng.choice(spots)
    repl = new(m.group()) if callable(new) else new
    return text[:m.start()] + repl + text[m.end():], f"{m.group()!r:.20} -> {repl!r:.30}"


def _wrap(rng: random.Random, eq: str) -> str:
    left, _, right = eq.partition("=")
    side = rng.choice(["left", "right", "both"])
    k = rng.choice([1, 2, 50, 98, 99, 100, 101, 102, 300, 1000])
    form = rng.randrange(6)

    def nest(x: str) -> str:
        if form == 0:
            return "(" * k + x + ")" * k
        if form == 1:
            f = rng.choice(FUNCTIONS[:5])
            return f"{f}(" * k + x + ")" * k
        if form == 2:
            return "-" * k + f"({x})"
        if form == 3:
            return f"({x}) + " + "^".join(["2"] * k)
        if form == 4:
            return f"({x}) + " + "^".join(["1"] * k)
        return "-(" * k + x + ")" * k
    if not _:
        return nest(eq)
    if side == "left":
        return f"{nest(left)}={right}"
    if side == "right":
        return f"{left}={nest(right)}"
    return f"{nest(left)}={nest(right)}"


def mutate_eq(rng: random.Random, eq: str, names: tuple[str, ...]) -> tuple[str, str]:
    """Change one equation once; return it and what was done."""
    op = rng.randrange(12)
    if op == 0:
        out, what = _sub(rng, eq, _NUMBER, lambda _: rng.choice(NUMBERS))
        if what:
            return out, f"number {what}"
    if op == 1:
        i = rng.randrange(len(eq) + 1)
        how = rng.randrange(3)
        if how == 0 or not eq:
            return eq[:i] + rng.choice(OPERATORS) + eq[i:], "insert operator"
        i = min(i, len(eq) - 1)
        if how == 1:
            return eq[:i] + rng.choice(OPERATORS) + eq[i + 1:], "replace character"
        return eq[:i] + eq[i + 1:], "drop character"
    if op == 2:
        pool = [*NAMES, *names] if names else NAMES
        out, what = _sub(rng, eq, _NAME, lambda w: rng.choice(pool) if rng.random() < 0.6
                         else fuzz._misspell(rng, w))
        if what:
            return out, f"name {what}"
    if op == 3:
        i = rng.randrange(len(eq) + 1)
        if rng.random() < 0.3:
            digits = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")
            return re.sub(r"_(\d)", lambda m: m.group(1).translate(digits), eq), "subscripts"
        return eq[:i] + rng.choice(UNICODE) + eq[i:], "unicode"
    if op == 4:
        return _wrap(rng, eq), "nesting"
    if op == 5:
        k = rng.choice([10, 100, 490, 997, 1500])
        piece = rng.choice(["+1", "+0*a_x", "*1", "-t", "+a_x", "+(1)", "*1.0001", "/1"])
        left, sep, right = eq.partition("=")
        return (left + piece * k + sep + right) if rng.random() < 0.5 else \
            (eq + piece * k), f"long {piece!r} x {k}"
    if op == 6:
        factor = rng.choice(LARGE)
        left, sep, right = eq.partition("=")
        how = rng.randrange(3)
        if how == 0:
            return f"{factor}*({left}){sep}{factor}*({right})", f"both sides times {factor}"
        if how == 1:
            return f"{left}{sep}{right} + {factor}", f"plus {factor}"
        return f"({left})/({factor}){sep}{right}", f"divided by {factor}"
    if op == 7:
        left, sep, right = eq.partition("=")
        how = rng.randrange(5)
        if how == 0:
            return f"{right}={left}", "sides swapped"
        if how == 1:
            return left + right, "no '='"
        if how == 2:
            return f"{eq} = 0", "a second '='"
        if how == 3:
            return f"{left}=", "right side empty"
        return f"={right}", "left side empty"
    if op == 8:
        f = rng.choice(FUNCTIONS)
        out, what = _sub(rng, eq, _NAME, lambda w: f"{f}({w})")
        if what:
            return out, f"function {what}"
        return f"{f}(pi/2)*{eq}", "function"
    if op == 9:
        out, what = _sub(rng, eq, _NAME, lambda w: rng.choice(
            [f"{w}*{w}", f"{w}^2", f"{w}^0", f"{w}^1", f"1/{w}", f"{w}/{w}", f"2^{w}",
             f"{w}^(1/2)", f"{w}^-1"]))
        if what:
            return out, f"nonlinear {what}"
    if op == 10:
        if rng.random() < 0.5:
            return eq[:rng.randrange(len(eq) + 1)], "cut"
        i, j = sorted(rng.randrange(len(eq) + 1) for _ in range(2))
        return eq[:j] + eq[i:j] + eq[j:], "repeat a slice"
    pad = rng.choice([" ", "+0", "0"]) * rng.choice([1000, 2000, 2001])
    return eq + pad, "padded"


def mutate_doc(rng: random.Random, doc, s: Sheet, other: Sheet) -> str:
    """Change the answers document once (in place); return what was done."""
    entries = doc.get("equations") if isinstance(doc, dict) else None
    entries = entries if isinstance(entries, list) else None
    op = rng.randrange(11)
    good = [e for e in entries or [] if isinstance(e, dict)]
    if op <= 3 and good:  # most changes are to an equation's text
        e = rng.choice(good)
        if isinstance(e.get("eq"), str):
            body = e.get("body") if isinstance(e.get("body"), str) else ""
            e["eq"], what = mutate_eq(rng, e["eq"], s.names.get(body, ()))
            return what
    if op == 4 and good:
        e = rng.choice(good)
        e["body"] = rng.choice([*s.bodies, *other.bodies, "ground", "",
                                fuzz._misspell(rng, str(e.get("body"))), 42, None, [], "é",
                                "x" * 5000, Raw("!!str 1"), Raw("*nothing")])
        return f"body -> {e['body']!r:.30}"
    if op == 5 and good:
        e = rng.choice(good)
        e["eq"] = rng.choice([42, 1.5, True, None, [], {"a": 1}, ["m*a_x", "= 0"],
                              Raw("!!float x"), Raw("!!str 1"), Raw("|\n    m*a_x = 0"),
                              Raw(">-\n    m*a_x\n    = 0"), "", " ", Raw("~")])
        return f"eq -> {e['eq']!r:.30}"
    if op == 6 and good:
        e = rng.choice(good)
        key = rng.choice(["body", "eq"])
        if rng.random() < 0.5:
            e.pop(key, None)
            return f"del {key}"
        e[rng.choice(["equation", "Eq", "bdy", "note", fuzz._misspell(rng, key)])] = "x"
        return "extra key"
    if op == 7 and entries:
        k = rng.choice([2, 2, 2, 10, 10, 100]) if rng.random() < 0.95 else 3000
        entries.extend(copy.deepcopy(rng.choice(entries)) for _ in range(k))
        return f"duplicated x {k}"
    if op == 8 and entries is not None:
        i = rng.randrange(len(entries) + 1)
        entries.insert(i, rng.choice([["rod", "m*a_x = 0"], "m*a_x = 0", 42, None, [],
                                      {"body": "rod"}, {"eq": "a_x = 0"}]))
        return "odd entry"
    if op == 9 and isinstance(doc, dict):
        key = rng.choice(["equations", "student", "equations", "eqs", "Student", "model"])
        doc[key] = rng.choice([None, [], {}, "m*a_x = 0", 42, {"body": "rod"}, [[1, 2]],
                               "x" * 3000, Raw("!!binary aGk="), Raw("&a [*a]")])
        return f"top {key} -> {doc[key]!r:.30}"
    if op == 10 and isinstance(doc, dict) and rng.random() < 0.1:
        doc["equations"] = rng.choice([[], "", [{"body": s.bodies[0], "eq": "a_x = 0"}
                                                for _ in range(20_001)]])
        return f"equations of {len(doc['equations'])}"
    e = rng.choice(good) if good else None
    if e is not None and isinstance(e.get("eq"), str):
        e["eq"], what = mutate_eq(rng, e["eq"], ())
        return what
    return "none"


def _styled(rng: random.Random, doc):
    """Equations written double-quoted (the writer's default), single-quoted or plain."""
    style = rng.choice(["double", "double", "single", "plain"])
    if style == "double" or not isinstance(doc, dict) or not isinstance(doc.get("equations"),
                                                                         list):
        return doc
    for e in doc["equations"]:
        if isinstance(e, dict) and type(e.get("eq")) is str and "\n" not in e["eq"]:
            e["eq"] = Raw("'" + e["eq"].replace("'", "''") + "'") if style == "single" \
                else Raw(e["eq"])
    return doc


@dataclass
class Case:
    index: int
    base: str
    model: str
    did: list[str]
    content: str | bytes
    heavy: bool


def make_case(seed: int, index: int, bases: list[Base], heavy_every: int = 0) -> Case:
    rng = random.Random(f"answers:{seed}:{index}")
    base = rng.choice(bases) if rng.random() < 0.7 else rng.choice(
        [b for b in bases if b.answers is not None])
    s = sheet(base.model)
    if base.answers is not None:
        doc, did = copy.deepcopy(base.answers), [f"answers/{base.model}"]
    else:
        doc, what = generated(rng, s)
        did = [what]
    other = sheet(rng.choice(bases).model)
    did += [mutate_doc(rng, doc, s, other) for _ in range(rng.choice([0, 0, 1, 1, 1, 2, 3]))]
    text: str | bytes = fuzz.dump(_styled(rng, doc), rng)
    if rng.random() < (0.3 if len(did) == 1 else 0.1):
        text, what = fuzz.mutate_text(rng, text)
        did.append(what)
    heavy = heavy_every > 0 and index % heavy_every == 0
    return Case(index, base.answers and "answers/" + base.model or base.model, base.model,
                did, text, heavy)


# -- running one case ------------------------------------------------------------------------

def classify(command: list[str], code: int | None, stdout: str, stderr: str, escaped: str,
             answers: str) -> Outcome:
    """tools/fuzz.py's `classify`, and what an answers file adds (see the module's text)."""
    name = "verify --json" if "--json" in command else command[0]
    judged = code in (0, 1) and stderr == "" and not escaped
    # exit 1 of verify is a verdict ("some equations are wrong"), not an error message
    o = fuzz.classify(name, 0 if judged else code, stdout, stderr, escaped, answers)
    if o.kind == CLEAN and code == 2:
        # the answers' own header, for the model's that `_unlocated_problems` knows
        text = re.sub(r"^(mbody: error: \d+ problems in the) answers:", r"\1 model:", stderr)
        bad = fuzz._unlocated_problems(text, answers)
        if bad:
            return Outcome(name, CRASH, code, "answers error without file:line:column: "
                           + "\n".join(bad)[:2000])
    if o.kind != ACCEPTED or command[0] != "verify":
        return o if o.kind != ACCEPTED else Outcome(name, JUDGED, code)
    if name == "verify --json":
        def refuse(constant: str):
            raise ValueError(f"{constant} is not JSON")
        try:
            doc = json.loads(stdout, parse_constant=refuse)
        except ValueError as exc:
            return Outcome(name, CRASH, code, f"not strict JSON ({exc}): {stdout[-1500:]}")
        n, correct = doc["summary"]["equations"], doc["summary"]["correct"]
        if n != len(doc["equations"]) or (code == 0) != (n == correct):
            return Outcome(name, CRASH, code, f"summary {doc['summary']} against exit {code}")
        return Outcome(name, JUDGED, code)
    m = re.search(r"\n(\d+) of (\d+) equations? correct; \d+ of \d+ rows covered\.\n\Z", stdout)
    if m is None or (code == 0) != (m.group(1) == m.group(2)):
        return Outcome(name, CRASH, code, f"no summary agreeing with exit {code}: "
                       + stdout[-1500:])
    return Outcome(name, JUDGED, code)


def run_case(case: Case, workdir: Path, hang: float) -> list[Outcome]:
    folder = Path(tempfile.mkdtemp(prefix=f"answers{case.index}.", dir=workdir))
    try:
        path = folder / "a.yaml"
        if isinstance(case.content, bytes):
            path.write_bytes(case.content)
        else:
            path.write_text(case.content, encoding="utf-8", newline="")
        model, p = str(MODELS / case.model), str(path)
        outcomes = []
        command = ["verify", model, p]
        code, out, err, esc = fuzz.run_command(command, hang)
        outcomes.append(classify(command, code, out, err, esc, p))
        # --json prints the verdicts another way; a refused file is refused the same way
        # (its message on stderr), so that is only checked now and then
        if outcomes[0].kind == JUDGED or case.index % 10 == 0:
            command = ["verify", model, p, "--json"]
            code, out, err, esc = fuzz.run_command(command, hang)
            outcomes.append(classify(command, code, out, err, esc, p))
        if case.heavy and outcomes[0].kind == JUDGED:
            command = ["report", model, "--answers", p, "-o", str(folder / "r.html")]
            code, out, err, esc = fuzz.run_command(command, hang)
            outcomes.append(classify(command, code, out, err, esc, p))
        return outcomes
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# -- the run: tools/fuzz.py's worker processes, watched for hangs --------------------------

def _worker(seed, indices, heavy_every, hang, results, workdir):
    bases = _bases()
    for i in indices:
        results.put(("start", i, os.getpid()))
        case = make_case(seed, i, bases, heavy_every)
        outcomes = run_case(case, Path(workdir), hang)
        failed = fuzz.verdict(outcomes) in (CRASH, HANG)
        results.put(("done", i, (case.base, case.did, case.content if failed else "",
                                 outcomes)))


def run(n: int, seed: int = 0, jobs: int = 1, heavy_every: int = 100, hang: float = 60.0,
        first: int = 0, log=print) -> dict:
    """Run cases first .. first + n - 1; return the counts and the failures."""
    return fuzz.run(n, seed, jobs, heavy_every, hang, first, log, worker=_worker)


def report(result: dict, show: int = 5) -> str:
    v, c = result["verdicts"], result["commands"]
    lines = [f"mbody fuzz_answers: {result['n']} answers files (seed {result['seed']}), "
             f"{sum(c.values())} commands, {result['seconds']:.0f} s",
             *fuzz.count_lines(v, [("judged", JUDGED, "every equation got a verdict: exit 0 "
                                    "or 1"),
                                   ("clean errors", CLEAN, "the answers refused, every problem "
                                    "located"),
                                   ("crashes", CRASH, ""), ("hangs", HANG, "")]),
             *fuzz.per_command_lines(c, ("verify", "verify --json", "report", "?"),
                                     (JUDGED, CLEAN, CRASH, HANG),
                                     "     judged  clean error  crash  hang", width=14)]
    for i, base, did, content, outcomes in result["failures"][:show]:
        lines.append(f"\n#{i} {base}: {'; '.join(did)}")
        lines += fuzz.failure_lines(outcomes, {"answers": content})
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = fuzz.fuzz_arguments(__doc__, "cases")
    ap.add_argument("--heavy-every", type=int, default=100, metavar="K",
                    help="report --answers on every K-th case that verify judged "
                    "(default 100; 0: never)")
    a = ap.parse_args(argv)
    if a.only is not None:
        case = make_case(a.seed, a.only, _bases(), a.heavy_every)
        print(f"#{a.only} {case.base}: {'; '.join(case.did)}\n{case.content!s:.3000}")
        workdir = Path(tempfile.mkdtemp(prefix="mbody-fuzz-answers."))
        for o in run_case(case, workdir, a.hang):
            print(f"{o.command}: {o.kind} (exit {o.code}) {o.detail}")
        shutil.rmtree(workdir, ignore_errors=True)
        return 0
    result = run(a.n, a.seed, max(1, a.jobs), a.heavy_every, a.hang,
                 log=lambda s: print(s, file=sys.stderr, flush=True))
    print(report(result, a.show))
    return 1 if result["verdicts"][CRASH] or result["verdicts"][HANG] else 0


if __name__ == "__main__":
    sys.exit(main())

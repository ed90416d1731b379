"""Structure-aware fuzzer of mbody's inputs: mutated shipped models through the command line.

    python tools/fuzz.py [-n 10000] [--seed 0] [--jobs N] [--heavy-every 5] [--hang 60]

Each mutation (number i of the run, reproducible from --seed and i alone) takes one of the
shipped models in models/, changes it one to three times in ways that know the model
format (a value replaced by an awkward number, text, tag or structure; a key deleted,
misspelt or added; a body, load or joint duplicated, dropped or grafted from another
model; a name reference pointed elsewhere; a vector lengthened; the dimension switched; a
number scaled by up to 10^±150; an expression of t put in a force), writes it out as
YAML in block or flow style, and sometimes damages the text as well (a tab in the
indentation, a line dropped, duplicated or swapped, the file cut short, a stray
character, CRLF, a BOM, a byte that is not UTF-8, a second document, anchors and
aliases). It then runs ``mbody check``, ``assemble`` and ``solve`` on it, and on every
--heavy-every'th mutation that check accepts also ``simulate`` (a short span, with step
and wall budgets, -o), ``export`` (json, npz or mat) and ``fbd`` (SVG), all through
``mbody.cli.main`` in this process with standard output and error captured and numpy's
RuntimeWarnings turned into errors (a warning printed to the user is a defect too).

Every command run is classified: accepted (exit 0), clean error (exit 1 or 2: one
paragraph, no traceback; a model error from check must name file:line:column in every
problem whose place in the file is known), crash (exit 70, a traceback, a warning, an
escaped exception, or a model error without its location) or hang (no answer within
--hang seconds: the worker is killed and restarted). A mutation counts as a crash or a
hang if any of its commands does, else as a clean error if check refused it, else as
accepted. The counts are printed at the end, with the first few crashes and hangs in full
(the mutation number reproduces one: ``--only I``).
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import math
import multiprocessing as mp
import os
import queue
import random
import re
import shutil
import signal
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"

ACCEPTED, CLEAN, CRASH, HANG = "accepted", "clean error", "crash", "hang"


# -- the inputs --------------------------------------------------------------------------------

class Raw(str):
    """YAML text written out as it is (a tag, a number in an odd form, an alias...)."""


def _bases() -> list[tuple[str, dict]]:
    return [(p.name, yaml.safe_load(p.read_text())) for p in sorted(MODELS.glob("*.yaml"))]


NUMBERS = ["0", "-0", "1", "-1", "0.5", "2", "1e3", "1e6", "1e9", "-1e9", "1e100", "1e101",
           "-1e200", "1e308", "1e309", "1e400", "-1e400", "1e-100", "1e-101", "1e-300",
           "5e-324", "2.2e-308", "1e-400", ".inf", "-.inf", ".nan", "3.14159", "1e-12",
           "1e12", "123456789012345678901234567890", "0x1F", "0o17", "0b101", "010", "08",
           "1:20", "1_000", "+.5", "1.", "-1e-3"]
TEXTS = ["", "x", "ground", "a b", "a.b", "30 deg", "-45 deg", "1e400 deg", "1e99 deg",
         "nan deg", "90 deg/s", "1e400 deg/s", "0.5 rad", "deg", "é", "world", "body",
         "revolute", "spring", "ZYX", "xyx", "XXY", "zyx", "#ff0000", "red"]
EXPRESSIONS = ["1/(t-1)", "log(t)", "log(t+1)", "sin(t)", "t^t^t", "exp(exp(t))",
               "1e300*exp(t)", "sqrt(-1)", "sqrt(1-t)", "tan(t)", "1/(t-pi)", "2t", "sin t",
               "50*sin(2*t", "abs(t)^0.5", "(" * 60 + "t" + ")" * 60, "(" * 150 + "t" +
               ")" * 150, "t" + "+t" * 600, "exp(710)", "1/0", "0/0", "-t^2", "2^-1074*t",
               "1e-320", "x + 1", "t == 1", "cos(1e300*t)", "exp(-t)*1e100"]
TAGGED = ["!!float abc", "!!bool maybe", "!!int 1.5", "!!null x", "!!str 1", "!!float 2",
          "!!int 3", "!!bool true", "!!python/object/apply:os.system ['true']",
          "!custom 3", "!!binary aGk=", "!!timestamp 2001-12-14", "!!set {a: null}", "! 1",
          "!!float 1e999", "!!int " + "7" * 5000, "!!float " + "9" * 400]
WORDS = ["on", "off", "yes", "no", "y", "n", "true", "false", "null", "~", "=", "<<", "Yes",
         "ON"]


def _big(rng: random.Random) -> str:
    n = rng.choice([101, 102, 400, 4299, 4301, 5000, 20000])
    digit = rng.choice("123456789")
    return rng.choice(["", "-", "0x", "0b", "-0x"]) + digit * n


def _structure(rng: random.Random) -> object:
    k = rng.randrange(12)
    if k == 0:
        return []
    if k == 1:
        return {}
    if k == 2:
        return [rng.uniform(-5, 5) for _ in range(rng.choice([1, 2, 3, 4, 9]))]
    if k == 3:
        return [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    if k == 4:
        return [[1, 2], [3, 4]]
    if k == 5:
        return {"a": 1}
    if k == 6:  # deep nesting, past the loader's limit sometimes
        v: object = 1
        for _ in range(rng.choice([5, 30, 63, 64, 65, 200])):
            v = [v]
        return v
    if k == 7:
        return {"box": [rng.choice([1, 0, -1, 1e-120]), 1, 1]}
    if k == 8:
        return {"quaternion": [0, 0, 0, 0]}
    if k == 9:
        return {"euler": [Raw(rng.choice(NUMBERS)), 0, 0], "sequence": rng.choice(TEXTS)}
    if k == 10:
        return {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, rng.choice([1, -1, 2])]]}
    return [Raw(rng.choice(NUMBERS)) for _ in range(3)]


def awkward(rng: random.Random) -> object:
    """A value that is out of place, out of range or oddly written."""
    k = rng.randrange(8)
    if k == 0:
        return Raw(rng.choice(NUMBERS))
    if k == 1:
        return rng.choice(TEXTS)
    if k == 2:
        return rng.choice(EXPRESSIONS)
    if k == 3:
        return Raw(rng.choice(TAGGED))
    if k == 4:
        return Raw(rng.choice(WORDS))
    if k == 5:
        return Raw(_big(rng))
    if k == 6:
        return "x" * rng.choice([100, 5000, 200_000])
    return _structure(rng)


def _paths(x, p=()):
    yield p, x
    items = x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, list) else ()
    for k, v in items:
        yield from _paths(v, (*p, k))


def _get(d, path):
    for k in path:
        d = d[k]
    return d


def _misspell(rng: random.Random, word: str) -> str:
    if not word:
        return "x"
    i = rng.randrange(len(word))
    op = rng.randrange(4)
    if op == 0:
        return word[:i] + word[i + 1:]
    if op == 1:
        return word[:i] + rng.choice("abcdefghijklmnopqrstuvwxyz_") + word[i:]
    if op == 2 and len(word) > 1:
        j = min(i + 1, len(word) - 1)
        return word[:i] + word[j] + word[i] + word[j + 1:]
    return word.upper() if word.islower() else word.lower()


KEYS = ["name", "mass", "inertia", "position", "velocity", "angular_velocity", "angle",
        "orientation", "shape", "color", "type", "body", "bodies", "force", "torque", "at",
        "frame", "stiffness", "rest_length", "damping", "parent", "child", "axis", "axis2",
        "gravity", "dimension", "reactions", "loads", "joints", "model", "description"]
JOINT_TYPES = ["revolute", "prismatic", "fixed", "cylindrical", "universal", "spherical",
               "planar", "ball"]


OP_WEIGHTS = [0.5, 1, 1, 1, 1, 1, 1, 1, 4, 1, 0.5, 2, 1.5, 1.5, 2, 1.5, 3]
"""How often each change of `mutate_tree` is chosen: those that keep a model valid but
awkward (scaled numbers, numbers at the range's edges, references, types, grafts,
expressions, known reactions) often enough that many mutants reach assemble, solve and
simulate."""
EDGES = ["1e100", "-1e100", "1e-100", "-1e-100", "1e-99", "9.99e99", "1.0000001e100",
         "0.99e-100", "1e50", "1e-50", "0", "-0.0", "1e9", "1e-9"]


def mutate_tree(rng: random.Random, data: dict, bases: list[tuple[str, dict]]) -> str:
    """Change `data` in place once; return what was done."""
    paths = [(p, v) for p, v in _paths(data) if p]
    op = rng.choices(range(17), weights=OP_WEIGHTS)[0]
    if op == 16:  # a number at the edge of the accepted range, or just past it
        numbers = [(q, w) for q, w in paths if isinstance(w, int | float)
                   and not isinstance(w, bool)]
        if numbers:
            q, _ = rng.choice(numbers)
            edge = Raw(rng.choice(EDGES))
            _get(data, q[:-1])[q[-1]] = edge
            return f"edge {q} = {edge}"
        op = 1
    if not paths or op == 0:
        key = rng.choice(KEYS + ["dimension", "dimension"])
        data[key] = awkward(rng) if rng.random() < 0.7 else rng.choice([2, 3, 4, "3"])
        return f"top {key} = {data[key]!r:.60}"
    p, v = rng.choice(paths)
    parent = _get(data, p[:-1])
    if op in (1, 2, 3):  # an awkward value anywhere
        parent[p[-1]] = awkward(rng)
        return f"{p} = {parent[p[-1]]!r:.60}"
    if op == 4 and isinstance(parent, dict):
        del parent[p[-1]]
        return f"del {p}"
    if op == 5 and isinstance(parent, dict):
        new = _misspell(rng, str(p[-1])) if rng.random() < 0.6 else rng.choice(KEYS)
        parent[new] = parent.pop(p[-1]) if rng.random() < 0.7 else awkward(rng)
        return f"key {p} -> {new}"
    if op == 6 and isinstance(parent, list):
        parent.insert(p[-1], copy.deepcopy(parent[p[-1]]))
        return f"dup {p}"
    if op == 7 and isinstance(parent, list):
        del parent[p[-1]]
        return f"drop {p}"
    if op == 8 and isinstance(v, int | float) and not isinstance(v, bool):
        k = rng.choice([rng.randint(-150, 150), rng.randint(-20, 20), 0])
        parent[p[-1]] = Raw(repr(v * 10.0 ** k)) if math.isfinite(v * 10.0 ** k) else Raw("1e400")
        if rng.random() < 0.2:
            parent[p[-1]] = -v
        return f"scale {p} by 1e{k}"
    if op == 9 and isinstance(v, list) and v and not isinstance(v[0], dict):
        if rng.random() < 0.5:
            v.append(copy.deepcopy(v[-1]))
        else:
            v.pop()
        return f"length {p}"
    if op == 10:
        data["dimension"] = 5 - data.get("dimension", 2) if isinstance(
            data.get("dimension"), int) and data.get("dimension") in (2, 3) else 3
        return "switch dimension"
    if op == 11:  # a name reference pointed elsewhere
        names = [b.get("name") for b in data.get("bodies") or [] if isinstance(b, dict)]
        refs = [(q, w) for q, w in paths if q[-1] in ("body", "parent", "child")
                or (len(q) > 1 and q[-2] == "bodies" and q[0] == "loads")]
        if refs:
            q, w = rng.choice(refs)
            choice = rng.choice([*(n for n in names if isinstance(n, str)), "ground",
                                 _misspell(rng, str(w)), 42])
            _get(data, q[:-1])[q[-1]] = choice
            return f"ref {q} -> {choice!r}"
    if op == 12:  # a type changed
        types = [(q, w) for q, w in paths if q[-1] == "type"]
        if types:
            q, _ = rng.choice(types)
            new = rng.choice(JOINT_TYPES + ["force", "torque", "spring", "gravity"])
            _get(data, q[:-1])["type"] = new
            return f"type {q} -> {new}"
    if op == 13:  # graft a body, load or joint from another model
        name, other = rng.choice(bases)
        section = rng.choice(["bodies", "loads", "joints"])
        if other.get(section):
            item = copy.deepcopy(rng.choice(other[section]))
            target = data.setdefault(section, [])
            if isinstance(target, list):
                target.insert(rng.randint(0, len(target)), item)
                return f"graft {section} from {name}"
    if op == 14:  # a force component becomes an expression of t
        forces = [(q, w) for q, w in paths if q[-1] in ("force", "torque")]
        if forces:
            q, w = rng.choice(forces)
            e = rng.choice(EXPRESSIONS)
            holder = _get(data, q[:-1])
            if isinstance(w, list) and w:
                w[rng.randrange(len(w))] = e
            else:
                holder[q[-1]] = e
            return f"expr {q} = {e!r:.40}"
    if op == 15:  # known reactions: a label and a value
        joints = [j for j in data.get("joints") or [] if isinstance(j, dict)]
        component = rng.choice(["Fx", "Fy", "Fz", "Mx", "Mz", "Mt", "Fq"])
        label = f"{rng.choice(joints).get('name')}.{component}" if joints else "A.Fx"
        reactions = data.setdefault("reactions", {})
        if isinstance(reactions, dict):
            reactions[label] = rng.choice([0, 1.5, -1e3, *EXPRESSIONS[:6], Raw("1e400")])
            return f"reaction {label}"
    parent[p[-1]] = awkward(rng)
    return f"{p} = {parent[p[-1]]!r:.60}"


# -- writing YAML, block or flow style ----------------------------------------------------------

_PLAIN_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*")


def _scalar(v) -> str:
    if isinstance(v, Raw):
        return str(v)
    if v is None:
        return "null"
    if v is True or v is False:
        return str(v).lower()
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return ".nan" if math.isnan(v) else (".inf" if v > 0 else "-.inf") \
            if math.isinf(v) else repr(v)
    return json.dumps(v, ensure_ascii=False)


def _key(k) -> str:
    if isinstance(k, Raw):
        return str(k)
    k = str(k)
    return k if _PLAIN_KEY.fullmatch(k) and k not in WORDS else json.dumps(k)


def _flow(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(_flow(e) for e in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)}: {_flow(e)}" for k, e in v.items()) + "}"
    return _scalar(v)


def _block(v, indent: str, rng: random.Random, out: list[str]) -> None:
    if isinstance(v, dict):
        for k, e in v.items():
            if isinstance(e, dict | list) and e and rng.random() < 0.6:
                out.append(f"{indent}{_key(k)}:")
                _block(e, indent + "  ", rng, out)
            else:
                out.append(f"{indent}{_key(k)}: {_flow(e)}")
    else:
        for e in v:
            if isinstance(e, dict) and e and rng.random() < 0.6:
                start = len(out)
                _block(e, indent + "  ", rng, out)
                out[start] = indent + "- " + out[start][len(indent) + 2:]
            else:
                out.append(f"{indent}- {_flow(e)}")


def dump(data, rng: random.Random) -> str:
    if not isinstance(data, dict | list) or not data:
        return _flow(data) + "\n"
    out: list[str] = []
    _block(data, "", rng, out)
    return "\n".join(out) + "\n"


def mutate_text(rng: random.Random, text: str) -> tuple[str | bytes, str]:
    """Damage the text itself once; return it (bytes when it is no longer UTF-8)."""
    lines = text.split("\n")
    i = rng.randrange(len(lines))
    op = rng.randrange(12)
    if op == 0:
        lines[i] = "\t" + lines[i].lstrip(" ") if rng.random() < 0.5 else \
            lines[i].replace("  ", "\t", 1)
        return "\n".join(lines), "tab"
    if op == 1:
        del lines[i]
        return "\n".join(lines), "drop line"
    if op == 2:
        lines.insert(i, lines[i])
        return "\n".join(lines), "dup line"
    if op == 3 and i + 1 < len(lines):
        lines[i], lines[i + 1] = lines[i + 1], lines[i]
        return "\n".join(lines), "swap lines"
    if op == 4:
        return text[:rng.randrange(len(text) + 1)], "cut"
    if op == 5:
        k = rng.randrange(len(text) + 1)
        return text[:k] + rng.choice("[]{}:,-'\"#&*!|>%@` \t\x00\x85\u2028") + text[k:], "char"
    if op == 6:
        return text.replace("\n", "\r\n"), "crlf"
    if op == 7:
        return "\ufeff" + text, "bom"
    if op == 8:
        k = rng.randrange(len(text) + 1)
        raw = text.encode()
        return raw[:k] + bytes([rng.choice([0x80, 0xff, 0xc3, 0xfe])]) + raw[k:], "bad byte"
    if op == 9:
        return text + "---\n" + text, "second document"
    if op == 10:  # an anchor on one value and an alias to it somewhere else
        spots = [j for j, line in enumerate(lines) if re.search(r": \S", line)]
        if len(spots) >= 2:
            a, b = sorted(rng.sample(spots, 2))
            lines[a] = re.sub(r": ", ": &x ", lines[a], count=1)
            lines[b] = re.sub(r": .*", ": *x", lines[b], count=1)
            return "\n".join(lines), "alias"
    if op == 11:  # an alias bomb
        bomb = "a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n" + "".join(
            f"a{k}: &a{k} [*a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}]\n"
            for k in range(1, rng.choice([3, 6, 9])))
        return bomb + text, "alias bomb"
    return text, "none"


@dataclass
class Case:
    index: int
    base: str
    did: list[str]
    content: str | bytes
    heavy: bool
    rng_state: object = field(default=None, repr=False)


def make_case(seed: int, index: int, bases: list[tuple[str, dict]], heavy_every: int) -> Case:
    rng = random.Random(f"{seed}:{index}")
    name, base = rng.choice(bases)
    data = copy.deepcopy(base)
    did = [mutate_tree(rng, data, bases) for _ in range(rng.choice([0, 1, 1, 1, 2, 3]))]
    text: str | bytes = dump(data, rng)
    if not did or rng.random() < 0.2:
        text, what = mutate_text(rng, text)
        did.append(what)
    heavy = heavy_every > 0 and index % heavy_every == 0
    return Case(index, name, did, text, heavy, rng.getstate())


# -- running one case ------------------------------------------------------------------------

class Hang(BaseException):
    """Raised by the alarm: a command took longer than the hang limit (not an Exception, so
    that mbody's own handlers do not turn it into an internal error)."""


@dataclass
class Outcome:
    command: str
    kind: str
    code: int | None
    detail: str = ""


_LOCATED = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): ")
_UNLOCATED = ("no such file", "this is a directory", "this is a character device",
              "the file is larger", "cannot read the file", "nothing came through",
              "this is a block device", "this is a socket")


def _unlocated_problems(stderr: str, path: str) -> list[str]:
    """Lines of a model error from `check` that do not name file:line:column."""
    text = stderr.removeprefix("mbody: error: ").rstrip("\n")
    lines = text.split("\n")
    if lines[0].endswith("problems in the model:"):
        lines = lines[1:]
    bad = []
    for line in lines:
        if line.startswith("... and "):
            continue
        m = _LOCATED.match(line)
        if m and m.group("file") == path and int(m.group("line")) > 0:
            continue
        if line.startswith(f"{path}: ") and any(u in line for u in _UNLOCATED):
            continue
        bad.append(line)
    return bad


def run_command(argv: list[str], hang: float) -> tuple[int | None, str, str, str]:
    """mbody.cli.main(argv) with captured output: (exit code, stdout, stderr, escaped)."""
    from mbody.cli import main

    out, err = io.StringIO(), io.StringIO()
    escaped = ""
    previous = signal.signal(signal.SIGALRM, _alarm) if hang else None
    if hang:
        signal.setitimer(signal.ITIMER_REAL, hang)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            code: int | None = main(argv)
    except Hang:
        code = None
    except SystemExit as exc:  # argparse
        code = exc.code if isinstance(exc.code, int) else 2
    except BaseException as exc:  # noqa: BLE001 - anything escaping main is a crash
        code, escaped = 70, "".join(traceback.format_exception(exc))
    finally:
        if hang:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)
    return code, out.getvalue(), err.getvalue(), escaped


def _alarm(signum, frame):
    raise Hang


def classify(command: str, code: int | None, stdout: str, stderr: str, escaped: str,
             path: str) -> Outcome:
    if code is None:
        return Outcome(command, HANG, None, "no answer")
    if escaped or "Traceback" in stderr or "Traceback" in stdout or code not in (0, 1, 2):
        return Outcome(command, CRASH, code, (escaped or stderr)[-3000:])
    if "Warning" in stderr:
        return Outcome(command, CRASH, code, "a warning reached the user: " + stderr[-2000:])
    if code == 0:
        return Outcome(command, ACCEPTED, 0)
    # Warnings and notices ("mbody: warning: ...") may come first; then one message.
    starts = [m.start() for m in re.finditer(r"^mbody: (error|cannot solve): ", stderr,
                                              re.MULTILINE)]
    before = stderr[:starts[0]].splitlines() if starts else []
    if len(starts) != 1 or not all(line.startswith("mbody: ") for line in before):
        return Outcome(command, CRASH, code, "not one clean message: " + stderr[-2000:])
    stderr = stderr[starts[0]:]
    if command == "check":
        bad = _unlocated_problems(stderr, path)
        if bad:
            return Outcome(command, CRASH, code, "model error without file:line:column: "
                           + "\n".join(bad)[:2000])
    return Outcome(command, CLEAN, code, stderr[:300])


def run_case(case: Case, workdir: Path, hang: float) -> list[Outcome]:
    folder = Path(tempfile.mkdtemp(prefix=f"case{case.index}.", dir=workdir))
    try:
        path = folder / "m.yaml"
        if isinstance(case.content, bytes):
            path.write_bytes(case.content)
        else:
            path.write_text(case.content, encoding="utf-8", newline="")
        p = str(path)
        outcomes = []
        rng = random.Random(f"run:{case.index}")
        for command in (["check", p], ["assemble", p], ["solve", p]):
            code, out, err, esc = run_command(command, hang)
            outcomes.append(classify(command[0], code, out, err, esc, p))
            if command[0] == "check" and code != 0:
                return outcomes  # refused: the other commands would refuse it the same way
        if case.heavy:
            t_end = rng.choice(["0.01", "0.05", "0.2", "0.5"])
            method = rng.choice(["DOP853"] * 6 + ["RK45", "LSODA", "BDF", "Radau"])
            heavy = [["simulate", p, "--t-end", t_end, "--fps", "20", "--no-progress",
                      "--max-steps", "3000", "--max-wall", "10", "--method", method,
                      "-o", str(folder / "run.npz")],
                     ["export", p, "-o", str(folder / rng.choice(["e.json", "e.npz",
                                                                  "e.mat"]))],
                     ["jacobian", p]]
            if rng.random() < 0.5:
                heavy.append(["fbd", p, "-o", str(folder / "fbd"), "--image-format", "svg"])
            for command in heavy:
                code, out, err, esc = run_command(command, hang)
                outcomes.append(classify(command[0], code, out, err, esc, p))
        return outcomes
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def verdict(outcomes: list[Outcome]) -> str:
    kinds = {o.kind for o in outcomes}
    for kind in (CRASH, HANG):
        if kind in kinds:
            return kind
    return ACCEPTED if outcomes[0].kind == ACCEPTED else CLEAN


# -- the run: worker processes watched for hangs ---------------------------------------------

def warm_up() -> None:
    """Solve and simulate a few models once, before anything is timed: the first of a
    process imports what they need (scipy, the core's workspace), which is no hang."""
    import mbody

    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        for name in ("slider_crank", "torque_free_asymmetric", "planar_time_varying_force",
                     "fourbar_spatial"):
            with contextlib.suppress(Exception):
                model = mbody.load(MODELS / f"{name}.yaml")
                mbody.assemble(model).solve()
                mbody.simulate(model, t_end=0.01, fps=100)


def _worker(seed, indices, heavy_every, hang, results, workdir):
    warm_up()
    bases = _bases()
    for i in indices:
        results.put(("start", i, os.getpid()))
        case = make_case(seed, i, bases, heavy_every)
        outcomes = run_case(case, Path(workdir), hang)
        results.put(("done", i, (case.base, case.did, case.content if verdict(outcomes) in
                                 (CRASH, HANG) else "", outcomes)))


def run(n: int, seed: int = 0, jobs: int = 1, heavy_every: int = 5, hang: float = 60.0,
        first: int = 0, log=print, worker=None) -> dict:
    """Run mutations first .. first + n - 1; return the counts and the failures.

    `worker` runs a list of mutation numbers in a child process (default `_worker`, this
    fuzzer's); another fuzzer (tools/fuzz_answers.py) passes its own, with the same
    arguments and messages, to be watched for hangs the same way."""
    workdir = tempfile.mkdtemp(prefix="mbody-fuzz.")
    todo = list(range(first, first + n))
    verdicts: Counter = Counter()
    commands: Counter = Counter()
    failures: list[tuple[int, str, list[str], str | bytes, list[Outcome]]] = []
    ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    results = ctx.Queue()
    chunks = [todo[k::jobs] for k in range(jobs)]
    workers: dict[int, tuple] = {}

    def start(indices):
        if not indices:
            return
        proc = ctx.Process(target=worker or _worker, args=(seed, indices, heavy_every, hang / 2,
                                                 results, workdir), daemon=True)
        proc.start()
        workers[proc.pid] = (proc, list(indices), None, None)

    for chunk in chunks:
        start(chunk)
    done = 0
    t0 = time.perf_counter()
    try:
        while workers:
            try:
                kind, i, payload = results.get(timeout=1.0)
            except queue.Empty:
                kind = None
            if kind == "start":
                for pid, (proc, indices, _, _) in workers.items():
                    if i in indices:
                        workers[pid] = (proc, indices, i, time.perf_counter())
            elif kind == "done":
                base, did, content, outcomes = payload
                v = verdict(outcomes)
                verdicts[v] += 1
                for o in outcomes:
                    commands[(o.command, o.kind)] += 1
                if v in (CRASH, HANG):
                    failures.append((i, base, did, content, outcomes))
                done += 1
                for pid, (proc, indices, _, _) in list(workers.items()):
                    if i in indices:
                        indices.remove(i)
                        workers[pid] = (proc, indices, None, None)
                if done % 500 == 0:
                    log(f"  {done} / {n} mutations, {time.perf_counter() - t0:.0f} s: "
                        + ", ".join(f"{k} {verdicts[k]}" for k in (CLEAN, ACCEPTED, CRASH,
                                                                   HANG)))
            now = time.perf_counter()
            for pid, (proc, indices, cur, since) in list(workers.items()):
                if cur is not None and now - since > hang:  # killed, counted, restarted
                    proc.kill()
                    proc.join()
                    del workers[pid]
                    verdicts[HANG] += 1
                    commands[("?", HANG)] += 1
                    failures.append((cur, "?", ["worker killed"], "", [Outcome("?", HANG,
                                                                                None)]))
                    done += 1
                    start([k for k in indices if k != cur])
                elif not proc.is_alive() and not indices:
                    proc.join()
                    del workers[pid]
                elif not proc.is_alive() and cur is None:
                    proc.join()
                    del workers[pid]
                    start(indices)
    finally:
        for proc, *_ in workers.values():
            proc.kill()
        shutil.rmtree(workdir, ignore_errors=True)
    return {"n": n, "seed": seed, "verdicts": verdicts, "commands": commands,
            "failures": sorted(failures, key=lambda f: f[0]),
            "seconds": time.perf_counter() - t0}


def fuzz_arguments(doc: str, what: str, *, jobs: int | None = None,
                   hang: float = 60.0) -> argparse.ArgumentParser:
    """The options every fuzzer here takes: -n, --seed, --jobs, --hang, --only, --show
    (`what`: a case's name in the help, "mutations", "cases"...)."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("-n", type=int, default=10_000, help=f"{what} (default 10000)")
    ap.add_argument("--seed", type=int, default=0)
    cpus = os.cpu_count() or 1
    ap.add_argument("--jobs", type=int, default=jobs if jobs is not None else cpus,
                    help="worker processes (default: "
                    + (f"{jobs})" if jobs is not None else "one per CPU)"))
    ap.add_argument("--hang", type=float, default=hang, metavar="SECONDS",
                    help=f"a case without an answer this long is a hang (default {hang:g})")
    ap.add_argument("--only", type=int, metavar="I", help="run case I alone, and show it")
    ap.add_argument("--show", type=int, default=5, help="failures shown in full")
    return ap


def count_lines(counts: Mapping[str, int], rows: Sequence[tuple[str, str, str]]) -> list[str]:
    """The report's totals: one line per (label, kind, why)."""
    return [f"  {label:<13}{counts[kind]:7d}" + (f"   ({why})" if why else "")
            for label, kind, why in rows]


def per_command_lines(per: Mapping[tuple[str, str], int], commands: Sequence[str],
                      kinds: Sequence[str], head: str, width: int = 10) -> list[str]:
    """The report's table of outcomes per command (a command with none left out)."""
    lines = [f"  per command: {head}"]
    for command in commands:
        row = [per[(command, k)] for k in kinds]
        if any(row):
            lines.append(f"    {command:<{width}} {row[0]:9d} {row[1]:12d} {row[2]:6d} "
                         f"{row[3]:5d}")
    return lines


def failure_lines(outcomes: Sequence[Outcome], shown: Mapping[str, object],
                  kinds: Sequence[str] = (CRASH, HANG)) -> list[str]:
    """A failed case in full: its outcomes of `kinds`, then each file (name -> content,
    1500 characters at most, indented)."""
    lines = [f"  {o.command}: {o.kind} (exit {o.code})\n{o.detail}"
             for o in outcomes if o.kind in kinds]
    for name, content in shown.items():
        text = content if isinstance(content, str) else repr(content)
        lines.append(f"  {name}:\n    " + text[:1500].replace("\n", "\n    "))
    return lines


def report(result: dict, show: int = 5) -> str:
    v, c = result["verdicts"], result["commands"]
    lines = [f"mbody fuzz: {result['n']} mutations of the shipped models (seed "
             f"{result['seed']}), {sum(c.values())} commands, {result['seconds']:.0f} s",
             *count_lines(v, [("clean errors", CLEAN, "check refused the file, naming what "
                               "and where"),
                              ("accepted", ACCEPTED, "check passed; the commands run on it "
                               "below"),
                              ("crashes", CRASH, ""), ("hangs", HANG, "")]),
             *per_command_lines(c, ("check", "assemble", "solve", "simulate", "export",
                                    "jacobian", "fbd"), (ACCEPTED, CLEAN, CRASH, HANG),
                                "  accepted  clean error  crash  hang")]
    for i, base, did, content, outcomes in result["failures"][:show]:
        lines.append(f"\n#{i} {base}: {'; '.join(did)}")
        lines += failure_lines(outcomes, {"model": content})
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = fuzz_arguments(__doc__, "mutations")
    ap.add_argument("--heavy-every", type=int, default=5, metavar="K",
                    help="simulate, export, jacobian (and sometimes fbd) every K-th mutation "
                    "that check accepts (default 5; 0: never)")
    a = ap.parse_args(argv)
    if a.only is not None:
        case = make_case(a.seed, a.only, _bases(), a.heavy_every)
        print(f"#{a.only} {case.base}: {'; '.join(case.did)}\n{case.content!s:.3000}")
        workdir = Path(tempfile.mkdtemp(prefix="mbody-fuzz."))
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

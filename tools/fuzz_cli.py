"""Fuzzer of mbody's command-line options: every command, every option, awkward values.

    python tools/fuzz_cli.py [-n 10000] [--seed 0] [--jobs N] [--hang 60] [--only I]

Each case (number i of the run, reproducible from --seed and i alone) picks a command and
builds its arguments from what the parser itself declares (`mbody.cli.build_parser`, so
a new command or option is fuzzed without changing this file): its positionals, and a
random handful of its options, each given a value drawn for its kind:

- numbers (an option whose argparse type converts one): 0, -0, negative, tiny (5e-324),
  huge (1e308, 1e400), inf, nan, a long integer, hex, "1_000", "1,5", words, "";
- paths (outputs, run files, answers, models): the shipped models copied into the case's
  folder, a run file, an answers file, a folder, a named pipe nobody writes or reads, a
  link to the model, a dangling link, a missing file, an empty or binary file, a Unicode
  name, a name too long for the file system, /dev/null, /dev/zero, /dev/full, the input
  itself (with and without --force), a file under a file, a new nested folder;
- choices: the valid ones most of the time, else a wrong or misspelt word (a picture
  format where a model's is expected...);
- NAME=VALUE options (--known, --q, --qd): labels right and wrong, values finite, huge,
  nan, with and without ``deg``;
- names (--body, --keyframe, --view, --method): valid, misspelt, Unicode, empty, long.

and sometimes repeats an option, adds an unknown one, drops a positional or adds one. So
that most valid runs stay short, simulate and animate get a short --t-end unless that is
the option being fuzzed. Not fuzzed: ``animate --live`` (it starts a server; tested in
tests/test_animate.py), ``simulate --progress`` (display only), and /dev/stdin, /dev/stdout
and /dev/tty as paths (they are the fuzzer's own streams; tests/test_outputs.py covers
/dev/stdout).

Each command runs through `mbody.cli.main` in this process, in a fresh folder holding
fresh copies of the fixtures (the current folder, for default outputs), with standard
output and error captured and numpy's RuntimeWarnings turned into errors, and is
classified as tools/fuzz.py classifies a command (`fuzz.classify`): accepted (exit 0),
clean error (exit 1 or 2 with one paragraph; argparse's usage lines before it are
allowed), crash (exit 70, a traceback, a warning reaching the user, an escaped
exception) or hang (no answer within --hang seconds). The counts are printed per
command, with the first crashes and hangs in full (``--only I`` reruns one).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
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
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"


def _fuzz_module():
    """tools/fuzz.py (the model fuzzer), for its outcome classification."""
    name = "mbody_fuzz"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / "fuzz.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


fuzz = _fuzz_module()
ACCEPTED, CLEAN, CRASH, HANG = fuzz.ACCEPTED, fuzz.CLEAN, fuzz.CRASH, fuzz.HANG
Outcome = fuzz.Outcome

COMMANDS = ("check", "assemble", "solve", "export", "simulate", "plot", "fbd", "graph",
            "report", "animate", "jacobian", "verify", "convert", "kinematics",
            "equilibrium", "lagrange", "modes", "sweep")
"""The commands (a test keeps this equal to the parser's), for the report's rows."""
NOT_FUZZED = {"--live", "--progress", "--help", "-h", "--scheduler"}
"""Options never chosen (see the module's text)."""

# -- the fixtures of a case's folder ------------------------------------------------------------

FIXTURES = {"m.yaml": "pendulum.yaml", "sc.yaml": "slider_crank.yaml",
            "top.yaml": "heavy_top.yaml", "seed.yaml": "seed_example_1.yaml",
            "arm.xml": "robots/two_link_arm.xml", "arm.urdf": "robots/two_link_arm.urdf",
            "ans.yaml": "answers/pendulum.yaml", "名.yaml": "pendulum.yaml",
            "d.yaml": "slider_crank_driven.yaml"}
"""Case-folder name -> shipped file copied there."""

MODEL_PATHS = ["m.yaml", "m.yaml", "sc.yaml", "top.yaml", "seed.yaml", "arm.xml", "arm.urdf",
               "名.yaml", "link.yaml", "d.yaml", "d.yaml"]
RUN_PATHS = ["run.npz", "run.npz", "sc.npz"]
ODD_PATHS = ["dir", "fifo", "dangling.yaml", "missing.yaml", "empty.yaml", "bin.yaml",
             "/dev/null", "/dev/zero", "/dev/full", "sub/../m.yaml", "", " ", "m.yaml/x",
             "dir/", "x" * 300 + ".yaml", "ans.yaml", "run.npz", "m.yaml", "-"]
OUTPUTS = ["out.npz", "out.json", "out.mat", "out.svg", "out.png", "out.pdf", "out.html",
           "out.tex", "out.xml", "out.yaml", "out.gif", "out", "new/deep/out.json",
           "new/deep/out.svg", "pics", "名.svg", "x" * 300 + ".svg", "y" * 250 + ".json",
           "OUT.SVG", ".svg", "out.csv", "out.parquet"]
NUMBERS = ["0", "-0", "1", "-1", "0.5", "2", "3", "5", "10", "60", "72", "150", "600",
           "601", "1e-300", "5e-324", "1e-13", "1e-14", "0.49", "0.5", "0.51", "1e6",
           "1e9", "1e15", "1e308", "1e309", "1e400", "-1e400", "inf", "-inf", "nan", "NaN",
           "Infinity", "123456789012345678901234567890", "0x10", "1_000", "1,5", "1e",
           "", " ", "abc", "1.5", "1000000000", "1000000001", "2147483648", "-5"]
LIGHT = {"t_end": ["0.05", "0.2", "0.5", "1"], "fps": ["5", "20", "60"],
         "dpi": ["10", "30", "72", "150"], "max_steps": ["0", "1", "10", "1000", "100000"],
         "max_wall": ["1e-9", "0.5", "5"], "rtol": ["1e-13", "1e-6", "1e-3", "0.01"],
         "atol": ["1e-300", "1e-12", "1e-3", "0.01"], "hold": ["0.1"]}
"""Valid values of the options that set the work, small enough to finish quickly."""
EDGES = {"t_end": ["1e9", "1e-9", "9e-10", "1e-300", "5e-324"], "fps": ["1e-300", "1000", "1001"],
         "dpi": ["9", "11", "600", "601", "100000", "150.0"],
         "max_steps": ["1000000000", "1000000001", "-1", "1e3"],
         "max_wall": ["1e7", "1.1e7"], "rtol": ["1e-14", "0.011", "0.5", "1", "2"],
         "atol": ["1e-301", "0.011", "1e6", "-1e-12"], "hold": ["1e7", "1.1e7"]}
"""Values at and just past the bounds of those options; with the refused NUMBERS, what
they are fuzzed with besides LIGHT (a valid but long run, say --t-end 600, would only
spend the run's time)."""
REFUSED = ["0", "-0", "-1", "1e308", "1e309", "1e400", "-1e400", "inf", "-inf", "nan", "NaN",
           "Infinity", "123456789012345678901234567890", "0x10", "1,5", "1e", "", " ",
           "abc", "-5", "1_000_000_000_0"]
LABELS = ["O.Fx", "O.Fy", "O.Mz", "A.Fx", "A.Fy", "B.Fx", "P.Fy", "P.Mz", "o.fx", "",
          "杆.Fx", "shoulder", "elbow", "joint1", "joint2", "x", " O.Fx", "O.Fx "]
VALUES = ["0", "3", "-2.5", "1e308", "1e-308", "nan", "inf", "abc", "", "30deg", "-45deg",
          "1e400deg", "deg", "90 deg", "10deg/s", "1e300", "0x3"]
NAMES = ["rod", "crank", "piston", "top", "plate", "link1", "link2", "rood", "", "杆", "😀",
         "a\u200bb", "x" * 2000, "ground", "-", "--body"]
TEXT = {"view": ["iso", "front", "top", "side", "30,-60", "90,0", "-90,180", "nan,0",
                 "1e308,1e308", "inf,0", "0,0,0", "sideways", "", "30;-60", "ISO"],
        "method": ["DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA", "rk45", "Euler", ""],
        "keyframe": ["initial", "home", "", "杆", "x" * 500],
        "max_bytes": ["1", "10", "100", "1k", "64k", "200M", "1G", "0", "-1", "1e3", "1.5G",
                      "99999999999999999999G", "abc", "", "2 M", "5MiB"],
        "point": ["P=crank:0.05,0", "P=rod:0,0", "Q=piston:0,0", "P=rood:0,0", "P=crank:1",
                  "=crank:0,0", "P=crank:nan,0", "P", "P=crank:1e400,0", "P=ground:0,0"],
        "set_values": ["bodies.rod.mass=2", "bodies.rod.mas=2", "gravity.1=-1.6",
                       "bodies.rod.mass=-1", "bodies.rod.mass=1:20", "x=1",
                       "bodies.rod.mass", "drivers.motor.speed=100 rpm",
                       "bodies.rod.position.5=1", "bodies.rod.mass=1e400"],
        "grid": ["bodies.rod.mass=1:2:3", "bodies.rod.mass=1:2:0", "bodies.rod.mass=1,2",
                 "bodies.rod.mas=1:2:2", "gravity.1=-9.81:-1.6:2", "bodies.rod.mass=1:2:1e9",
                 "drivers.motor.speed=100:600:2", "bodies.crank.mass=0.2:0.6:2", "x"],
        "coordinates": ["O", "O.turn", "rod.theta", "x", "", "O,O"],
        "against": ["time", "motor", "O", "bogus", ""]}
CHOICE_WRONG = ["png", "svg", "pdf", "gif", "yml", "xml", "YAML", "", "mjcf ", "json"]
WEIGHTS = {"animate": 0.6, "plot": 0.5, "fbd": 0.8, "report": 0.8, "sweep": 0.5,
           "lagrange": 0.6}
"""How often a command is chosen (1 by default): those whose accepted runs take a tenth
of a second or more, less often."""
UNKNOWN = ["--bogus", "--forse", "-x", "--format=", "--t_end", "--", "-", "--json=1",
           "--known", "-o"]


def make_fixtures(folder: Path, run_files: dict[str, bytes]) -> None:
    """Every fixture in `folder`, new (cases may replace them with --force)."""
    for name, shipped in FIXTURES.items():
        shutil.copyfile(MODELS / shipped, folder / name)
    for name, data in run_files.items():
        (folder / name).write_bytes(data)
    (folder / "dir").mkdir()
    (folder / "empty.yaml").write_bytes(b"")
    (folder / "bin.yaml").write_bytes(bytes(range(256)) * 4)
    os.symlink("m.yaml", folder / "link.yaml")
    os.symlink("nowhere.yaml", folder / "dangling.yaml")
    os.mkfifo(folder / "fifo")


def make_runs() -> dict[str, bytes]:
    """The bytes of two short run files (a pendulum, a slider-crank), made once."""
    import mbody

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, model in (("run.npz", "pendulum.yaml"), ("sc.npz", "slider_crank.yaml")):
            path = Path(tmp) / name
            mbody.simulate(mbody.load(MODELS / model), t_end=0.3, fps=20).save(path)
            out[name] = path.read_bytes()
    return out


# -- the cases ----------------------------------------------------------------------------------

@dataclass
class Case:
    index: int
    argv: list[str]


def _commands() -> dict[str, argparse.ArgumentParser]:
    from mbody.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return dict(sub.choices)


def _is_number(action: argparse.Action) -> bool:
    return action.type in (int, float) or getattr(action.type, "__name__", "") in (
        "byte_size", "_tolerance") or bool(re.match(r"an? .*(number|tolerance)",
                                                    getattr(action.type, "__name__", "")))


def _path_value(rng: random.Random, dest: str) -> str:
    if dest in ("output", "latex", "csv"):
        pool = OUTPUTS if rng.random() < 0.75 else ODD_PATHS + MODEL_PATHS
    elif dest in ("trajectory", "state"):
        pool = RUN_PATHS if rng.random() < 0.7 else ODD_PATHS + MODEL_PATHS
    elif dest == "answers":
        pool = ["ans.yaml"] * 3 + ODD_PATHS if rng.random() < 0.8 else MODEL_PATHS
    elif dest == "source":
        pool = MODEL_PATHS + RUN_PATHS if rng.random() < 0.75 else ODD_PATHS
    else:  # a model
        pool = MODEL_PATHS if rng.random() < 0.75 else ODD_PATHS + RUN_PATHS
    return rng.choice(pool)


def _value(rng: random.Random, action: argparse.Action) -> str:
    dest = action.dest
    if dest in ("output", "latex", "csv", "trajectory", "state", "answers", "source",
                "model"):
        return _path_value(rng, dest)
    if dest in LIGHT:
        return rng.choice(LIGHT[dest] if rng.random() < 0.6 else REFUSED + EDGES[dest])
    if action.choices is not None:
        return rng.choice(list(action.choices)) if rng.random() < 0.75 else rng.choice(
            CHOICE_WRONG)
    if dest in ("known", "q", "qd"):
        if rng.random() < 0.1:
            return rng.choice(["=", "O.Fx", "==3", "O.Fx==3", "O.Fx=3=4"])
        return f"{rng.choice(LABELS)}={rng.choice(VALUES)}"
    if dest == "body":
        return rng.choice(NAMES)
    if dest in TEXT:
        return rng.choice(TEXT[dest])
    if _is_number(action):
        return rng.choice(NUMBERS)
    return rng.choice(NAMES + NUMBERS)


def make_case(seed: int, index: int, commands: dict[str, argparse.ArgumentParser]) -> Case:
    """Case `index` of the run with `seed`: a command and its arguments."""
    rng = random.Random(f"cli:{seed}:{index}")
    if rng.random() < 0.02:  # a misspelt or missing command
        return Case(index, rng.choice([["chek", "m.yaml"], [], ["--version"], ["fbd"],
                                       ["Simulate", "m.yaml"], ["--", "check"]]))
    names = sorted(commands)
    name = rng.choices(names, weights=[WEIGHTS.get(c, 1.0) for c in names])[0]
    parser = commands[name]
    argv = [name]
    for action in parser._get_positional_actions():
        if rng.random() < 0.97:
            argv.append(_path_value(rng, action.dest))
    options = [a for a in parser._get_optional_actions()
               if not set(a.option_strings) & NOT_FUZZED]
    chosen = rng.sample(options, k=min(len(options), rng.choice([0, 1, 1, 2, 2, 3, 4])))
    given = set()
    for action in chosen:
        given.add(action.dest)
        flag = rng.choice(action.option_strings)
        for _ in range(rng.choice([1, 1, 1, 2]) if isinstance(action, argparse._AppendAction)
                       else 1):
            if action.nargs == 0:
                argv.append(flag)
            elif action.nargs == "?" and rng.random() < 0.3:
                argv.append(flag)  # --latex alone: standard output
            elif rng.random() < 0.1:
                argv.append(f"{flag}={_value(rng, action)}")
            else:
                argv += [flag, _value(rng, action)]
    if name in ("simulate", "animate") and "t_end" not in given:
        argv += ["--t-end", rng.choice(LIGHT["t_end"])]
    if name == "simulate" and "max_wall" not in given:
        argv += ["--max-wall", "5"]
    if name == "plot" and "output" not in given and rng.random() < 0.5:
        # its required -o (a picture), often not drawn among 7 options: else mostly usage
        # errors
        argv += ["-o", rng.choice(["out.png", "out.svg", "out.pdf"])]
    if name == "sweep":  # its two required options, when not drawn: else only usage errors
        if "workers" not in given:
            argv += ["--workers", "0"]  # in this process: a local cluster per case is slow
        if "grid" not in given:
            argv += ["--set", rng.choice(TEXT["grid"][:3] + ["bodies.rod.mass=1:2:2"] * 3)]
        if "output" not in given:
            argv += ["--out", rng.choice(["out.csv", "out.csv", "out.parquet"])]
    if name == "convert" and "output" not in given:  # its required -o, as sweep's above:
        # an output named as --to or SOURCE's format says, or any other (refused with a
        # did-you-mean when its extension names another format)
        argv += ["-o", rng.choice(["out.yaml", "out.xml", "out.yml", *OUTPUTS])]
    if rng.random() < 0.04:
        argv.insert(rng.randrange(1, len(argv) + 1), rng.choice(UNKNOWN))
    if rng.random() < 0.03:
        argv.append(rng.choice(MODEL_PATHS))  # one positional too many
    return Case(index, argv)


# -- running one case -----------------------------------------------------------------------------

_USAGE = re.compile(r"\Ausage: mbody.*?(?=^mbody: )", re.S | re.M)


def classify(command: str, code: int | None, stdout: str, stderr: str, escaped: str,
             model: str) -> Outcome:
    """`fuzz.classify`, with argparse's usage lines before its one-line message allowed."""
    if code == 2 and stderr.startswith("usage: mbody"):
        if "mbody: error: " not in stderr:  # a bare `mbody`: the help itself
            return Outcome(command, CLEAN, code, stderr[-300:])
        stderr = _USAGE.sub("", stderr, count=1)
    if command == "verify" and code == 1 and not escaped and not stderr.strip("\n") and \
            stdout.strip():
        return Outcome(command, ACCEPTED, code)  # its answer: some equations are wrong
    # not as "check": fuzz.py's rule that check's messages name file:line:column is for
    # bad models, and an option's message names the option instead
    o = fuzz.classify("cli", code, stdout, stderr, escaped, model)
    return Outcome(command, o.kind, o.code, o.detail)


def _snapshot(folder: Path) -> list[tuple]:
    """What a case could change in its folder: every entry's name, kind, size and time."""
    out = []
    for e in sorted(os.scandir(folder), key=lambda e: e.name):
        st = e.stat(follow_symlinks=False)
        out.append((e.name, st.st_mode, st.st_ino, st.st_size, st.st_mtime_ns))
    return out


class Folder:
    """A case's folder in `workdir` with the fixtures, made again only after a case
    changed it (most cases write nothing: making it anew for each would double the
    run's time)."""

    def __init__(self, workdir: Path, runs: dict[str, bytes]) -> None:
        self.workdir, self.runs = workdir, runs
        self.path: Path | None = None
        self.before: list[tuple] = []

    def fresh(self) -> Path:
        if self.path is not None and _snapshot(self.path) == self.before:
            return self.path
        self.clear()
        self.path = Path(tempfile.mkdtemp(prefix="case.", dir=self.workdir))
        make_fixtures(self.path, self.runs)
        self.before = _snapshot(self.path)
        return self.path

    def clear(self) -> None:
        if self.path is not None:
            shutil.rmtree(self.path, ignore_errors=True)
            self.path = None


def run_case(case: Case, folder: Folder, hang: float) -> Outcome:
    """Run one case in the fixtures' folder (the current folder meanwhile)."""
    here = os.getcwd()
    try:
        os.chdir(folder.fresh())
        code, out, err, escaped = fuzz.run_command(list(case.argv), hang)
        command = case.argv[0] if case.argv and case.argv[0] in COMMANDS else "?"
        model = case.argv[1] if len(case.argv) > 1 else ""
        return classify(command, code, out, err, escaped, model)
    finally:
        os.chdir(here)


def warm_up(set_attr=setattr) -> dict[str, bytes]:
    """Run `fuzz.warm_up` (the first solve and simulation of a process); make named pipes
    refused after a short wait (no writer on an input, no reader on an output) rather
    than the interactive one; build the parser once per process, not once per case
    (12 ms, a third of a clean error's time: argparse keeps no state between parses).
    Returns the run files' bytes.
    `set_attr` sets those module attributes (pytest's monkeypatch.setattr undoes them)."""
    import functools

    from mbody.cli import app
    from mbody.model import loader
    from mbody.util import atomic

    fuzz.warm_up()
    set_attr(atomic, "PIPE_WAIT", 0.05)
    set_attr(loader, "FIFO_WAIT", 0.05)
    set_attr(app, "build_parser", functools.cache(app.build_parser))
    return make_runs()


# -- the run: worker processes watched for hangs ------------------------------------------------

def _worker(seed, indices, hang, results, workdir):
    null = os.open(os.devnull, os.O_RDONLY)  # no case may read the fuzzer's own input
    os.dup2(null, 0)
    folder = Folder(Path(workdir), warm_up())
    commands = _commands()
    for i in indices:
        results.put(("start", i, os.getpid()))
        case = make_case(seed, i, commands)
        outcome = run_case(case, folder, hang)
        results.put(("done", i, (case.argv, outcome)))
    folder.clear()


def run(n: int, seed: int = 0, jobs: int = 1, hang: float = 60.0, first: int = 0,
        log=print) -> dict:
    """Run cases first .. first + n - 1 in `jobs` processes; return counts and failures."""
    workdir = tempfile.mkdtemp(prefix="mbody-fuzz-cli.")
    todo = list(range(first, first + n))
    kinds: Counter = Counter()
    per: Counter = Counter()
    failures: list[tuple[int, list[str], Outcome]] = []
    ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    results = ctx.Queue()
    workers: dict[int, list] = {}

    def start(indices):
        if indices:
            proc = ctx.Process(target=_worker, args=(seed, indices, hang / 2, results,
                                                     workdir), daemon=True)
            proc.start()
            workers[proc.pid] = [proc, list(indices), None, None]

    for k in range(jobs):
        start(todo[k::jobs])
    done, t0 = 0, time.perf_counter()
    try:
        while workers:
            try:
                kind, i, payload = results.get(timeout=1.0)
            except queue.Empty:
                kind = None
            for w in workers.values():
                if kind == "start" and i in w[1]:
                    w[2], w[3] = i, time.perf_counter()
                elif kind == "done" and i in w[1]:
                    w[1].remove(i)
                    w[2] = w[3] = None
            if kind == "done":
                argv, o = payload
                kinds[o.kind] += 1
                per[(o.command, o.kind)] += 1
                if o.kind in (CRASH, HANG):
                    failures.append((i, argv, o))
                done += 1
                if done % 1000 == 0:
                    log(f"  {done} / {n} cases, {time.perf_counter() - t0:.0f} s: "
                        + ", ".join(f"{k} {kinds[k]}" for k in (CLEAN, ACCEPTED, CRASH, HANG)))
            now = time.perf_counter()
            for pid, (proc, indices, cur, since) in list(workers.items()):
                if cur is not None and now - since > hang:  # killed, counted, restarted
                    proc.kill()
                    proc.join()
                    del workers[pid]
                    kinds[HANG] += 1
                    per[("?", HANG)] += 1
                    failures.append((cur, ["?"], Outcome("?", HANG, None, "worker killed")))
                    done += 1
                    start([k for k in indices if k != cur])
                elif not proc.is_alive() and (not indices or results.empty()):
                    proc.join()  # finished; or died (its results all read): go on without it
                    del workers[pid]
                    if cur is not None:  # the case it died in
                        kinds[CRASH] += 1
                        per[("?", CRASH)] += 1
                        failures.append((cur, ["?"], Outcome("?", CRASH, None,
                                                             "the worker process died")))
                        done += 1
                    start([k for k in indices if k != cur])
    finally:
        for proc, *_ in workers.values():
            proc.kill()
        shutil.rmtree(workdir, ignore_errors=True)
    return {"n": n, "seed": seed, "kinds": kinds, "per": per,
            "failures": sorted(failures, key=lambda f: f[0]),
            "seconds": time.perf_counter() - t0}


def report(result: dict, show: int = 5) -> str:
    k, per = result["kinds"], result["per"]
    lines = [f"mbody fuzz_cli: {result['n']} command lines (seed {result['seed']}), "
             f"{result['seconds']:.0f} s",
             *fuzz.count_lines(k, [("clean errors", CLEAN, "exit 1 or 2, one message"),
                                   ("accepted", ACCEPTED, "exit 0; verify's 1: a wrong "
                                    "equation"),
                                   ("crashes", CRASH, ""), ("hangs", HANG, "")]),
             *fuzz.per_command_lines(per, (*COMMANDS, "?"), (ACCEPTED, CLEAN, CRASH, HANG),
                                     "  accepted  clean error  crash  hang")]
    for i, argv, o in result["failures"][:show]:
        lines.append(f"\n#{i}: mbody {' '.join(repr(a) if not a or ' ' in a else a for a in argv)}"
                     f"\n  {o.kind} (exit {o.code})\n{o.detail}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    a = fuzz.fuzz_arguments(__doc__, "command lines").parse_args(argv)
    if a.only is not None:
        workdir = Path(tempfile.mkdtemp(prefix="mbody-fuzz-cli."))
        folder = Folder(workdir, warm_up())
        case = make_case(a.seed, a.only, _commands())
        print(f"#{a.only}: mbody {' '.join(case.argv)}")
        o = run_case(case, folder, a.hang)
        shutil.rmtree(workdir, ignore_errors=True)
        print(f"{o.command}: {o.kind} (exit {o.code}) {o.detail}")
        return 0
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        result = run(a.n, a.seed, max(1, a.jobs), a.hang,
                     log=lambda s: print(s, file=sys.stderr, flush=True))
    finally:
        signal.signal(signal.SIGINT, previous)
    print(report(result, a.show))
    return 1 if result["kinds"][CRASH] or result["kinds"][HANG] else 0


if __name__ == "__main__":
    with contextlib.suppress(KeyboardInterrupt):
        sys.exit(main())

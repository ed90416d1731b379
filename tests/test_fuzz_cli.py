"""The command-line option fuzzer (tools/fuzz_cli.py) in the suite: a few thousand command
lines of every command with awkward option values (numbers, paths, special files, the
input itself, Unicode, empty strings, combinations), in this process, seeded. Each ends
accepted or with one clean message: no crash (exit 70, a traceback, a warning), no hang.
The long run is ``python tools/fuzz_cli.py`` (10 000 cases, several processes).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CASES = 2400
SEED = 7


@pytest.fixture(scope="module")
def fuzz_cli():
    spec = importlib.util.spec_from_file_location("mbody_fuzz_cli", ROOT / "tools" /
                                                  "fuzz_cli.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["mbody_fuzz_cli"] = module
    spec.loader.exec_module(module)
    return module


def test_command_lines_give_clean_errors_only(fuzz_cli, tmp_path, monkeypatch):
    folder = fuzz_cli.Folder(tmp_path, fuzz_cli.warm_up(monkeypatch.setattr))
    commands = fuzz_cli._commands()
    kinds: dict[str, int] = {}
    per_command: dict[str, set[str]] = {}
    for i in range(CASES):
        case = fuzz_cli.make_case(SEED, i, commands)
        o = fuzz_cli.run_case(case, folder, hang=30.0)
        kinds[o.kind] = kinds.get(o.kind, 0) + 1
        per_command.setdefault(o.command, set()).add(o.kind)
        if o.kind in (fuzz_cli.CRASH, fuzz_cli.HANG):
            pytest.fail(f"case {i}: mbody {' '.join(map(repr, case.argv))}: {o.kind} "
                        f"(exit {o.code})\n{o.detail}\n(python tools/fuzz_cli.py --seed "
                        f"{SEED} --only {i})")
    folder.clear()
    # the cases are neither all refused nor all harmless, on every command
    assert kinds[fuzz_cli.CLEAN] > CASES // 2
    assert kinds[fuzz_cli.ACCEPTED] > CASES // 20
    for command in fuzz_cli.COMMANDS:
        assert per_command[command] == {fuzz_cli.CLEAN, fuzz_cli.ACCEPTED}, command


def test_the_fuzzer_knows_every_command_and_option(fuzz_cli):
    commands = fuzz_cli._commands()
    assert set(fuzz_cli.COMMANDS) == set(commands)
    # every option is drawn (only those named in NOT_FUZZED are left out)
    seen: set[tuple[str, str]] = set()
    for i in range(3000):
        argv = fuzz_cli.make_case(1, i, commands).argv
        if argv and argv[0] in commands:
            seen |= {(argv[0], a.split("=")[0]) for a in argv[1:] if a.startswith("-")}
    for name, parser in commands.items():
        for action in parser._get_optional_actions():
            flags = set(action.option_strings) - fuzz_cli.NOT_FUZZED
            if flags:
                assert {(name, f) for f in flags} & seen, (name, action.option_strings)


def test_the_classification(fuzz_cli):
    usage = "usage: mbody fbd [-h] MODEL\n                 [--dpi N]\n"
    clean = fuzz_cli.classify("fbd", 2, "", usage + "mbody: error: argument --dpi: x\n", "",
                              "m")
    assert clean.kind == fuzz_cli.CLEAN
    assert fuzz_cli.classify("fbd", 2, "", usage, "", "m").kind == fuzz_cli.CLEAN  # help
    assert fuzz_cli.classify("verify", 1, "rod: wrong\n", "", "", "m").kind == \
        fuzz_cli.ACCEPTED
    assert fuzz_cli.classify("fbd", 70, "", "mbody: internal error: x\n", "", "m").kind == \
        fuzz_cli.CRASH
    assert fuzz_cli.classify("fbd", 2, "", "UserWarning: Glyph missing\nmbody: error: x\n",
                             "", "m").kind == fuzz_cli.CRASH
    assert fuzz_cli.classify("fbd", None, "", "", "", "m").kind == fuzz_cli.HANG
    # a model error from check without a line is no crash here: options are not models
    assert fuzz_cli.classify("check", 2, "", "mbody: error: --q x: 'a' is not a number\n", "",
                             "m.yaml").kind == fuzz_cli.CLEAN


def test_the_counts_report(fuzz_cli):
    result = fuzz_cli.run(12, seed=3, jobs=2, hang=60.0, log=lambda s: None)
    text = fuzz_cli.report(result)
    assert text.startswith("mbody fuzz_cli: 12 command lines (seed 3), ")
    for label in ("clean errors", "accepted", "crashes", "hangs"):
        assert f"  {label} " in text
    assert sum(result["kinds"].values()) == 12
    assert result["kinds"][fuzz_cli.CRASH] == result["kinds"][fuzz_cli.HANG] == 0

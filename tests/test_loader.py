"""The YAML boundary: what the loader refuses, how fast, and where it says the problem is.

Every test loads real text from a file in `tmp_path` (or a string) and asserts the
`Issue`'s file, line and column, computed from the text itself, plus the message.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml

import mbody
from mbody.errors import Issue, ModelError
from mbody.model import loader
from mbody.util.budget import byte_budget, byte_limit

MODELS = Path(__file__).resolve().parent.parent / "models"


BODY = "bodies:\n  - {name: a, mass: 1, inertia: 1}\n"


def mark_of(text: str, needle: str, nth: int = 1) -> tuple[int, int]:
    """1-based (line, column) of the `nth` occurrence of `needle` in `text`."""
    at = -1
    for _ in range(nth):
        at = text.index(needle, at + 1)
    line = text.count("\n", 0, at) + 1
    return line, at - (text.rfind("\n", 0, at) + 1) + 1


def issues(path: Path, text: str | bytes, **kw) -> list[Issue]:
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    with pytest.raises(ModelError) as err:
        mbody.load(path, **kw)
    for i in err.value.issues:
        assert i.file == str(path)
    return err.value.issues


def events_read(monkeypatch) -> list[int]:
    """A one-item list that counts the parser events the loader takes from now on (with
    whichever parser `loader._Loader` is): the loader's work, without a clock."""
    count = [0]
    parser = loader._Loader

    class Counting(parser):  # type: ignore[misc, valid-type]
        def get_event(self):
            count[0] += 1
            return super().get_event()

    monkeypatch.setattr(loader, "_Loader", Counting)
    return count


def opened(monkeypatch) -> list[str]:
    """The paths `os.open` is given from now on (it still opens them)."""
    paths: list[str] = []
    real = os.open

    def spy(path, *args, **kw):
        paths.append(os.fspath(path))
        return real(path, *args, **kw)

    monkeypatch.setattr(os, "open", spy)
    return paths


def only(path: Path, text: str | bytes, **kw) -> Issue:
    found = issues(path, text, **kw)
    assert len(found) == 1, found
    return found[0]


@pytest.fixture(params=["libyaml", "python"])
def any_parser(request, monkeypatch):
    """Run a test with PyYAML's C parser and with its pure-Python fallback."""
    if request.param == "python":
        monkeypatch.setattr(loader, "_Loader", yaml.SafeLoader)
    elif not hasattr(yaml, "CSafeLoader"):  # pragma: no cover
        pytest.skip("PyYAML without libyaml")
    return request.param


# -- duplicate keys -------------------------------------------------------------------

def test_duplicate_top_level_key_is_refused_with_both_lines(tmp_path, any_parser):
    text = "model: x\ndimension: 2\n" + BODY + "dimension: 3\n"
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == mark_of(text, "dimension", 2) == (5, 1)
    assert i.key == "dimension"
    assert "duplicate key 'dimension'" in i.message
    assert i.hint == "first given on line 2"


def test_duplicate_key_inside_a_body_is_refused(tmp_path, any_parser):
    # The stock loader would silently keep mass: 5.
    text = "dimension: 2\nbodies:\n  - name: a\n    mass: 1\n    inertia: 1\n    mass: 5\n"
    assert yaml.safe_load(text)["bodies"][0]["mass"] == 5
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == mark_of(text, "mass: 5") == (6, 5)
    assert i.key == "bodies[0].mass"
    assert i.hint == "first given on line 4"


def test_every_duplicate_key_is_reported_together(tmp_path):
    text = "dimension: 2\ndimension: 2\n" + BODY + "loads: []\nloads: []\n"
    found = issues(tmp_path / "m.yaml", text)
    assert [(i.key, i.line) for i in found] == [("dimension", 2), ("loads", 6)]


# -- tags and other YAML features -----------------------------------------------------

def test_python_object_tag_is_refused_and_never_run(tmp_path, any_parser):
    witness = tmp_path / "pwned"
    text = f"dimension: 2\nmodel: !!python/object/apply:os.system ['touch {witness}']\n" + BODY
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == mark_of(text, "!!python")
    assert i.key == "model"
    assert "python/object/apply:os.system" in i.message and "not allowed" in i.message
    assert not witness.exists()


@pytest.mark.parametrize("tagged", ["!!python/name:os.system", "!!set {x: null}",
                                    "!custom 3", "!!python/tuple [1, 2]"])
def test_other_constructing_tags_are_refused(tmp_path, tagged):
    text = f"dimension: 2\nmodel: {tagged}\n" + BODY
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == (2, 8)
    assert "not allowed" in i.message


def test_tag_shorthand_from_a_directive_is_refused_too(tmp_path, any_parser):
    text = ("%TAG !py! tag:yaml.org,2002:python/object/apply:\n---\n"
            "dimension: 2\nmodel: !py!os.system ['true']\n" + BODY)
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == mark_of(text, "!py!os")
    assert "'tag:yaml.org,2002:python/object/apply:os.system' is not allowed" in i.message


def test_core_tags_are_accepted(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("dimension: !!int 2\nmodel: !!str 12\n"
                    "bodies:\n  - {name: a, mass: !!float 3, inertia: 1}\n")
    m = mbody.load(path)
    assert (m.dimension, m.name, m.mass[0]) == (2, "12", 3.0)


def test_merge_keys_are_refused(tmp_path):
    text = ("dimension: 2\nmodel: &b m\nbodies:\n  - {<<: *b, name: a, inertia: 1}\n"
            "  - {name: b, <<: *b, inertia: 1}\n")
    found = issues(tmp_path / "m.yaml", text)
    assert [(i.line, i.column) for i in found] == [mark_of(text, "<<"), mark_of(text, "<<", 2)]
    assert all("merge keys ('<<') are not supported" in i.message for i in found)


def test_complex_and_alias_keys_are_refused(tmp_path, any_parser):
    text = "dimension: 2\n? [1, 2]\n: 3\n" + BODY
    i = only(tmp_path / "m.yaml", text)
    assert "key must be a plain name" in i.message and i.line == 2


def test_undefined_alias_is_named(tmp_path):
    text = "dimension: 2\nmodel: *nowhere\n" + BODY
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == mark_of(text, "*nowhere")
    assert "'*nowhere'" in i.message


def test_a_small_alias_is_fine(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("dimension: 3\nbodies:\n"
                    "  - {name: a, mass: 1, inertia: &J [2, 3, 4]}\n"
                    "  - {name: b, mass: 1, inertia: *J}\n")
    m = mbody.load(path)
    assert m.bodies["b"].inertia.diagonal().tolist() == [2, 3, 4]


def test_alias_bomb_is_refused_quickly(tmp_path, monkeypatch, any_parser):
    """"Billion laughs": 9 levels of 9 aliases would expand to 9**9 = 387 million strings.
    The loader reads each alias once, as one event (never the nodes it names again), and
    stops at the one that takes the expansion past the limit. (Its time against reading a
    small model: tools/bench_reading.py, "refusals".)"""
    lines = ['l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for k in range(1, 10):
        lines.append(f"l{k}: &l{k} [" + ", ".join([f"*l{k - 1}"] * 9) + "]")
    text = "\n".join(lines) + "\n"
    events = events_read(monkeypatch)
    i = only(tmp_path / "bomb.yaml", text)
    assert "alias" in i.message and str(loader.MAX_ALIAS_NODES) in i.message
    assert i.line <= 10
    assert events[0] <= len(list(yaml.parse(text)))  # no more than the text's own events
    # l_k (line k + 1) holds 9**(k + 1) strings: its 9 aliases add 9 times l_(k-1)'s; the
    # refusal is on the line of the first level that takes their sum past the limit
    level = next(k for k in range(1, 10) if sum(9 ** (j + 1) for j in range(1, k + 1))
                 > loader.MAX_ALIAS_NODES)
    assert i.line == level + 1


def test_an_alias_is_the_anchored_value_itself_not_a_copy():
    """Why an alias costs one event: the same list, whatever its size (a bomb within the
    limit reads in the time of its text)."""
    lines = ["l0: &l0 [1, 2, 3, 4, 5, 6, 7, 8, 9]"]
    lines += [f"l{k}: &l{k} [" + ", ".join([f"*l{k - 1}"] * 9) + "]" for k in range(1, 5)]
    data = loader.load_text("\n".join(lines) + "\n").data
    assert all(x is data["l3"] for x in data["l4"])
    assert data["l4"][8][8][8][8] == [1, 2, 3, 4, 5, 6, 7, 8, 9]


# -- size, depth, encoding, files -----------------------------------------------------

def test_file_over_max_bytes_is_refused_before_reading(tmp_path, monkeypatch):
    path = tmp_path / "huge.yaml"
    with open(path, "wb") as f:  # a sparse 200 MiB file: instant to make, slow to parse
        f.truncate(200 * 2**20)
    paths = opened(monkeypatch)
    with pytest.raises(ModelError) as err:
        mbody.load(path)
    assert str(path) not in paths  # refused from its size: never opened (timed against
    # reading a small model: tools/bench_reading.py, "refusals")
    (i,) = err.value.issues
    assert i.file == str(path)
    assert "the file is 200 MiB; mbody reads at most 32 MiB" in i.message


def test_max_bytes_argument(tmp_path):
    path = tmp_path / "m.yaml"
    text = "dimension: 2\n" + BODY + "# padding\n" * 200_000  # about 2 MB of comments
    path.write_text(text)
    with pytest.raises(ModelError) as err:
        mbody.load(path, max_bytes=2**20)
    assert "at most 1 MiB" in str(err.value)
    assert mbody.load(path, max_bytes=4 * 2**20).n == 1


def test_max_bytes_on_the_command_line(tmp_path, capsys):
    from mbody.cli import main

    path = tmp_path / "m.yaml"
    path.write_text("dimension: 2\n" + BODY + "# padding\n" * 1000)  # about 10 kB
    assert main(["check", str(path), "--max-bytes", "4k"]) == 2
    err = capsys.readouterr().err
    assert "mbody reads at most 4 KiB" in err and "--max-bytes N" in err
    assert main(["check", str(path), "--max-bytes", "1M"]) == 0
    assert main(["check", str(path), "--max-bytes", "20000"]) == 0
    assert byte_limit(None, loader.MAX_BYTES) == loader.MAX_BYTES  # set around the command only


@pytest.mark.parametrize("text, size", [("100", 100), ("4k", 4096), ("200M", 200 * 2**20),
                                        ("1.5G", 3 * 2**29), ("2MiB", 2**21)])
def test_max_bytes_sizes(text, size):
    from mbody.cli.common import byte_size

    assert byte_size(text) == size


@pytest.mark.parametrize("text", ["", "x", "-1", "0", "1T", "1e9"])
def test_max_bytes_bad_sizes(text, capsys):
    from mbody.cli import main

    with pytest.raises(SystemExit) as exit_:  # argparse's own exit, one paragraph
        main(["check", "m.yaml", "--max-bytes", text])
    assert exit_.value.code == 2
    assert "--max-bytes: expected a size" in capsys.readouterr().err


def test_every_command_that_reads_a_model_takes_max_bytes():
    from mbody.cli.app import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    readers = [name for name, p in sub.choices.items()
               if any(a.dest in ("model", "source") for a in p._get_positional_actions())]
    assert {"check", "assemble", "solve", "simulate", "export", "animate"} <= set(readers)
    for name in readers:
        assert "--max-bytes" in sub.choices[name].format_help(), name


def test_max_bytes_limit_is_scoped(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("dimension: 2\n" + BODY + "# padding\n" * 1000)
    with byte_budget(1000), pytest.raises(ModelError, match="at most"):
        mbody.load(path)
    assert mbody.load(path).n == 1
    with byte_budget(1000):
        assert mbody.load(path, max_bytes=10**6).n == 1  # the call's own limit wins


DEEP_NESTS = [("[" * 100_000 + "]" * 100_000, "["),
              ("\n  " + "- " * 100_000 + "x", "- "),
              ("{a: " * 5000 + "1" + "}" * 5000, "{")]


@pytest.mark.parametrize("nest, opener", DEEP_NESTS)
def test_deep_nesting_is_refused_without_crashing(tmp_path, monkeypatch, nest, opener,
                                                   any_parser):
    """PyYAML's own composer recurses once per level and overflows the C stack (a
    segmentation fault) on the first of these; the loader must answer in one line, at the
    place where the nesting passed the limit.

    Which layer refuses first is not mbody's contract: the loader stops at `MAX_DEPTH`
    levels as the events arrive, but libyaml 0.2.6 (PyYAML 6.0.4's wheels) scans a flow
    collection's tokens ahead and stops at its own 1000 levels before the loader has
    seen the 65th ("YAML syntax error: ... exceeded maximum nesting depth"); libyaml
    0.2.5 (PyYAML 6.0.3) had no limit. Either way the issue points into the nest where
    it is deeper than `MAX_DEPTH` levels."""
    text = "dimension: 2\nbodies: " + nest + "\n"
    events = events_read(monkeypatch)
    i = only(tmp_path / "deep.yaml", text)
    # the loader stops within the limit's events (a level is at most a key and its
    # collection), not at the end of the nest; time against depth:
    # tools/bench_reading_text.py, "nesting ... n levels deep"
    assert events[0] <= 2 * loader.MAX_DEPTH + 8
    assert i.line in (2, 3) and i.column >= 1
    lines = text.split("\n")
    at = sum(len(s) + 1 for s in lines[:i.line - 1]) + i.column - 1
    assert at < len(text) - 1  # inside the nest, not at its end
    # the document's mapping, the collections opened before that point and the one
    # opened there: more levels than the limit
    assert 1 + text[:at].count(opener) + 1 > loader.MAX_DEPTH
    assert i.message and "\n" not in i.message
    assert i.key == "" or i.key.startswith("bodies")
    if i.message.startswith("nesting"):  # the loader's own refusal names its limit
        assert i.message == f"nesting deeper than {loader.MAX_DEPTH} levels"
        assert i.key.startswith("bodies")


@pytest.mark.parametrize("nest, opener", DEEP_NESTS)
def test_deep_nesting_on_the_command_line_exits_2_with_a_place(tmp_path, capsys, nest,
                                                                opener, any_parser):
    from mbody.cli import main

    path = tmp_path / "deep.yaml"
    path.write_text("dimension: 2\nbodies: " + nest + "\n", encoding="utf-8")
    assert main(["check", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith(f"mbody: error: {path}:")
    line = int(err[len(f"mbody: error: {path}:"):].split(":")[0])
    assert line in (2, 3)
    assert "Traceback" not in err and len(err.splitlines()) <= 2


def test_deep_nesting_below_libyamls_own_limit_is_the_loaders(tmp_path, any_parser):
    """Deeper than `MAX_DEPTH` and well below libyaml's 1000: whatever the parser, the
    loader's refusal with its path."""
    depth = 3 * loader.MAX_DEPTH
    text = "dimension: 2\nbodies: " + "[" * depth + "]" * depth + "\n"
    i = only(tmp_path / "deep.yaml", text)
    assert i.message == f"nesting deeper than {loader.MAX_DEPTH} levels"
    # the document's mapping is the first level: the 64th bracket opens the 65th
    assert (i.line, i.column) == (2, len("bodies: ") + loader.MAX_DEPTH)
    assert i.key.startswith("bodies[0]")


def test_nesting_at_the_limit_is_parsed():
    depth = loader.MAX_DEPTH - 1
    doc = loader.load_text("a: " + "[" * depth + "1" + "]" * depth)
    v = doc.data["a"]
    for _ in range(depth):
        v = v[0]
    assert v == 1


@pytest.mark.parametrize("text", ["", "\n\n", "# only a comment\n", "---\n...\n"])
def test_empty_file(tmp_path, text):
    found = issues(tmp_path / "m.yaml", text)
    assert len(found) == 1
    msg = found[0].message
    assert "empty" in msg or "expected a model mapping" in msg


def test_top_level_must_be_a_mapping(tmp_path):
    i = only(tmp_path / "m.yaml", "- a\n- b\n")
    assert (i.line, i.column) == (1, 1)
    assert i.message == "expected a model mapping, got a list of 2"


def test_non_utf8_file_names_the_byte(tmp_path):
    raw = b"dimension: 2\nmodel: caf\xe9\n" + BODY.encode()
    i = only(tmp_path / "latin1.yaml", raw)
    assert (i.line, i.column) == (2, 11)
    assert "not UTF-8" in i.message and "0xe9" in i.message


def test_utf8_with_bom_and_unicode_names(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_bytes("\ufeffdimension: 2\nmodel: Schwungrad-Übung\n".encode()
                     + b"bodies:\n  - {name: r\xc3\xa4d, mass: 1, inertia: 1}\n")
    m = mbody.load(path)
    assert m.name == "Schwungrad-Übung" and m.body_names == ("räd",)


def test_directory_is_refused(tmp_path):
    with pytest.raises(ModelError) as err:
        mbody.load(tmp_path)
    (i,) = err.value.issues
    assert i.file == str(tmp_path) and "directory" in i.message


def test_missing_file(tmp_path):
    path = tmp_path / "nope.yaml"
    with pytest.raises(ModelError) as err:
        mbody.load(path)
    assert str(err.value) == f"{path}: no such file"


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads everything")
def test_unreadable_file(tmp_path):
    path = tmp_path / "locked.yaml"
    path.write_text("dimension: 2\n" + BODY)
    path.chmod(0)
    try:
        with pytest.raises(ModelError) as err:
            mbody.load(path)
        assert "cannot read the file" in str(err.value)
    finally:
        path.chmod(0o644)


# -- syntax errors --------------------------------------------------------------------

@pytest.mark.parametrize(("text", "where", "words"), [
    ("dimension: 2\nbodies: [\n  {name: a, mass: 1\n", (4, 1), "flow"),
    ("dimension: 2\nbodies:\n\t- {name: a}\n", (3, 1), "a tab in the indentation"),
    ("dimension: 2\nmodel: a: b\n", (2, 9), "mapping values are not allowed"),
    ("dimension: 2\nbodies:\n  a: 1\n b: 2\n", (4, 2), "block mapping"),
    ("dimension: 2\nmodel: \"unclosed\n", (3, 1), "quoted scalar"),
])
def test_syntax_errors_name_line_and_column(tmp_path, text, where, words, any_parser):
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == where
    assert i.message.startswith("YAML syntax error") and words in i.message


def test_syntax_error_says_where_the_unclosed_part_started(tmp_path):
    text = "dimension: 2\nbodies: [\n  {name: a, mass: 1}\n\n"
    i = only(tmp_path / "m.yaml", text)
    assert "started at line 2, column 9" in i.message


def test_second_document_is_refused(tmp_path):
    text = "dimension: 2\n" + BODY + "---\ndimension: 3\n"
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == mark_of(text, "---")
    assert "second YAML document" in i.message


# -- scalars --------------------------------------------------------------------------

def test_exponent_without_dot_is_a_number(any_parser):
    # YAML 1.1 reads 1e3 as text; engineers mean a thousand. Quoted, it stays text.
    data = loader.load_text("a: 1e3\nb: -2.5E-2\nc: '1e3'\nd: -.5\ne: 1.\n").data
    assert data == {"a": 1000.0, "b": -0.025, "c": "1e3", "d": -0.5, "e": 1.0}


def test_quoted_number_is_text_where_a_number_is_expected(tmp_path):
    text = "dimension: 2\nbodies:\n  - {name: a, mass: '1e3', inertia: 1}\n"
    i = only(tmp_path / "m.yaml", text)
    assert (i.line, i.column) == mark_of(text, "'1e3'")
    assert i.message == "expected a number, got the text '1e3'"


def test_marks_of_keys_and_values(any_parser):
    text = "dimension: 3\nbodies:\n  - name: a\n    inertia:\n      - [1, 0, 0]\n"
    doc = loader.load_text(text)
    assert doc.key_marks[("bodies", 0, "inertia")] == (4, 5)
    assert doc.marks[("bodies", 0, "inertia", 0, 2)] == mark_of(text, "0]")
    assert doc.where(("bodies", 0, "mass")) == (3, 5)  # absent: the enclosing mapping


@pytest.mark.parametrize("path", sorted(MODELS.glob("*.yaml")), ids=lambda p: p.name)
def test_same_values_as_pyyaml_on_shipped_models(path):
    text = path.read_text()
    assert loader.load_text(text, str(path)).data == yaml.safe_load(text)


def test_loading_10000_bodies_is_fast(tmp_path):
    body = ("  - {name: b%d, mass: 1.5, inertia: [2, 3, 4], position: [%d, 0, 0], "
            "angular_velocity: [1, 2, 3], orientation: {quaternion: [1, 0, 0, 0]}}\n")
    text = "dimension: 3\nbodies:\n" + "".join(body % (i, i) for i in range(10_000))
    # time against the number of bodies: tools/bench_reading_text.py, "n bodies one a
    # line, located" (linear)
    doc = loader.load_text(text)
    assert len(doc.data["bodies"]) == 10_000 and doc.marks[("bodies", 9999)] == (10_002, 5)
    last = body % (9999, 9999)  # and every value of the last one has its place
    assert doc.marks[("bodies", 9999, "orientation", "quaternion", 3)] == (
        10_002, last.rindex("0]") + 1)


def test_mangled_text_gives_model_errors_only():
    """Random edits of shipped model files: each loads, or fails with a located ModelError."""
    import random

    rng = random.Random(7)
    texts = [p.read_text() for p in sorted(MODELS.glob("*.yaml"))]
    pieces = list("[]{}:,-'\"#&*!|>%@` \n\t0123456789.eE+ab") + ["deg", "~", "<<: ", ": "]
    refused = 0
    for _ in range(1500):
        t = rng.choice(texts)
        for _ in range(rng.randint(1, 3)):
            k = rng.randrange(len(t))
            op = rng.random()
            if op < 0.4:
                t = t[:k] + rng.choice(pieces) + t[k:]
            elif op < 0.7:
                t = t[:k] + t[k + rng.randint(1, 5):]
            else:
                t = t[:k] + rng.choice(pieces) + t[k + 1:]
        try:
            mbody.assemble(mbody.loads(t, "m.yaml"))
        except ModelError as exc:
            refused += 1
            lines = t.count("\n") + 2
            assert all(i.file == "m.yaml" and 0 <= i.line <= lines for i in exc.issues)
        except Exception as exc:  # pragma: no cover - the failure message is the point
            pytest.fail(f"{type(exc).__name__}: {exc} on\n{t}")
    assert refused > 300


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero")
def test_endless_device_is_refused_unread(monkeypatch):
    paths = opened(monkeypatch)
    with pytest.raises(ModelError) as err:
        mbody.load("/dev/zero", max_bytes=2**20)
    assert paths == []  # refused from its kind, never opened (tools/bench_reading.py)
    assert str(err.value).startswith("/dev/zero: this is a character device")


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="no /proc")
def test_endless_pipe_is_read_only_up_to_the_limit(tmp_path, monkeypatch):
    import subprocess

    fifo = tmp_path / "endless.yaml"
    os.mkfifo(fifo)
    writer = subprocess.Popen(f"yes 'a: 1' > {fifo}", shell=True)
    taken = []
    real_read = os.read

    def read(fd: int, n: int) -> bytes:
        chunk = real_read(fd, n)
        taken.append(len(chunk))
        return chunk

    try:
        monkeypatch.setattr(os, "read", read)
        with pytest.raises(ModelError) as err:
            mbody.load(fifo, max_bytes=2**20)
        monkeypatch.undo()
        # the limit and one byte to see it passed, then no more (tools/bench_reading.py
        # times it against reading a 1 MiB file)
        assert sum(taken) == 2**20 + 1
        assert str(err.value) == (f"{fifo}: the file is larger than 1048576 bytes, the most "
                                  "that is read (--max-bytes N on the command line, or "
                                      "mbody.load(path, max_bytes=N), reads more)")
    finally:
        writer.kill()
        writer.wait()


def test_model_from_a_pipe(tmp_path):
    import threading

    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    text = (MODELS / "seed_example_1.yaml").read_text()
    writer = threading.Thread(target=fifo.write_text, args=(text,))
    writer.start()
    try:
        assert mbody.load(fifo).mass.tolist() == [10.0]
    finally:
        writer.join(timeout=5)


def test_a_missing_file_names_the_nearest_one_beside_it(tmp_path):
    """A misspelt model file: the file of the same suffix whose name is nearest, with its
    folder (nothing when no name is near: '.yaml' alone does not make two names alike)."""
    (tmp_path / "slider_crank_driven.yaml").write_text("x")
    (tmp_path / "scotch_yoke.yaml").write_text("x")
    with pytest.raises(ModelError) as err:
        mbody.load(tmp_path / "slider_crank_drive.yaml")
    (i,) = err.value.issues
    assert i.message == "no such file"
    assert i.hint == f"did you mean '{tmp_path / 'slider_crank_driven.yaml'}'?"
    with pytest.raises(ModelError) as err:
        mbody.load(tmp_path / "nothing_like_it.yaml")
    assert err.value.issues[0].hint == ""


# -- the Python entry points' arguments (a notebook user's slips) ---------------------------
@pytest.mark.parametrize("load", [mbody.load, mbody.model.load], ids=["mbody", "model"])
@pytest.mark.parametrize("source, got", [(None, "got None"), (3, "got int 3"),
                                         (b"models/pendulum.yaml", "got bytes"),
                                         (["a.yaml"], "got list")],
                         ids=["None", "int", "bytes", "list"])
def test_load_of_a_wrong_type_names_source_and_what_it_takes(load, source, got):
    """Neither a path nor a dict: a TypeError (and an MbodyError: exit 2 on the command
    line) that names `source`, the kinds it takes and the text reader, not pathlib's."""
    with pytest.raises(TypeError) as err:
        load(source)
    assert isinstance(err.value, mbody.MbodyError)
    msg = str(err.value)
    assert msg.startswith("source must be a path")
    assert "a dict" in msg and "mbody.loads" in msg and got in msg


def test_load_of_an_open_file_says_to_give_its_path_or_its_text():
    with open(MODELS / "pendulum.yaml", encoding="utf-8") as fh, \
            pytest.raises(TypeError, match=r"source must be .*got TextIOWrapper") as err:
        mbody.load(fh)
    assert "f.name" in str(err.value) and "mbody.loads(f.read())" in str(err.value)


@pytest.mark.parametrize("text", [
    "dimension: 2\nbodies: []",                     # a line break
    "{dimension: 2, bodies: []}",                   # a flow mapping on one line
    "dimension: 2",                                 # a mapping's first key
], ids=["lines", "flow", "key"])
def test_yaml_text_given_as_a_path_points_to_loads(text):
    with pytest.raises(ModelError) as err:
        mbody.load(text)
    (issue,) = err.value.issues
    assert issue.key == "source" and "looks like YAML text" in issue.message
    assert issue.hint == "use mbody.loads(text)"


def test_a_whole_model_file_given_as_a_path_is_not_echoed_back():
    """Before: 'cannot read the file: File name too long', after the whole text."""
    text = (MODELS / "pendulum.yaml").read_text(encoding="utf-8")
    with pytest.raises(ModelError) as err:
        mbody.load(text)
    msg = str(err.value)
    assert "mbody.loads(text)" in msg and len(msg) < 200 and "too long" not in msg


def test_a_path_that_looks_like_yaml_but_exists_is_read(tmp_path, monkeypatch):
    """The YAML test is asked only of a path that does not exist."""
    monkeypatch.chdir(tmp_path)
    Path("dimension: 2").write_text("dimension: 2\n" + BODY, encoding="utf-8")
    assert mbody.load("dimension: 2").n == 1


@pytest.mark.parametrize("max_bytes", ["10", 1.5, True, [10]])
def test_max_bytes_of_a_wrong_type_is_refused_by_name(max_bytes):
    with pytest.raises(TypeError, match=r"^max_bytes must be a whole number of bytes"):
        mbody.load(MODELS / "pendulum.yaml", max_bytes=max_bytes)


@pytest.mark.parametrize("max_bytes", [0, -5])
def test_max_bytes_below_one_byte_is_refused(max_bytes):
    with pytest.raises(mbody.MbodyError, match=r"^max_bytes: expected a size of at least 1"):
        mbody.load(MODELS / "pendulum.yaml", max_bytes=max_bytes)


def test_max_bytes_as_a_whole_float_or_numpy_integer_is_a_size():
    import numpy as np

    path = MODELS / "pendulum.yaml"
    size = path.stat().st_size
    assert mbody.load(path, max_bytes=float(size)).n == 1
    assert mbody.load(path, max_bytes=np.int64(size)).n == 1
    with pytest.raises(ModelError, match="at most"):
        mbody.load(path, max_bytes=np.int64(size - 1))


def test_loads_reads_utf8_bytes_as_a_file_is_read():
    raw = (MODELS / "pendulum.yaml").read_bytes()
    assert mbody.loads(raw).n == mbody.load(MODELS / "pendulum.yaml").n == 1
    bad = b"dimension: 2\nname: caf\xe9\n" + BODY.encode()
    with pytest.raises(ModelError) as err:
        mbody.loads(bad, "cafe.yaml")
    (issue,) = err.value.issues
    assert (issue.file, issue.line, issue.column) == ("cafe.yaml", 2, 10)
    assert "not UTF-8" in issue.message


@pytest.mark.parametrize("text", [None, 3, MODELS / "pendulum.yaml"], ids=["None", "int", "path"])
def test_loads_of_a_wrong_type_names_text(text):
    with pytest.raises(TypeError, match=r"^text must be a model file's YAML text") as err:
        mbody.loads(text)
    if isinstance(text, Path):
        assert "mbody.load(path)" in str(err.value)


@pytest.mark.parametrize("text", ["models/pendulum.yaml", "robots/arm.URDF "])
def test_loads_of_a_path_points_to_load(text):
    """Before: "expected a model mapping, got the text 'models/pendulum.yaml'"."""
    with pytest.raises(ModelError) as err:
        mbody.loads(text)
    (issue,) = err.value.issues
    assert "looks like a path" in issue.message and issue.hint == "use mbody.load(path)"


@pytest.mark.parametrize("name", ["v1:", "C:\\models\\arm.yaml"])
def test_a_one_line_name_colon_in_a_path_is_still_a_missing_file(tmp_path, monkeypatch, name):
    """Only 'key: value' (a blank after the colon) reads as YAML on one line: 'v1:' and
    'C:\\models' are names of files, looked for as such."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ModelError, match="no such file"):
        mbody.load(name)

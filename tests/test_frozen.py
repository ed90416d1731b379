"""`mbody.util.frozen`: records that refuse changes, and dataclasses made so on first look.

`dataclass_on_first_look` must give every reader of dataclasses what ``@dataclass`` gives
(fields, replace, is_dataclass, asdict, a subclass dataclass, the match statement), and
only when one looks: a process that simulates and never introspects pays nothing."""

from __future__ import annotations

import copy
import dataclasses
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from mbody.util.frozen import Frozen, dataclass_on_first_look

ROOT = Path(__file__).resolve().parents[1]


def _record(decorate):
    @decorate(eq=False, init=False, repr=False)
    class Record(Frozen):
        """Two fields, one with a default_factory."""

        a: int
        b: list[int] = field(default_factory=list)
        c: str = "c"

        def __init__(self, a: int, b: list[int] | None = None, c: str = "c") -> None:
            self.__dict__.update(a=a, b=[] if b is None else b, c=c)

    return Record


def _seen(cls) -> list[tuple]:
    return [(f.name, f.type, f.default, f.default_factory, f.init, f.kw_only)
            for f in dataclasses.fields(cls)]


def test_a_record_on_first_look_reads_as_the_decorated_one():
    lazy, eager = _record(dataclass_on_first_look), _record(dataclass)
    assert _seen(lazy) == _seen(eager)
    r = lazy(1, [2])
    assert dataclasses.is_dataclass(lazy) and dataclasses.is_dataclass(r)
    assert dataclasses.asdict(r) == {"a": 1, "b": [2], "c": "c"}
    s = dataclasses.replace(r, a=3)
    assert (type(s), s.a, s.b, s.c) == (lazy, 3, [2], "c")
    assert lazy.__match_args__ == eager.__match_args__ == ("a", "b", "c")
    match r:
        case lazy(a, b):  # positional patterns read __match_args__
            assert (a, b) == (1, [2])
        case _:
            pytest.fail("the positional pattern did not match")
    with pytest.raises(dataclasses.FrozenInstanceError, match="'a'"):
        r.a = 2


@pytest.mark.parametrize("first", ["__match_args__", "__dataclass_params__",
                                   "__dataclass_fields__"])
def test_whichever_attribute_is_read_first_makes_the_dataclass(first: str):
    lazy = _record(dataclass_on_first_look)
    getattr(lazy, first)
    assert type(lazy.__dict__["__dataclass_fields__"]) is dict
    assert lazy.__dataclass_params__.eq is False and lazy.__dataclass_params__.init is False
    assert "__eq__" not in lazy.__dict__ and "__repr__" not in lazy.__dict__


def test_a_dataclass_subclass_reads_the_fields_of_its_lazy_base():
    lazy = _record(dataclass_on_first_look)

    @dataclass(eq=False)
    class More(lazy):
        d: float = 0.5

    assert [f.name for f in dataclasses.fields(More)] == ["a", "b", "c", "d"]


def test_threads_looking_at_once_make_it_once():
    lazy = _record(dataclass_on_first_look)
    seen: list[object] = []
    barrier = threading.Barrier(8)

    def look() -> None:
        barrier.wait()
        seen.append(lazy.__dataclass_fields__)

    threads = [threading.Thread(target=look) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(seen) == 8 and all(s is seen[0] for s in seen)


def test_before_the_first_look_the_class_is_as_the_dataclass_leaves_it():
    """Its Field defaults are plain class attributes (or none), as after ``@dataclass``:
    an instance missing a field does not read a Field object."""
    lazy, eager = _record(dataclass_on_first_look), _record(dataclass)
    assert type(lazy.__dict__["__dataclass_fields__"]).__name__ == "_OnFirstLook"
    for name in ("a", "b", "c"):
        assert (name in lazy.__dict__) == (name in eager.__dict__), name
    assert lazy.c == eager.c == "c"
    assert not hasattr(lazy.__new__(lazy), "b")


@pytest.mark.skipif(sys.version_info < (3, 13), reason="copy.replace is Python 3.13's")
def test_copy_replace_works_before_any_other_look():
    lazy = _record(dataclass_on_first_look)
    r = copy.replace(lazy(1), a=2)  # type: ignore[attr-defined]
    assert (r.a, r.c) == (2, "c")


def test_what_cannot_be_deferred_is_refused():
    for options in ({}, {"eq": False, "init": False}, {"eq": False, "init": False,
                                                      "repr": False, "frozen": True}):
        with pytest.raises(TypeError, match="eq=False, init=False, repr=False"):
            dataclass_on_first_look(**options)

    class Bare(Frozen):
        a: int

    with pytest.raises(TypeError, match="needs a docstring"):
        dataclass_on_first_look(eq=False, init=False, repr=False)(Bare)


def test_a_thread_never_sees_the_class_half_made():
    """One thread makes the dataclass (a first look) while another reads it without
    going through a look of its own (`fields`, a positional ``match``), the interpreter
    switching threads every microsecond: the reader sees the class before or after,
    never between (a version that removed the looks before making the class failed a
    trial in 15)."""
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    failures: list[str] = []
    try:
        for _ in range(150):
            lazy = _record(dataclass_on_first_look)
            go, stop = threading.Event(), threading.Event()

            def read(cls=lazy, go=go, stop=stop) -> None:
                go.wait()
                while not stop.is_set():
                    try:
                        dataclasses.fields(cls)
                        match cls(1):
                            case cls(a):
                                assert a == 1
                    except Exception as exc:  # noqa: BLE001 - any failure is the finding
                        failures.append(f"{type(exc).__name__}: {exc}")
                        return

            reader = threading.Thread(target=read)
            reader.start()
            go.set()
            lazy.__dataclass_params__  # noqa: B018 - the first look
            stop.set()
            reader.join()
    finally:
        sys.setswitchinterval(interval)
    assert failures == []


def test_a_run_does_not_make_the_trajectory_a_dataclass_until_asked():
    """The point of the deferral: a fresh process's simulate pays for no dataclass; a
    look afterwards still finds one."""
    code = (
        "import dataclasses, inspect, mbody\n"
        f"traj = mbody.simulate(mbody.load({str(ROOT / 'models' / 'pendulum.yaml')!r}), "
        "t_end=0.1)\n"
        "T = type(traj)\n"
        "print(type(T.__dict__['__dataclass_fields__']).__name__)\n"
        "names = [f.name for f in dataclasses.fields(traj)]\n"
        "print(names == list(inspect.signature(T.__init__).parameters)[1:], "
        "type(T.__dict__['__dataclass_fields__']).__name__)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == ["_OnFirstLook", "True", "dict"]

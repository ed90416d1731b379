"""Run files (`Trajectory.save`, `mbody simulate -o`) read as hostile input (review R1,
B3, B4, P6): a tampered run is refused at load time, naming the file and what is wrong,
with exit code 2 in every command that reads one (plot, animate, export --state); what a
file claims is checked before anything is inflated; the model text a run carries is
named as the run's, and a file a run names is never echoed."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import sys
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli import main
from mbody.errors import MbodyError, ModelError, TrajectoryFileError
from mbody.simulate.trajectory import Trajectory
from mbody.util.budget import byte_budget

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
MIB = 1 << 20
sys.path.insert(0, str(ROOT / "tools"))
from crafted_files import npy_header, npz_bomb, npz_members  # noqa: E402  (as the benchmark)


@pytest.fixture(scope="module")
def run_data(tmp_path_factory) -> dict[str, np.ndarray]:
    """The arrays of a saved run of the pendulum (1 s at 60 fps: 61 samples)."""
    path = tmp_path_factory.mktemp("run") / "run.npz"
    mbody.simulate(mbody.load(MODELS / "pendulum.yaml"), t_end=1.0, fps=60).save(path)
    with np.load(path) as z:
        return dict(z)


def tampered(tmp_path: Path, data: dict[str, np.ndarray], name: str = "bad.npz",
             **changes) -> Path:
    """`data` with `changes` (None: the entry removed), saved as `name`."""
    d = {**data, **changes}
    path = tmp_path / name
    np.savez(path, **{k: v for k, v in d.items() if v is not None})
    return path


def archive(path: Path, data: dict[str, np.ndarray], member: str, header: dict,
            body: bytes, deflate: bool = False) -> Path:
    """`data` as an npz in which `member` has the .npy `header` and the bytes `body`."""
    method = zipfile.ZIP_DEFLATED if deflate else zipfile.ZIP_STORED
    with zipfile.ZipFile(path, "w", method) as z:
        for k, v in data.items():
            b = io.BytesIO()
            if k == member:
                np.lib.format.write_array_header_1_0(b, header)
                b.write(body)
            else:
                np.save(b, v)
            z.writestr(k + ".npy", b.getvalue())
    return path


COMMANDS = {
    "plot": ["plot", "{run}", "-o", "{tmp}/x.png"],
    "animate": ["animate", "{run}", "-o", "{tmp}/x.html"],
    "export": ["export", str(MODELS / "pendulum.yaml"), "--state", "{run}", "-o",
               "{tmp}/x.json"],
}


def refused(capsys, tmp_path: Path, command: str, run: Path) -> str:
    """The one-line error of `command` on `run`, asserted to exit 2, name the run and
    write nothing."""
    args = [a.format(run=run, tmp=tmp_path) for a in COMMANDS[command]]
    code = main(args)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith(f"mbody: error: {run}") and "Traceback" not in err, err
    assert not any(tmp_path.glob("x.*"))
    return err


# -- B3: nesting, declared sizes, values --------------------------------------------------


@pytest.mark.parametrize("command", COMMANDS)
def test_json_nested_too_deeply_is_refused(run_data, tmp_path, capsys, command):
    run = tampered(tmp_path, run_data, info=np.array('{"a":' * 10000))
    err = refused(capsys, tmp_path, command, run)
    assert "damaged" in err and "'info'" in err and "nested 10000 deep" in err
    assert "at most 64" in err


def test_shapes_and_colors_json_are_bounded_and_checked(run_data, tmp_path):
    for key, text, words in (("shapes", "[" * 5000 + "]" * 5000, "nested 5000 deep"),
                             ("colors", '["red", "blue"]', "2 entries for 1 bodies"),
                             ("shapes", '["box"]', "entry 0 is 'box', expected null or an "
                                                   "object"),
                             ("colors", "{}", "expected a list")):
        run = tampered(tmp_path, run_data, **{key: np.array(text)})
        with pytest.raises(TrajectoryFileError, match=f"'{key}'") as exc:
            Trajectory.load(run)
        assert str(exc.value).startswith(f"{run}: ") and words in str(exc.value), key


@pytest.mark.parametrize("command", COMMANDS)
def test_a_header_claiming_more_than_the_member_holds_is_refused_unallocated(
        run_data, tmp_path, capsys, command):
    """The reviewer's liar: t.npy's header claims 10^15 samples, the member holds 16
    bytes (numpy would allocate 7 PiB, a MemoryError, exit 70)."""
    run = archive(tmp_path / "liar.npz", run_data, "t",
                  {"descr": "<f8", "fortran_order": False, "shape": (10**15,)}, b"\0" * 16)
    err = refused(capsys, tmp_path, command, run)
    assert "damaged" in err and "member t.npy" in err
    assert "1,000,000,000,000,000 values" in err and "16 bytes" in err


def test_infinite_positions_are_refused_with_the_sample_and_body(run_data, tmp_path,
                                                                 capsys):
    pos = run_data["position"].copy()
    pos[7, 0, 1] = np.inf
    run = tampered(tmp_path, run_data, position=pos)
    for command in COMMANDS:  # animate fitted its camera to inf: ValueError, exit 70
        err = refused(capsys, tmp_path, command, run)
        assert "'position' holds inf at sample 7" in err and "body 'rod'" in err


@pytest.mark.parametrize("key", ["velocity", "orientation", "angular_velocity", "mass",
                                 "inertia", "gravity"])
def test_every_state_and_body_array_must_be_finite(run_data, tmp_path, key):
    a = run_data[key].copy()
    a.reshape(-1)[-1] = np.nan
    with pytest.raises(TrajectoryFileError, match=f"'{key}' holds nan"):
        Trajectory.load(tampered(tmp_path, run_data, **{key: a}))


@pytest.mark.parametrize("command", COMMANDS)
def test_times_not_finite_or_not_increasing_are_refused(run_data, tmp_path, capsys,
                                                        command):
    t = run_data["t"]
    nan = tampered(tmp_path, run_data, "nant.npz", t=np.where(t > 0.5, np.nan, t))
    err = refused(capsys, tmp_path, command, nan)
    assert "'t' holds nan at sample 31" in err
    back = t.copy()
    back[[10, 11]] = back[[11, 10]]
    rev = tampered(tmp_path, run_data, "revt.npz", t=back)
    err = refused(capsys, tmp_path, command, rev)
    assert "'t' do not increase: sample 11" in err
    same = tampered(tmp_path, run_data, "samet.npz", t=np.minimum(t, 0.5))
    assert "'t' do not increase: sample 31" in refused(capsys, tmp_path, command, same)


@pytest.mark.parametrize(("key", "value", "expected"), [
    ("rtol", "x", "a number"),
    ("rtol", True, "a number"),  # JSON true is a Python int: taken as 1 before (review R3 Y10)
    ("energy_drift", False, "a number"),
    ("momentum_initial", [0.0, True, 0.0], "3 numbers"),
    ("warnings", 3, "a list of texts"),
    ("reaction_axes", "sideways", "'joint' or 'world'"),
    ("model_values", [["bodies.rod.mass"]], "[path, value] pairs"),
    ("drivers", [{"name": 1}], "a list of drivers"),
])
def test_info_entries_a_reader_uses_must_be_of_their_kind(run_data, tmp_path, capsys, key,
                                                          value, expected):
    """plot formats info['rtol'] with :g and adds ' axes' to info['reaction_axes']; a
    tampered entry was an internal error (exit 70) there."""
    info = json.loads(str(run_data["info"]))
    info[key] = value
    run = tampered(tmp_path, run_data, info=np.array(json.dumps(info)))
    err = refused(capsys, tmp_path, "plot", run)
    assert f"its entry {key!r} is" in err and expected in err


def test_arrays_that_are_not_numbers_or_texts_are_refused(run_data, tmp_path):
    for changes, words in (({"t": run_data["t"].astype(str)}, "'t' holds"),
                           ({"dimension": np.array("2")}, "expected one whole number"),
                           ({"body_names": np.array([1.0])}, "expected a list of names"),
                           ({"model_yaml": np.array([1, 2])}, "expected one text")):
        with pytest.raises(TrajectoryFileError, match=words):
            Trajectory.load(tampered(tmp_path, run_data, **changes))


PER_SAMPLE = ("t", "position", "velocity", "orientation", "angular_velocity", "reactions")


def without_samples(run_data: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The run with every per-sample array cut to no samples."""
    return {k: v[:0] if k in PER_SAMPLE or k.startswith("series/") else v
            for k, v in run_data.items()}


@pytest.mark.parametrize("command", COMMANDS)
def test_values_of_no_bytes_are_refused_whatever_they_claim(run_data, tmp_path, capsys,
                                                            command):
    """Review R3, S1: 10^12 body names of width 0 ('<U0') held no bytes, so the header
    agreed with its size; with no samples every state array held none either, and the
    5 kB file made plot build 10^12 texts (106 s, 3.6 GB, a MemoryError: exit 70)."""
    n = 10**12
    data: dict[str, np.ndarray | bytes | None] = {
        **without_samples(run_data), "body_names": npy_header((n,), "<U0"),
        "position": npy_header((0, n, 2), "<f8"), "velocity": npy_header((0, n, 2), "<f8"),
        "orientation": npy_header((0, n), "<f8"),
        "angular_velocity": npy_header((0, n), "<f8"), "mass": None, "inertia": None}
    run = npz_members(tmp_path / "u0.npz", data)
    assert run.stat().st_size < 10_000
    err = refused(capsys, tmp_path, command, run)
    assert "member body_names.npy's header says it holds 1,000,000,000,000 values of " \
           "0 bytes each, dtype <U0" in err
    assert peak_bytes(Trajectory.load, run) < MIB


def test_any_member_of_zero_width_values_is_refused(run_data, tmp_path):
    """Not only texts: a void or field-less record type is 0 bytes wide too; an empty
    array of them claims nothing and is read as before."""
    for descr in ("|V0", "<U0"):
        run = npz_members(tmp_path / "v0.npz", {**run_data, "series/energy":
                                            npy_header((61,), descr)})
        with pytest.raises(TrajectoryFileError, match=r"member series/energy.npy's header "
                           r"says it holds 61 values of 0 bytes each"):
            Trajectory.load(run)
    empty = npz_members(tmp_path / "empty.npz", {**run_data, "reaction_labels":
                                             npy_header((0,), "<U0"), "reactions":
                                             run_data["reactions"][:, :0]})
    assert Trajectory.load(empty).reaction_labels == ()


@pytest.mark.parametrize("command", COMMANDS)
def test_a_run_without_samples_is_refused_when_it_is_read(run_data, tmp_path, capsys,
                                                          command):
    """Review R3, B2: plot took the minimum of no energies (exit 70); animate and export
    each refused it in words of their own."""
    run = tampered(tmp_path, without_samples(run_data), "k0.npz")
    err = refused(capsys, tmp_path, command, run)
    assert "'t' holds no samples (a run holds at least one sample)" in err


def test_a_trajectory_made_without_samples_is_refused_by_every_reader(run_data, tmp_path):
    """A trajectory made in code is not read from a file: each reader that needs a sample
    asks `need_samples`, one wording for all."""
    from mbody.io.export import state_at
    from mbody.present.animate import build_scene
    from mbody.present.plot import plot_trajectory

    good = Trajectory.load(tampered(tmp_path, run_data, "good.npz"))
    assert good.need_samples() == 61
    d = {f.name: getattr(good, f.name) for f in dataclasses.fields(good)}
    empty = Trajectory(**{**d, **{k: d[k][:0] for k in PER_SAMPLE}})
    for read in (empty.need_samples, lambda: empty.state_at(0.0),
                 lambda: state_at(empty, None), lambda: plot_trajectory(empty),
                 lambda: build_scene(empty, good.model())):
        with pytest.raises(MbodyError, match=r"^the trajectory holds no samples \(a run "
                           r"holds at least one sample\)$"):
            read()


def test_more_names_than_one_per_kib_of_the_budget_are_refused_unread(run_data, tmp_path):
    """Each name becomes a Python text of some 60 bytes where the file spends 4: the
    names a run holds are bounded by the budget (`NAME_BYTES`), from their header."""
    n = 2000
    data = {**run_data, "t": run_data["t"][:1], "body_names": np.array(["b"] * n),
            "position": np.zeros((1, n, 2)), "velocity": np.zeros((1, n, 2)),
            "orientation": np.zeros((1, n)), "angular_velocity": np.zeros((1, n)),
            "reactions": run_data["reactions"][:1], "mass": np.ones(n),
            "inertia": np.broadcast_to(np.eye(3), (n, 3, 3)).copy(),
            "shapes": np.array("[]"), "colors": np.array("[]")}
    data = {k: v for k, v in data.items() if not k.startswith("series/")}
    run = npz_members(tmp_path / "names.npz", data)
    with pytest.raises(TrajectoryFileError) as exc:
        Trajectory.load(run, max_bytes=MIB)
    assert str(exc.value).startswith(f"{run}: 'body_names' holds 2,000 names; at most "
                                     "1,024 are read, one per KiB of the budget of 1 MiB")
    assert "--max-bytes N" in str(exc.value)
    assert Trajectory.load(run, max_bytes=2 * MIB).n == n


# -- B4: bounded work ---------------------------------------------------------------------


def peak_bytes(load, *args) -> int:
    """The most memory Python and numpy held while `load(*args)` ran (until it raised)."""
    tracemalloc.start()
    with contextlib.suppress(MbodyError):  # the refusal is checked by the caller
        load(*args)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def test_a_member_over_the_budget_is_refused_before_it_is_inflated(run_data, tmp_path):
    """The reviewer's bomb, scaled down: t.npy inflates to 64 MiB from about 64 kB; with a
    16 MiB budget it is refused from the zip directory, before anything is inflated."""
    run = npz_bomb(tmp_path / "bomb.npz", run_data, 8 * MIB)
    assert run.stat().st_size < MIB
    with byte_budget(16 * MIB), pytest.raises(TrajectoryFileError) as exc:
        Trajectory.load(run)
    assert str(exc.value).startswith(f"{run}: holds 64 MiB of data once inflated")
    assert "at most 16 MiB is read" in str(exc.value) and "--max-bytes N" in str(exc.value)
    with byte_budget(16 * MIB):
        assert peak_bytes(Trajectory.load, run) < 4 * MIB
    with pytest.raises(TrajectoryFileError, match="at most 1 KiB"):
        Trajectory.load(tmp_path / "bomb.npz", max_bytes=1024)


def test_shapes_are_checked_against_each_other_before_any_array_is_inflated(run_data,
                                                                            tmp_path):
    """Under the budget, a t.npy of 8 Mi samples beside 61 positions is refused from the
    headers: the 64 MiB are never inflated."""
    run = npz_bomb(tmp_path / "bomb.npz", run_data, 8 * MIB)
    with pytest.raises(TrajectoryFileError, match=r"'position' has shape \(61, 1, 2\), "
                       r"expected \(8388608, 1, 2\)"):
        Trajectory.load(run)
    assert peak_bytes(Trajectory.load, run) < 4 * MIB


def test_max_bytes_on_the_command_line_reads_a_larger_run(run_data, tmp_path, capsys):
    run = tampered(tmp_path, run_data, "run.npz")
    code = main(["plot", str(run), "-o", str(tmp_path / "x.png"), "--max-bytes", "10k"])
    err = capsys.readouterr().err
    assert code == 2 and f"{run}: holds " in err and "at most 10 KiB" in err
    assert main(["plot", str(run), "-o", str(tmp_path / "x.png"), "--max-bytes", "1M"]) == 0


@pytest.mark.parametrize("problem", ["method", "encrypted", "twice", "objects"])
def test_members_numpy_does_not_write_are_refused(run_data, tmp_path, problem):
    path = tmp_path / "odd.npz"
    with zipfile.ZipFile(path, "w") as z:
        for k, v in run_data.items():
            b = io.BytesIO()
            np.save(b, v)
            info = zipfile.ZipInfo(k + ".npy")
            if k == "t" and problem == "method":
                info.compress_type = zipfile.ZIP_BZIP2
            if k == "t" and problem == "objects":
                b = io.BytesIO()
                np.lib.format.write_array_header_1_0(
                    b, {"descr": "|O", "fortran_order": False, "shape": (0,)})
            z.writestr(info, b.getvalue())
        if problem == "twice":
            with pytest.warns(UserWarning, match="Duplicate name"):
                z.writestr("t.npy", b"")
    if problem == "encrypted":  # zipfile writes no encryption: the directory's flag set
        raw = bytearray(path.read_bytes())
        entry = raw.index(b"PK\x01\x02")  # the central directory's first entry
        while raw[entry + 46:entry + 51] != b"t.npy":
            entry = raw.index(b"PK\x01\x02", entry + 4)
        raw[entry + 8] |= 0x1
        path.write_bytes(bytes(raw))
    with pytest.raises(TrajectoryFileError, match="member t.npy") as exc:
        Trajectory.load(path)
    assert str(exc.value).startswith(f"{path}: damaged or truncated trajectory file")


# -- P6: the model a run carries, and the file it names -----------------------------------


def test_an_error_in_the_stored_model_names_the_run_not_the_model_file(run_data, tmp_path,
                                                                       capsys):
    text = str(run_data["model_yaml"]).replace("mass: 2.0", "mass: -2.0")
    run = tampered(tmp_path, run_data, "yamlneg.npz", model_yaml=np.array(text))
    code = main(["animate", str(run), "-o", str(tmp_path / "x.html")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith(f"mbody: error: the model stored in {run} (the text of ")
    assert "line 18, column 11: bodies[0].mass: expected a number > 0, got -2.0" in err
    assert "pendulum.yaml:18" not in err  # the file on disk says 2.0
    with pytest.raises(ModelError, match=f"the model stored in {run}"):
        Trajectory.load(run).model()


def test_a_run_naming_another_file_never_prints_it(run_data, tmp_path, capsys):
    secret = tmp_path / "secret.txt"
    secret.write_text("token-5f3a: do not print me\nmore: lines\n")
    run = tampered(tmp_path, run_data, "otherfile.npz", model_yaml=None,
                   model_file=np.array(str(secret)))
    code = main(["animate", str(run), "-o", str(tmp_path / "x.html")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"mbody: error: {run} carries no model text")
    assert "token-5f3a" not in err and "--model MODEL" in err


def test_a_run_without_its_text_still_uses_the_model_file_it_names(run_data, tmp_path,
                                                                   capsys):
    """A run that carries no text (a mode played as a run, saved) is animated with the
    model file it names, as before."""
    run = tampered(tmp_path, run_data, "named.npz", model_yaml=None,
                   model_file=np.array(str(MODELS / "pendulum.yaml")))
    assert main(["animate", str(run), "-o", str(tmp_path / "named.html")]) == 0
    assert "wrote" in capsys.readouterr().out


def test_a_good_run_reads_back_as_it_was_saved(run_data, tmp_path):
    run = tampered(tmp_path, run_data, "good.npz")
    traj = Trajectory.load(run)
    assert traj.run_file == str(run) and len(traj) == 61
    np.testing.assert_array_equal(traj.position, run_data["position"])
    assert traj.model().body_names == ("rod",)


def test_sizes_in_messages_say_which_is_larger():
    from mbody.util.formatting import size_text
    from mbody.util.npzfile import over_budget

    assert size_text(16) == "16 bytes" and size_text(1536) == "1.5 KiB (1,536 bytes)"
    assert size_text(2**31) == "2 GiB" and size_text(8 * 10**15) == "7.11 PiB"
    close = over_budget("r.npz", 2**30 + 100, 2**20, 2**30, "more")
    assert "holds 1,073,741,924 bytes" in close and "at most 1,073,741,824 bytes" in close

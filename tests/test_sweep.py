"""`mbody sweep`: its rows equal the same cases run one by one through the public API; the
local cluster, an existing cluster and this process give the same numbers; a worker
killed mid-run loses nothing and repeats nothing; failed cases are rows; an interrupted
sweep resumes; the grid, samples and errors of the command line (a rerun with other
settings: tests/test_sweep_outputs.py)."""

from __future__ import annotations

import csv
import math
import os
import signal
import socket
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.errors import MbodyError
from mbody.sweep import cluster
from mbody.sweep.grid import parse_grid
from mbody.sweep.record import record
from mbody.sweep.runs import RUNS, Job, Settings, columns, final_values
from mbody.sweep.table import Results

ROOT = Path(__file__).resolve().parent.parent
SLIDER = ROOT / "models" / "slider_crank.yaml"


def driven_text(speed: str = "100") -> str:
    """The shipped slider-crank without its loads, its crank driven at `speed`."""
    text = SLIDER.read_text()
    text = "\n".join(line for line in text.splitlines()
                     if "{name: gas" not in line and "{name: load" not in line)
    return text + f"\ndrivers:\n  - {{name: motor, joint: O, speed: {speed}}}\n"


@pytest.fixture
def driven_file(tmp_path) -> Path:
    path = tmp_path / "driven.yaml"
    path.write_text(driven_text())
    return path


def read(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def floats(cells: list[str]) -> np.ndarray:
    return np.array([float(c) if c else math.nan for c in cells])


def mbody_cli(*argv: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "mbody", *argv], capture_output=True,
                          text=True, cwd=cwd or ROOT, timeout=600, env=env)


def job_of(model: mbody.Model, grid_specs: list[str], settings: Settings, **kw) -> Job:
    return Job(model.source, parse_grid(grid_specs, **kw), settings, uuid.uuid4().hex)


def run_here(job: Job, out: Path, **kw) -> tuple[list[str], list[list[str]]]:
    model = mbody.loads(driven_text(), "driven.yaml")
    results = Results(out, columns(model, job.settings), job.grid, record(job.settings, model))
    cluster.run(job, [k for k in range(len(job.grid)) if k not in results.rows], results,
                progress=False, **kw)
    results.finish()
    return read(out)


GRID = ["drivers.motor.speed=60:240:3", "bodies.rod.mass=0.3:1.2:2"]


def test_solve_rows_are_the_cases_solved_one_by_one(tmp_path):
    """Each row: the case's model read with its values (Model.with_values), solved at its
    own initial state (mbody.assemble(model).solve()): the same numbers to the bit."""
    base = mbody.loads(driven_text(), "driven.yaml")
    job = job_of(base, GRID, Settings("solve"))
    header, rows = run_here(job, tmp_path / "r.csv", workers=0)
    assert header == ["case", "drivers.motor.speed", "bodies.rod.mass",
                      *[f"acceleration:{c}" for c in base.coordinates],
                      *[f"reaction:{r}" for r in base.reactions], "error", "settings"]
    assert [int(r[0]) for r in rows] == list(range(6))
    for row in rows:
        values = {"drivers.motor.speed": float(row[1]), "bodies.rod.mass": float(row[2])}
        sol = mbody.assemble(base.with_values(values)).solve()
        want = [*sol.accelerations, *(sol.reactions[r] for r in base.reactions)]
        assert floats(row[3:-2]).tolist() == want and row[-2] == ""
        assert row[-1] == record(job.settings, base)
    # the grid: the last axis fastest, both ends included
    assert [(float(r[1]), float(r[2])) for r in rows] == [
        (60.0, 0.3), (60.0, 1.2), (150.0, 0.3), (150.0, 1.2), (240.0, 0.3), (240.0, 1.2)]


def one_by_one(base: mbody.Model, values: dict, turns: float, steps: int) -> np.ndarray:
    """The kinematics run of one case through the public API: the kinematic analysis at
    each instant from the previous one, a solve at each; final positions, then peaks."""
    model = base.with_values(values)
    rate = float(model.drivers.laws[0][1](0.0))
    t = np.linspace(0.0, 2 * math.pi * turns / abs(rate), steps)
    state, peaks = model.initial, np.zeros(len(model.reactions))
    for tk in t:
        state = mbody.kinematics(model, float(tk), start=state)
        sol = mbody.assemble(model, state).solve()
        peaks = np.maximum(peaks, np.abs([sol.reactions[r] for r in model.reactions]))
    y = np.concatenate((state.position.ravel(), state.quaternion.ravel()))[None]
    return np.concatenate((final_values(model, y)[0], peaks))


def test_kinematics_rows_are_the_cases_run_one_by_one(tmp_path):
    """The batched kinetostatics (Newton from the previous instant moved along its
    velocities, one analysis shared by the cases of one motion) against the public API's
    loop: positions within the kinematic tolerance (1e-12 of the size; angles rad), peaks
    within 1e-9 of the largest (the positions' error times the forces' sensitivity)."""
    base = mbody.loads(driven_text(), "driven.yaml")
    job = job_of(base, GRID, Settings("kinematics", revolutions=1.0, steps=37))
    _, rows = run_here(job, tmp_path / "k.csv", workers=0)
    nf = 3 * base.n
    for row in rows:
        values = {"drivers.motor.speed": float(row[1]), "bodies.rod.mass": float(row[2])}
        want = one_by_one(base, values, 1.0, 37)
        got = floats(row[3:-2])
        assert np.abs(got[:nf] - want[:nf]).max() <= 1e-11
        peaks, ref = got[nf:], want[nf:]
        assert np.abs(peaks - ref).max() <= 1e-9 * ref.max(), values
    # physics: a heavier rod needs more torque at the same speed; a faster crank more still
    torque = {(float(r[1]), float(r[2])): float(r[-3]) for r in rows}
    assert torque[(150.0, 1.2)] > torque[(150.0, 0.3)]
    assert torque[(240.0, 0.3)] > torque[(150.0, 0.3)] > torque[(60.0, 0.3)]
    # after one turn the crank is back where it started (its angle, within rounding)
    assert float(rows[0][5]) == pytest.approx(math.pi / 4, abs=1e-9)


def test_a_failed_case_is_a_row_with_its_message(tmp_path):
    base = mbody.loads(driven_text(), "driven.yaml")
    job = job_of(base, ["bodies.rod.mass=-0.5:1.5:3"], Settings("solve"))
    _, rows = run_here(job, tmp_path / "f.csv", workers=0)
    assert len(rows) == 3
    assert "bodies.rod.mass" in rows[0][-2] and "expected a number > 0" in rows[0][-2]
    assert all(c == "" for c in rows[0][2:-2])
    assert rows[1][-2] == "" == rows[2][-2]


def test_an_interrupted_sweep_resumes(tmp_path):
    """Interrupted after its first chunk: the rows so far are in the journal; the same
    sweep again runs only the others, and the output holds every case once, equal to an
    uninterrupted run."""
    base = mbody.loads(driven_text(), "driven.yaml")
    specs = ["drivers.motor.speed=60:240:4", "bodies.rod.mass=0.3:1.2:3"]
    job = job_of(base, specs, Settings("solve"))
    out = tmp_path / "resume.csv"
    results = Results(out, columns(base, job.settings), job.grid, record(job.settings, base))

    def stop(rows):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        cluster.run(job, range(12), results, workers=0, chunk=5, progress=False,
                    on_chunk=stop)
    assert not out.exists() and results.journal.exists()
    again = Results(out, columns(base, job.settings), job.grid, record(job.settings, base))
    assert sorted(again.done) == list(range(5))
    ran = []
    cluster.run(job, [k for k in range(12) if k not in again.rows], again, workers=0,
                chunk=5, progress=False, on_chunk=lambda rows: ran.extend(rows.indices))
    again.finish()
    assert ran == list(range(5, 12)) and not again.journal.exists()
    _, rows = read(out)
    _, whole = run_here(job_of(base, specs, Settings("solve")), tmp_path / "whole.csv",
                        workers=0)
    assert rows == whole
    # another sweep's file is refused, not mixed in
    other = job_of(base, ["drivers.motor.speed=70:240:4", "bodies.rod.mass=0.3:1.2:3"],
                   Settings("solve"))
    with pytest.raises(MbodyError, match="another sweep"):
        Results(out, columns(base, other.settings), other.grid, record(other.settings, base))


def test_random_samples_are_seeded_and_in_range():
    g = parse_grid(["bodies.rod.mass=0.3:1.2", "joints.P.axis.1=0,0.1"], samples=50,
                   seed=4)
    again = parse_grid(["bodies.rod.mass=0.3:1.2", "joints.P.axis.1=0,0.1"], samples=50,
                       seed=4)
    nums = [g.numbers(k) for k in range(50)]
    assert nums == [again.numbers(k) for k in range(50)]
    assert all(0.3 <= m < 1.2 and a in (0, 0.1) for m, a in nums)
    assert len({a for _, a in nums}) == 2
    other = parse_grid(["bodies.rod.mass=0.3:1.2"], samples=50, seed=5)
    assert [other.numbers(k)[0] for k in range(50)] != [m for m, _ in nums]


@pytest.mark.parametrize(("specs", "kw", "pattern"), [
    (["bodies.rod.mass=0.3:1.2"], {}, "expected START:STOP:COUNT"),
    (["bodies.rod.mass=0.3:1.2:10"], {"samples": 5}, "expected START:STOP,"),
    (["bodies.rod.mass=0.3:x:10"], {}, "'x' is not a number"),
    (["bodies.rod.mass=0.3:1.2:0"], {}, "a count of at least 1"),
    (["drivers.motor.speed=10 rpm:20:3"], {}, "different units"),
    (["bodies.rod.mass=2"], {}, "varies at least one value"),
    (["bodies.rod.mass=1:2:3", "bodies.rod.mass=1:2:3"], {},
     r"^values\['bodies.rod.mass'\] is given twice$"),  # from Python: the keyword's spelling
    (["bodies.rod.mass=1,,2"], {}, "an empty value"),
    (["bodies.rod.mass=0:1:20000", "bodies.crank.mass=0:1:20000"], {}, "at most"),
])
def test_bad_grids_are_refused(specs, kw, pattern):
    with pytest.raises(MbodyError, match=pattern):
        parse_grid(specs, **kw)


def test_units_in_a_range_are_read_as_the_file_reads_them():
    g = parse_grid(["drivers.motor.speed=600 rpm:1200 rpm:2"])
    assert g.values(1) == {"drivers.motor.speed": "1200.0 rpm"}
    base = mbody.loads(driven_text(), "driven.yaml")
    assert base.with_values(g.values(1)).initial.omega[0, 2] == pytest.approx(
        1200 * 2 * math.pi / 60, rel=1e-12)


def test_the_command_line(driven_file, tmp_path):
    """A bad path is refused before any case runs (exit 2, located, did-you-mean); a
    sweep in this process writes its CSV; Parquet holds the same numbers."""
    p = mbody_cli("sweep", str(driven_file), "--set", "bodies.rdo.mass=0.3:1.2:3",
                  "--out", str(tmp_path / "x.csv"), "--workers", "0", "--quiet")
    assert p.returncode == 2 and "did you mean 'rod'" in p.stderr
    assert f"{driven_file}:" in p.stderr and not (tmp_path / "x.csv").exists()
    p = mbody_cli("sweep", str(driven_file), "--set", "bodies.rod.mass=0.3:1.2:3",
                  "--out", str(tmp_path / "x.txt"), "--workers", "0")
    assert p.returncode == 2 and ".csv or .parquet" in p.stderr
    p = mbody_cli("sweep", str(driven_file), "--set", "bodies.rod.mass=0.3:1.2:3",
                  "--run", "kinematics", "--out", str(tmp_path / "x.csv"), "--workers", "0")
    assert p.returncode == 2 and "needs --t-end" in p.stderr

    def sweep_to(out: str) -> None:
        p = mbody_cli("sweep", str(driven_file), "--set", "bodies.rod.mass=0.3:1.2:3",
                      "--set", "gravity=[0, -1.62]", "--out", str(tmp_path / out),
                      "--workers", "0", "--quiet")
        assert p.returncode == 0, p.stderr
        assert "wrote" in p.stdout and "3 cases" in p.stdout

    sweep_to("c.csv")
    header, rows = read(tmp_path / "c.csv")
    # the fixed value (not a column) was set: the rod's weight in O.Fy on the Moon
    model = mbody.load(driven_file).with_values({"gravity": [0, -1.62],
                                                 "bodies.rod.mass": 0.3})
    assert float(rows[0][header.index("reaction:O.Fy")]) == \
        mbody.assemble(model).solve().reactions["O.Fy"]
    pq = pytest.importorskip("pyarrow.parquet")  # the sweep extra
    sweep_to("c.parquet")
    table = pq.read_table(tmp_path / "c.parquet")
    assert table.column_names == header
    for i, name in enumerate(header[:-2]):
        assert floats([r[i] for r in rows]).tolist() == table.column(name).to_pylist()
    for name in ("error", "settings"):  # text
        assert table.column(name).to_pylist() == [r[header.index(name)] for r in rows]


def test_modes_run_gives_the_pendulums_frequency(tmp_path):
    """The physical pendulum held at 30 deg, linearised there: omega^2 = g a cos(30 deg) /
    ((w^2 + L^2)/12 + a^2) whatever its mass (the mass cancels): both rows give it, and
    each equals mbody.linearize of its case run alone."""
    pend = mbody.load(ROOT / "models" / "pendulum.yaml")
    job = Job(pend.source, parse_grid(["bodies.rod.mass=1:3:2"]), Settings("modes"),
              uuid.uuid4().hex)
    results = Results(tmp_path / "m.csv", columns(pend, job.settings), job.grid,
                      record(job.settings, pend))
    cluster.run(job, [0, 1], results, workers=0, progress=False)
    results.finish()
    header, rows = read(tmp_path / "m.csv")
    f, m = header.index("frequency:1"), header.index("bodies.rod.mass")
    a, w, L = 0.5, 0.05, 1.0
    closed = np.sqrt(9.81 * a * np.cos(np.radians(30.0)) / ((w**2 + L**2) / 12 + a**2))
    for row, mass in zip(rows, (1.0, 3.0), strict=True):
        assert float(row[m]) == mass
        assert float(row[f]) == pytest.approx(closed, rel=1e-9)
        lin = mbody.linearize(pend.with_values({"bodies.rod.mass": mass}))
        assert float(row[f]) == float(lin.frequencies[0])


def test_runs_match_the_command_names():
    from mbody.cli.sweep import RUN_NAMES

    assert set(RUN_NAMES) == set(RUNS)


# -- Dask ------------------------------------------------------------------------------

def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(predicate, seconds: float, what: str) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if predicate():
            return
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}")


@pytest.fixture
def dask_cluster(tmp_path):
    """A real scheduler and two workers (no nannies: a killed worker stays dead), started
    here as the `dask` command starts them, on 127.0.0.1; stopped at the end."""
    pytest.importorskip("distributed")
    from distributed import Client

    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    logs = [open(tmp_path / f"{n}.log", "w") for n in ("scheduler", "w1", "w2")]  # noqa: SIM115
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--host",
                               "127.0.0.1", "--port", str(port), "--no-dashboard",
                               "--dashboard-address", "127.0.0.1:0"],
                              stdout=logs[0], stderr=subprocess.STDOUT, env=env)]
    try:
        wait_for(lambda: _listening(port), 120, "the scheduler")
        for i in (1, 2):
            procs.append(subprocess.Popen(
                [sys.executable, "-m", "dask", "worker", address, "--no-nanny", "--nthreads",
                 "1", "--host", "127.0.0.1", "--no-dashboard", "--dashboard-address",
                 "127.0.0.1:0", "--name", f"w{i}"],
                stdout=logs[i], stderr=subprocess.STDOUT, env=env))
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        yield address, procs
    finally:
        for p in reversed(procs):  # the workers, then the scheduler
            if p.poll() is None:
                p.terminate()
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        for f in logs:
            f.close()


def _listening(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(1.0)
        return s.connect_ex(("127.0.0.1", port)) == 0


def test_a_worker_killed_mid_run_loses_and_repeats_nothing(dask_cluster, tmp_path):
    """Two workers; once chunks are coming back, worker w1 is killed (SIGKILL) while the
    scheduler has a chunk running on it. Dask runs that chunk again on w2: every case is
    in the output exactly once (the lost chunk's cases from w2), with the same numbers as
    a run in this process."""
    from distributed import Client

    address, procs = dask_cluster
    base = mbody.loads(driven_text(), "driven.yaml")
    specs = ["drivers.motor.speed=60:240:6", "bodies.rod.mass=0.3:1.2:3"]
    # a chunk of one case, some 0.1 s of work: both workers busy whenever one is killed
    settings = Settings("kinematics", revolutions=0.5, steps=20000)
    job = job_of(base, specs, settings)
    results = Results(tmp_path / "killed.csv", columns(base, settings), job.grid,
                      record(settings, base))
    by_case: dict[int, list[str]] = {}
    victim = procs[1]
    lost: list[str] = []
    with Client(address, timeout=60, set_as_default=False) as watcher:
        names = {w["name"]: a for a, w in watcher.scheduler_info()["workers"].items()}

        def kill_once(rows):
            for k in rows.indices:
                by_case.setdefault(k, []).append(rows.worker)
            if victim.poll() is not None or len(by_case) < 3:
                return
            wait_for(lambda: watcher.processing().get(names["w1"]), 60, "a chunk on w1")
            lost.extend(watcher.processing()[names["w1"]])
            victim.send_signal(signal.SIGKILL)
            victim.wait(timeout=20)

        report = cluster.run(job, range(len(job.grid)), results, scheduler=address,
                             chunk=1, progress=False, on_chunk=kill_once)
    results.finish()
    assert victim.returncode == -signal.SIGKILL and lost
    _, rows = read(tmp_path / "killed.csv")
    assert [int(r[0]) for r in rows] == list(range(len(job.grid)))  # each once, in order
    assert all(len(w) == 1 for w in by_case.values()) and len(by_case) == len(job.grid)
    assert all(r[-2] == "" for r in rows) and report.lost == 0
    survivors = {w for ws in by_case.values() for w in ws}
    for key in lost:  # the killed worker's chunk (one case) was run again, by the other
        k = int(str(key).rsplit("-", 1)[1])
        assert by_case[k] != [] and len(by_case[k]) == 1
    assert len(survivors) == 2  # rows came from both workers
    _, here = run_here(job_of(base, specs, settings), tmp_path / "here.csv", workers=0)
    for a, b in zip(rows, here, strict=True):
        assert a[:3] == b[:3] and a[-1] == b[-1]
        x, y = floats(a[3:-2]), floats(b[3:-2])
        assert np.abs(x - y).max() <= 1e-12 * np.abs(y).max()


def test_the_local_cluster_gives_the_numbers_of_this_process(driven_file, tmp_path):
    """The command's default, a local cluster it starts and stops (two worker processes
    here), against the same sweep in this process (an existing cluster: the test above):
    the same rows."""
    pytest.importorskip("distributed")
    specs = ["drivers.motor.speed=60:240:3", "bodies.rod.mass=0.3:1.2:4"]
    out = tmp_path / "local.csv"
    p = mbody_cli("sweep", str(driven_file), "--set", specs[0], "--set", specs[1], "--run",
                  "kinematics", "--t-end", "1 rev", "--steps", "50", "--quiet", "--chunk",
                  "3", "--workers", "2", "--out", str(out))
    assert p.returncode == 0, p.stderr
    assert "on a local cluster of 2 worker processes" in p.stdout
    base = mbody.loads(driven_text(), "driven.yaml")
    job = job_of(base, specs, Settings("kinematics", revolutions=1.0, steps=50))
    header, here = run_here(job, tmp_path / "here.csv", workers=0)
    assert read(out)[0] == header
    for a, b in zip(read(out)[1], here, strict=True):
        x, y = floats(a[3:-2]), floats(b[3:-2])
        assert a[:3] == b[:3] and np.abs(x - y).max() <= 1e-12 * np.abs(y).max()
        assert a[-1] == b[-1]  # the same settings recorded, wherever the case ran


def test_simulate_rows_are_the_cases_simulated_one_by_one(tmp_path):
    """Each row: mbody.simulate of the case's model, its last sample's position
    coordinates and the largest |value| of each reaction over the samples; a pendulum's
    swing does not depend on its mass, its pin's load is proportional to it."""
    base = mbody.load(ROOT / "models" / "pendulum.yaml")
    job = Job(base.source, parse_grid(["bodies.rod.mass=1:3:3"]),
              Settings("simulate", t_end=0.5, fps=40), uuid.uuid4().hex)
    results = Results(tmp_path / "s.csv", columns(base, job.settings), job.grid,
                      record(job.settings, base))
    cluster.run(job, range(3), results, workers=0, progress=False)
    results.finish()
    header, rows = read(tmp_path / "s.csv")
    for row in rows:
        model = base.with_values({"bodies.rod.mass": float(row[1])})
        traj = mbody.simulate(model, t_end=0.5, fps=40)
        last = traj.state(len(traj.t) - 1)
        y = np.concatenate((last.position.ravel(), last.quaternion.ravel()))[None]
        peaks = np.abs(traj.reactions).max(axis=0)
        want = [*final_values(model, y)[0],
                *(peaks[list(traj.reaction_labels).index(r)] for r in model.reactions)]
        assert floats(row[2:-2]).tolist() == want
    finals = np.array([floats(r[2:5]) for r in rows])
    assert np.abs(finals - finals[0]).max() <= 1e-12
    loads = np.array([floats(r[5:-2]) for r in rows])
    assert np.allclose(loads / loads[0], np.array([[1.0], [2.0], [3.0]]), rtol=1e-9)


def test_what_a_newcomer_got_wrong_is_refused_or_said(tmp_path):
    """A kinematics sweep of a model that is not fully driven is refused as `mbody
    kinematics` refuses it (it had given rows of a pendulum that never moved); a range
    of count 1 across two values is refused (it had run START alone); a sweep where every
    case fails exits 1 with the first case's message."""
    def sweep(*args):
        return subprocess.run([sys.executable, "-m", "mbody", "sweep", *args, "--workers", "0",
                               "--quiet"], capture_output=True, text=True, cwd=tmp_path)

    p = sweep(str(ROOT / "models" / "double_pendulum.yaml"), "--set",
              "bodies.upper.mass=1:2:2", "--run", "kinematics", "--t-end", "0.1", "--out",
              "y.csv")
    assert p.returncode == 2 and "is not fully driven" in p.stderr
    assert not (tmp_path / "y.csv").exists()
    p = sweep(str(SLIDER), "--set", "bodies.rod.mass=0.4:0.8:1", "--out", "z.csv")
    assert p.returncode == 2 and "a count of 1 is one value" in p.stderr
    p = sweep(str(SLIDER), "--set", "joints.P.axis=0:1:2", "--out", "f.csv")
    assert p.returncode == 1 and "every case failed; case 0:" in p.stderr
    header, rows = read(tmp_path / "f.csv")
    assert len(rows) == 2 and all(r[header.index("error")] for r in rows)


def test_a_local_cluster_that_cannot_start_is_a_clean_error(tmp_path, monkeypatch):
    """'Nanny failed to start' on a busy machine (the CLI fuzzer met it) is an MbodyError
    that says what to do, not an internal error; the rows already run are kept."""
    distributed = pytest.importorskip("distributed")

    def failing(*args, **kwargs):
        raise RuntimeError("Nanny failed to start.")

    monkeypatch.setattr(distributed, "LocalCluster", failing)
    import dask.distributed  # re-exports the name: patched there too, where mbody reads it

    monkeypatch.setattr(dask.distributed, "LocalCluster", failing)
    base = mbody.load(SLIDER)
    job = Job(base.source, parse_grid(["bodies.rod.mass=1:2:3"]), Settings("solve"),
              uuid.uuid4().hex)
    results = Results(tmp_path / "c.csv", columns(base, job.settings), job.grid,
                      record(job.settings, base))
    with pytest.raises(MbodyError, match=r"could not start a local Dask cluster of 2 .*"
                                         r"workers=0"):  # Python's spelling (here)
        cluster.run(job, [0, 1, 2], results, workers=2, progress=False)

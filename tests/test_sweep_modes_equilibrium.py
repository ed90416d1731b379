"""A sweep's ``modes`` run says what `mbody modes` says with its frequencies: the growth
rates of the modes that grow (``growth:k``), whether the state linearised about is an
equilibrium (``steady``) and its verdict (``stable``), each true or false; and,
with ``--equilibrium`` (`Settings.equilibrium`), it linearises each case about the static
equilibrium nearest its initial pose, as ``mbody modes --equilibrium`` does.

The shipped pendulum (a 1 m x 50 mm uniform rod pinned at its top end, released from 30
degrees) is the closed form: about its rest position ω² = m g d / I_O with d = L/2 and
I_O = m ((w² + L²)/12 + d²), whatever its mass; at the 30-degree release the tangent
system's is ω² = m g d cos 30° / I_O (not an equilibrium: no verdict). Held near upright
it finds the inverted equilibrium: steady, unstable, no oscillation, a mode growing at
sqrt(g d / k_O²). A free body spinning about its intermediate axis (the course's worked
example 2, principal inertias 2, 3, 4) is unstable too: its growth rate is Euler's closed
form."""

from __future__ import annotations

import csv
import math
import os
import subprocess
import sys
import uuid
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.errors import MbodyError
from mbody.sweep import cluster
from mbody.sweep.grid import parse_grid
from mbody.sweep.record import record
from mbody.sweep.runs import Job, Settings, check_settings, columns
from mbody.sweep.table import Results

ROOT = Path(__file__).resolve().parent.parent
PENDULUM = ROOT / "models" / "pendulum.yaml"
G, D, W, L = 9.81, 0.5, 0.05, 1.0
"""The pendulum's gravity (m/s^2), pin-to-centre distance, the rod's width and length (m)."""
K_O2 = (W**2 + L**2) / 12 + D**2
"""I_O / m (m^2): the rod's radius of gyration about the pin, squared."""


def at_rest(g: float = G) -> float:
    """ω (rad/s) of small swings about the hanging rest position: sqrt(m g d / I_O)."""
    return math.sqrt(g * D / K_O2)


def released(g: float = G, angle_deg: float = 30.0) -> float:
    """The tangent system's ω (rad/s) at the release angle: sqrt(m g d cos θ / I_O)."""
    return math.sqrt(g * D * math.cos(math.radians(angle_deg)) / K_O2)


def read(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def sweep_here(model: mbody.Model, specs: list[str], settings: Settings, out: Path
               ) -> tuple[list[str], list[dict[str, str]]]:
    """The sweep run in this process through the Python API; rows as {column: cell}."""
    job = Job(model.source, parse_grid(specs), settings, uuid.uuid4().hex)
    results = Results(out, columns(model, settings), job.grid, record(settings, model))
    cluster.run(job, range(len(job.grid)), results, workers=0, progress=False)
    results.finish()
    header, rows = read(out)
    return header, [dict(zip(header, r, strict=True)) for r in rows]


def mbody_cli(*argv: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "mbody", *argv], capture_output=True,
                          text=True, cwd=cwd, timeout=600, env=env)


def error_bound(lin: mbody.Linearization) -> float:
    """How far the linearisation's frequency may be from the exact one (rad/s)."""
    return float(lin.eigenvalue_errors.max())


def test_about_the_initial_state_the_rows_say_it_is_not_an_equilibrium(tmp_path):
    """The 30-degree release is not at rest: the rows carry the tangent system's frequency
    (as `mbody modes` prints it), steady false and no verdict, as `mbody.linearize` says."""
    pend = mbody.load(PENDULUM)
    header, rows = sweep_here(pend, ["bodies.rod.mass=1:3:3"], Settings("modes"),
                              tmp_path / "m.csv")
    assert header == ["case", "bodies.rod.mass", "frequency:1", "growth:1", "steady", "stable",
                      "error", "settings"]
    for row in rows:
        case = pend.with_values({"bodies.rod.mass": float(row["bodies.rod.mass"])})
        lin = mbody.linearize(case)
        assert not lin.steady and lin.stable is None
        assert row["steady"] == "false" and row["stable"] == "" and row["error"] == ""
        assert row["growth:1"] == ""  # the tangent system's one mode oscillates
        assert float(row["frequency:1"]) == float(lin.frequencies[0])
        assert float(row["frequency:1"]) == pytest.approx(released(), abs=error_bound(lin))


def test_about_the_equilibrium_the_rows_give_the_natural_frequency(tmp_path):
    """With equilibrium: ω = sqrt(m g d / I_O) for every mass (the mass cancels), steady
    and stable, the rod hanging straight down (its centre d below the pin); each row is
    `mbody.linearize` about `mbody.equilibrium` of its case, as `mbody modes
    --equilibrium` computes it."""
    pend = mbody.load(PENDULUM)
    header, rows = sweep_here(pend, ["bodies.rod.mass=1:3:3"],
                              Settings("modes", equilibrium=True), tmp_path / "e.csv")
    assert header == ["case", "bodies.rod.mass", "frequency:1", "growth:1", "steady", "stable",
                      "equilibrium:rod.x", "equilibrium:rod.y", "equilibrium:rod.theta",
                      "error", "settings"]
    for row in rows:
        case = pend.with_values({"bodies.rod.mass": float(row["bodies.rod.mass"])})
        rest = mbody.equilibrium(case)
        lin = mbody.linearize(case, rest)
        assert lin.steady and lin.stable is True
        assert row["steady"] == "true" and row["stable"] == "true" and row["error"] == ""
        assert row["growth:1"] == ""
        assert float(row["frequency:1"]) == float(lin.frequencies[0])
        assert float(row["frequency:1"]) == pytest.approx(at_rest(), abs=error_bound(lin))
        assert float(row["equilibrium:rod.x"]) == float(rest.position[0, 0])
        # Newton's method stops when the gravity torque is below 1e-8 of its terms
        assert abs(float(row["equilibrium:rod.x"])) <= 1e-8 * D
        assert float(row["equilibrium:rod.y"]) == pytest.approx(-D, abs=1e-8 * D)
        assert abs(float(row["equilibrium:rod.theta"])) <= 1e-8


def test_the_frequency_about_the_equilibrium_goes_as_the_square_root_of_gravity(tmp_path):
    """Earth, Mars and the Moon: ω = sqrt(g d / k_O²) in each row (listed values)."""
    pend = mbody.load(PENDULUM)
    _, rows = sweep_here(pend, ["gravity.1=-9.81,-3.72,-1.62"],
                         Settings("modes", equilibrium=True), tmp_path / "g.csv")
    assert [float(r["gravity.1"]) for r in rows] == [-9.81, -3.72, -1.62]
    for row in rows:
        g = -float(row["gravity.1"])
        lin = mbody.linearize(pend.with_values({"gravity.1": -g}),
                              mbody.equilibrium(pend.with_values({"gravity.1": -g})))
        assert float(row["frequency:1"]) == pytest.approx(at_rest(g), abs=error_bound(lin))


INVERTED = """model: inverted-pendulum
dimension: 2
gravity: [0, -9.81]
bodies:
  - {name: rod, mass: 2.0, shape: {box: [0.05, 1.0]}, angle: 170 deg,
     position: [0.08682408883346517, 0.49240387650610395]}
joints:
  - {name: O, type: revolute, parent: ground, child: rod, at: [0, 0]}
"""


def test_an_unstable_equilibrium_is_said_unstable(tmp_path):
    """The rod held 10 degrees from upright: the nearest equilibrium is upright, steady
    and unstable (λ = ±sqrt(g d / k_O²), real: no oscillation, so no frequency), and the
    row gives the rate at which it falls, growth:1 = sqrt(g d / k_O²) (F9 of review R4:
    the growth rate appeared nowhere)."""
    path = tmp_path / "inverted.yaml"
    path.write_text(INVERTED)
    model = mbody.load(path)
    _, rows = sweep_here(model, ["bodies.rod.mass=1,2"], Settings("modes", equilibrium=True),
                         tmp_path / "i.csv")
    lin = mbody.linearize(model, mbody.equilibrium(model))
    for row in rows:
        assert row["error"] == "" and row["frequency:1"] == ""
        assert row["steady"] == "true" and row["stable"] == "false"
        assert float(row["growth:1"]) == pytest.approx(at_rest(), abs=error_bound(lin))
        assert float(row["equilibrium:rod.y"]) == pytest.approx(D, abs=1e-8 * D)
        assert abs(abs(float(row["equilibrium:rod.theta"])) - math.pi) <= 1e-8
    growth = max(m.eigenvalue.real for m in lin.modes)
    assert growth == pytest.approx(at_rest(), abs=error_bound(lin))


def test_a_case_without_an_equilibrium_is_a_row_with_mbody_equilibriums_message(tmp_path):
    """A constant torque on a free wheel never balances: the case's row says so, in the
    words of mbody.equilibrium."""
    text = ("model: wheel\ndimension: 2\ngravity: [0, -9.81]\nbodies:\n"
            "  - {name: wheel, mass: 1.0, inertia: 0.1, position: [0, 0]}\n"
            "loads:\n  - {name: drive, type: torque, body: wheel, torque: 1.0}\n"
            "joints:\n  - {name: O, type: revolute, parent: ground, child: wheel, at: [0, 0]}\n")
    path = tmp_path / "wheel.yaml"
    path.write_text(text)
    model = mbody.load(path)
    _, rows = sweep_here(model, ["bodies.wheel.mass=1,2"],
                         Settings("modes", equilibrium=True), tmp_path / "w.csv")
    with pytest.raises(MbodyError) as exc:
        mbody.equilibrium(model)
    for row in rows:
        assert row["error"] == str(exc.value)
        assert row["steady"] == "" and row["stable"] == ""


def test_equilibrium_goes_with_the_modes_run_only():
    pend = mbody.load(PENDULUM)
    with pytest.raises(MbodyError, match="^equilibrium=True goes with run='modes'"):
        check_settings(pend, Settings("solve", equilibrium=True))
    check_settings(pend, Settings("modes", equilibrium=True))


def test_the_command_line(tmp_path):
    """`mbody sweep --run modes` warns, on standard error, that the initial states are not
    equilibria and names --equilibrium; with it the CSV holds the natural frequency;
    --equilibrium with another run is refused (exit 2, no
    traceback); an output of the other kind of modes sweep is refused, never mixed in."""
    plain = tmp_path / "plain.csv"
    p = mbody_cli("sweep", str(PENDULUM), "--set", "bodies.rod.mass=1:3:3", "--run", "modes",
                  "--workers", "0", "--quiet", "--out", str(plain))
    assert p.returncode == 0, p.stderr
    assert "warning: the initial state of 3 of 3 cases is not an equilibrium" in p.stderr
    assert "--equilibrium linearises each about the static equilibrium" in p.stderr
    header, rows = read(plain)
    assert [r[header.index("steady")] for r in rows] == ["false"] * 3

    p = mbody_cli("sweep", str(PENDULUM), "--set", "bodies.rod.mass=1:3:3", "--run", "modes",
                  "--equilibrium", "--workers", "0", "--quiet", "--out", str(plain))
    assert p.returncode == 2 and "holds another sweep's results" in p.stderr

    header, rows = equilibrium_sweep(tmp_path / "eq.csv")
    lin = mbody.linearize(mbody.load(PENDULUM), mbody.equilibrium(mbody.load(PENDULUM)))
    for r in rows:
        assert float(r[header.index("frequency:1")]) == pytest.approx(
            at_rest(), abs=error_bound(lin))
        assert r[header.index("stable")] == "true"

    p = mbody_cli("sweep", str(PENDULUM), "--set", "bodies.rod.mass=1:3:3", "--equilibrium",
                  "--workers", "0", "--out", str(tmp_path / "s.csv"))
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert "--equilibrium goes with --run modes" in p.stderr
    assert not (tmp_path / "s.csv").exists()


def equilibrium_sweep(out) -> tuple[list[str], list[list[str]]]:
    """The equilibrium modes sweep of the pendulum's three masses into `out` (.csv or
    .parquet), without a warning; its CSV rows when `out` is one."""
    p = mbody_cli("sweep", str(PENDULUM), "--set", "bodies.rod.mass=1:3:3", "--run",
                  "modes", "--equilibrium", "--workers", "0", "--quiet", "--out", str(out))
    assert p.returncode == 0, p.stderr
    assert "warning" not in p.stderr
    return read(out) if str(out).endswith(".csv") else ([], [])


def test_the_parquet_output_holds_the_csvs_numbers(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")  # the sweep extra
    header, rows = equilibrium_sweep(tmp_path / "eq.csv")
    equilibrium_sweep(tmp_path / "eq.parquet")
    table = pq.read_table(tmp_path / "eq.parquet")
    assert table.column_names == header
    assert table.column("frequency:1").to_pylist() == [float(r[header.index("frequency:1")])
                                                       for r in rows]
    assert all(math.isnan(x) for x in table.column("growth:1").to_pylist())
    for name in ("steady", "stable"):  # booleans, as the CSV's true and false
        assert str(table.column(name).type) == "bool"
        assert table.column(name).to_pylist() == [r[header.index(name)] == "true"
                                                  for r in rows] == [True] * 3


def test_a_local_cluster_gives_the_numbers_of_this_process(tmp_path):
    """The equilibrium modes sweep on two worker processes: the rows of this process."""
    pytest.importorskip("distributed")
    out = tmp_path / "local.csv"
    p = mbody_cli("sweep", str(PENDULUM), "--set", "bodies.rod.mass=1:3:3", "--set",
                  "gravity.1=-9.81,-1.62", "--run", "modes", "--equilibrium", "--workers",
                  "2", "--chunk", "2", "--quiet", "--out", str(out))
    assert p.returncode == 0, p.stderr
    assert "on a local cluster of 2 worker processes" in p.stdout
    header, here = sweep_here(mbody.load(PENDULUM),
                              ["bodies.rod.mass=1:3:3", "gravity.1=-9.81,-1.62"],
                              Settings("modes", equilibrium=True), tmp_path / "here.csv")
    got_header, got = read(out)
    assert got_header == header and len(got) == len(here) == 6
    flags = [header.index("steady"), header.index("stable")]
    numbers = [i for i in range(1, len(header) - 2) if i not in flags]
    for a, b in zip(got, here, strict=True):
        assert [a[i] for i in flags] == [b[header[i]] for i in flags] == ["true"] * 2
        x = np.array([float(a[i]) if a[i] else np.nan for i in numbers])
        y = np.array([float(b[header[i]]) if b[header[i]] else np.nan for i in numbers])
        assert np.array_equal(np.isnan(x), np.isnan(y))
        x, y = x[~np.isnan(x)], y[~np.isnan(y)]
        assert a[0] == b["case"] and a[-2] == b["error"] == ""
        assert a[-1] == b["settings"]
        # the same computation in another process: equal up to its rounding
        assert np.abs(x - y).max() <= 1e-12 * np.abs(y).max()


SPINS = {"bodies.body.angular_velocity": [[2, 0, 0], [0, 2, 0], [0, 0, 2]]}
"""The course's worked example 2 (principal inertias 2, 3, 4 kg m², no torque) spun at
2 rad/s about each principal axis in turn."""


def test_a_spin_about_the_intermediate_axis_grows_at_eulers_rate(tmp_path):
    """F9 of review R4: about the intermediate axis the row had six empty frequency:
    columns and stable 0.0, and its growth rate, 0.707 1/s, appeared nowhere. Euler's
    equations linearised about a steady spin Ω about axis a: λ² = Ω² (I_a − I_b)(I_c − I_a)
    / (I_b I_c); about the largest or the smallest axis a wobble at |λ|, about the
    intermediate one a real λ > 0, a small motion growing as e^(λ t)."""
    model = mbody.load(ROOT / "models" / "seed_example_2.yaml")
    result = mbody.run_sweep(model, SPINS, tmp_path / "spin.csv", run="modes", workers=0)
    spin, (i1, i2, i3) = 2.0, (2.0, 3.0, 4.0)
    wobble_1 = spin * math.sqrt((i2 - i1) * (i3 - i1) / (i2 * i3))   # 0.8165 rad/s
    wobble_3 = spin * math.sqrt((i3 - i1) * (i3 - i2) / (i1 * i2))   # 1.1547 rad/s
    grows_2 = spin * math.sqrt((i2 - i1) * (i3 - i2) / (i1 * i3))    # 1/sqrt(2) 1/s
    at = result.header.index
    assert [r[at("steady")] for r in result.rows] == ["true"] * 3
    assert [r[at("stable")] for r in result.rows] == ["true", "false", "true"]
    assert result.column("stable").tolist() == [1.0, 0.0, 1.0]
    assert result.warnings == [] and result.failed == 0
    growth = [c for c in result.header if c.startswith("growth:")]
    assert growth == [f"growth:{k}" for k in range(1, 7)]  # one per coordinate
    for k, values in enumerate(SPINS["bodies.body.angular_velocity"]):
        lin = mbody.linearize(model.with_values({"bodies.body.angular_velocity": values}))
        bound = error_bound(lin)
        rates = [result.column(c)[k] for c in growth]
        if k == 1:
            assert math.isnan(result.column("frequency:1")[k])
            assert rates[0] == pytest.approx(grows_2, abs=bound)
            assert all(math.isnan(r) for r in rates[1:])
        else:
            assert result.column("frequency:1")[k] == pytest.approx(
                (wobble_1, None, wobble_3)[k], abs=bound)
            assert all(math.isnan(r) for r in rates)


def test_a_csv_reader_reads_true_and_false_as_booleans(tmp_path):
    """steady and stable are written true or false (they were 1.0 and 0.0): pyarrow's CSV
    reader (the sweep extra) types them bool, empty cells as nulls; the csv module and
    SweepResult.column read them too."""
    pcsv = pytest.importorskip("pyarrow.csv")
    result = mbody.run_sweep(PENDULUM, {"gravity.1": [-9.81, -1.62]}, tmp_path / "g.csv",
                             run="modes", workers=0)  # about the release: no verdict
    table = pcsv.read_csv(tmp_path / "g.csv")
    assert str(table.schema.field("steady").type) == "bool"
    assert table.column("steady").to_pylist() == [False, False]
    assert table.column("stable").null_count == 2
    header, rows = read(tmp_path / "g.csv")
    assert [r[header.index("steady")] for r in rows] == ["false", "false"]
    assert result.column("steady").tolist() == [0.0, 0.0]
    assert np.isnan(result.column("stable")).all()

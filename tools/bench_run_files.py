"""Benchmark: reading run files (`Trajectory.load`) is linear in what they hold, and a
hostile file is refused in milliseconds whatever it claims.

Prints three tables:

- good runs of N spatial bodies over K samples (saved by `Trajectory.save`, compressed):
  the bytes on disk and once inflated, the best load time, and the time per inflated MiB,
  which stays about constant as the run grows (linear reading);
- the review's hostile files (R1, B3/B4), built here: a 2 MB zip bomb whose t.npy inflates
  to 2 GiB, a header that claims 10^15 samples in 16 bytes, an `info` nested 10 000 deep,
  the same bomb as a .mat export (`mbody.load_export`): the time to the refusal and the
  peak memory Python and numpy held meanwhile (tracemalloc), with the message's start;
  and review R3's: 10^12 body names of 0 bytes each in a 5 kB run (S1), a string of
  escaped quotes that never ends as a run's `info` and as a JSON export (S2);
- the nesting bound every JSON text read back goes through (`jsontext.nesting`: a run's
  `info`, `shapes` and `colors`, JSON exports, CSV `info.csv` cells): its time against
  the text's size, for JSON like an export's and for that string of escaped quotes; the
  time per MB stays about constant (linear).

    python tools/bench_run_files.py [--repeat 3] [--largest 200000]

Before the bounds (mbody of review R1), the bomb took 14 s and 2.2 GB of memory to be
refused, the liar and the nesting ended in a MemoryError or RecursionError (exit 70).
Before review R3, the names of 0 bytes took 106 s and 3.6 GB to a MemoryError (exit 70),
and the nesting bound was quadratic on escaped quotes: 64 kB of them took 21 s.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from crafted_files import mat_bomb, npy_header, npz_bomb, npz_members, npz_with  # noqa: E402
from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.errors import MbodyError  # noqa: E402
from mbody.simulate.trajectory import Trajectory  # noqa: E402
from mbody.util.jsontext import nesting  # noqa: E402

MIB = 1 << 20


def tumbling(n: int, K: int, seed: int = 0) -> Trajectory:
    """n free bodies over K samples, each drifting and spinning (random rates): data that
    compresses as little as a real run's."""
    rng = np.random.default_rng(seed)
    t = np.arange(K) / 60.0
    v, w = rng.uniform(-1, 1, (n, 3)), rng.uniform(-2, 2, (n, 3))
    pos = t[:, None, None] * v + rng.uniform(-5, 5, (n, 3))
    angle = t[:, None] * np.linalg.norm(w, axis=1)
    axis = w / np.linalg.norm(w, axis=1)[:, None]
    quat = np.concatenate((np.cos(angle / 2)[..., None],
                           np.sin(angle / 2)[..., None] * axis), axis=2)
    return Trajectory(t, pos, np.broadcast_to(v, pos.shape).copy(), quat,
                      np.broadcast_to(w, pos.shape).copy(), tuple(f"b{i}" for i in range(n)),
                      3, model_name="tumbling", mass=np.ones(n),
                      inertia=np.broadcast_to(np.eye(3), (n, 3, 3)).copy(),
                      gravity=np.zeros(3))


def inflated(path: Path) -> int:
    with zipfile.ZipFile(path) as z:
        return sum(i.file_size for i in z.infolist())


def good_runs(folder: Path, repeat: int, largest: int) -> None:
    print("good runs (Trajectory.load): reading time against what the run holds")
    print(f"{'bodies x samples':>18} {'on disk':>10} {'inflated':>10} {'load':>9} "
          f"{'per MiB':>9}")
    n, samples = 10, 1000
    while samples <= largest:
        path = folder / f"run_{n}_{samples}.npz"
        tumbling(n, samples).save(path)
        size = inflated(path)
        t = best(lambda path=path: Trajectory.load(path), repeat)
        print(f"{n:>8} x {samples:<8} {path.stat().st_size / MIB:>8.2f} M "
              f"{size / MIB:>8.2f} M {t * 1e3:>7.1f} ms {t * 1e3 / (size / MIB):>6.2f} ms")
        path.unlink()
        samples *= 4


def weightless_run(path: Path, good: dict[str, np.ndarray]) -> Path:
    """Review R3, S1: 10^12 body names of '<U0' (0 bytes each) and no samples."""
    n = 10**12
    raw = {"body_names": npy_header((n,), "<U0"), "position": npy_header((0, n, 2), "<f8"),
           "velocity": npy_header((0, n, 2), "<f8"), "orientation": npy_header((0, n), "<f8"),
           "angular_velocity": npy_header((0, n), "<f8")}
    return npz_members(path, {k: raw.get(k, v[:0] if k in ("t", "reactions") else v)
                              for k, v in good.items()
                              if k not in ("mass", "inertia") and not k.startswith("series/")})


def escaped_quotes(n: int) -> str:
    """Review R3, S2: a string of `n` escaped quotes that never ends."""
    return '"' + '\\"' * n


def refusal(load, path: Path) -> tuple[float, int, str]:
    """(seconds to the refusal, peak bytes held, the message's start)."""
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        load(path)
        message = "read (not refused)"
    except MbodyError as exc:
        message = str(exc).replace(str(path), path.name)
    elapsed = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return elapsed, peak, message


def hostile(folder: Path) -> None:
    run = folder / "run.npz"
    mbody.simulate(mbody.load(ROOT / "models" / "pendulum.yaml"), t_end=1.0).save(run)
    with np.load(run) as z:
        good = dict(z)
    deep = dict(good)
    deep["info"] = np.array('{"a":' * 10000)
    np.savez(folder / "deepinfo.npz", **deep)
    quoted = dict(good)
    quoted["info"] = np.array(escaped_quotes(32_000))
    np.savez_compressed(folder / "quotes.npz", **quoted)
    (folder / "quotes.json").write_text(escaped_quotes(4_000_000))
    files = [(Trajectory.load, npz_bomb(folder / "bomb.npz", good, 2**28)),
             (Trajectory.load, npz_with(folder / "liar.npz", good, "t", {
                 "descr": "<f8", "fortran_order": False, "shape": (10**15,)}, bytes(16))),
             (Trajectory.load, folder / "deepinfo.npz"),
             (mbody.load_export, mat_bomb(folder / "bomb.mat", 2**28)),
             (Trajectory.load, weightless_run(folder / "names0.npz", good)),
             (Trajectory.load, folder / "quotes.npz"),
             (mbody.load_export, folder / "quotes.json")]
    print("\nhostile files: time to the refusal, peak memory held meanwhile")
    print(f"{'file':>14} {'on disk':>10} {'time':>9} {'peak':>9}  message")
    for load, path in files:
        elapsed, peak, message = refusal(load, path)
        print(f"{path.name:>14} {path.stat().st_size / MIB:>8.2f} M {elapsed * 1e3:>6.1f} ms "
              f"{peak / MIB:>6.2f} M  {message[:110]}")


def export_like(chars: int) -> str:
    """JSON text of about `chars` characters nested as an export is: objects of names,
    numbers and texts with escaped quotes and brackets in them."""
    row = {"name": "b0", "mass": 1.25, "inertia": [[0.1, 0.0, 0.0], [0.0, 0.2, 0.0],
                                                     [0.0, 0.0, 0.3]],
           "source": 'run "a" [t = 0.5 s] {rod}\\', "known": None}
    one = len(json.dumps(row)) + 2
    return json.dumps({"format": "mbody-export", "bodies": [row] * max(1, chars // one)})


def json_scan(repeat: int) -> None:
    print("\nthe JSON nesting bound (jsontext.nesting): time against the text's size")
    print(f"{'characters':>12} {'export-like':>12} {'per MB':>9} {'escaped quotes':>15} "
          f"{'per MB':>9}")
    for chars in (64_000, 256_000, 1_024_000, 4_096_000, 16_384_000):
        texts = (export_like(chars), escaped_quotes(chars // 2))
        times = [best(lambda text=text: nesting(text), repeat) for text in texts]
        cells = [f"{t * 1e3:>9.2f} ms {t * 1e3 / (len(x) / 1e6):>6.2f} ms"
                 for t, x in zip(times, texts, strict=True)]
        print(f"{chars:>12,} {cells[0]:>22} {cells[1]:>25}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--largest", type=int, default=256_000,
                   help="most samples of the good runs (10 bodies)")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        good_runs(Path(tmp), a.repeat, a.largest)
        hostile(Path(tmp))
    json_scan(a.repeat)


if __name__ == "__main__":
    main()

"""Speed of a driven mechanism's revolution: mbody's kinematic run beside a hand-written
numpy floor, in one process; and the whole command's wall time.

    python tools/bench_drive.py [--repeat 20]

The job (issue 25): one revolution of the shipped `models/slider_crank_driven.yaml` at 360
positions, each a position, velocity and acceleration analysis and the nine reactions and
the motor torque (kinetostatics). Targets: within 20 ms in a warm process, and `mbody
simulate` of it within 1 s wall.

The floor is what a student who knows the mechanism writes in numpy: the closed-form
slider-crank kinematics for all 360 angles at once, and the 9 Newton-Euler rows of the
three bodies solved as one batched `numpy.linalg.solve`. It knows the mechanism's shape;
mbody solves any mechanism from its file. The two must agree (printed), and the ratio
is mbody's time over the floor's, best of `--repeat` runs each.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
MODEL = ROOT / "models" / "slider_crank_driven.yaml"
R, L = 0.05, 0.16
OMEGA = 20 * math.pi  # 600 rpm
THETA0 = math.pi / 6
POSITIONS = 360


def floor(t: np.ndarray, mass: np.ndarray, I: np.ndarray) -> np.ndarray:
    """(K, 9) [O.Fx, O.Fy, A.Fx, A.Fy, B.Fx, B.Fy, P.Fy, P.Mz, motor.M] in world axes at
    the times t: closed-form kinematics, then the batched 9 x 9 Newton-Euler solve."""
    g = 9.81
    th = THETA0 + OMEGA * t
    s, c = np.sin(th), np.cos(th)
    sp = -R * s / L
    cp = np.sqrt(1.0 - sp * sp)
    phid = -R * c * OMEGA / (L * cp)
    phidd = (R * s * OMEGA**2 + L * sp * phid**2) / (L * cp)
    A = np.stack((R * c, R * s), axis=1)
    B = np.stack((R * c + L * cp, np.zeros_like(t)), axis=1)
    xc, xr = A / 2, (A + B) / 2
    aA = -R * OMEGA**2 * np.stack((c, s), axis=1)
    aB = aA + L * (phidd[:, None] * np.stack((-sp, cp), axis=1)
                   - (phid**2)[:, None] * np.stack((cp, sp), axis=1))
    ac, ar, ap = aA / 2, (aA + aB) / 2, aB
    alpha = np.stack((np.zeros_like(t), phidd, np.zeros_like(t)), axis=1)
    gas = 250.0 * (s + np.abs(s))
    K = len(t)
    M = np.zeros((K, 9, 9))
    rhs = np.zeros((K, 9))

    def cross(r: np.ndarray, col: int, sign: float, row: int) -> None:
        """row += sign (r × F) with F = (x[col], x[col + 1])."""
        M[:, row, col] += -sign * r[:, 1]
        M[:, row, col + 1] += sign * r[:, 0]

    # crank (rows 0-2): +F_O, -F_A, +motor
    M[:, 0, 0], M[:, 1, 1], M[:, 0, 2], M[:, 1, 3] = 1, 1, -1, -1
    cross(-xc, 0, 1.0, 2)
    cross(A - xc, 2, -1.0, 2)
    M[:, 2, 8] = 1
    # rod (rows 3-5): +F_A, -F_B
    M[:, 3, 2], M[:, 4, 3], M[:, 3, 4], M[:, 4, 5] = 1, 1, -1, -1
    cross(A - xr, 2, 1.0, 5)
    cross(B - xr, 4, -1.0, 5)
    # piston (rows 6-8): +F_B, +P.Fy, +P.Mz, the gas load (its point is the mass centre)
    M[:, 6, 4], M[:, 7, 5], M[:, 7, 6], M[:, 8, 7] = 1, 1, 1, 1
    for b, (a, x_row) in enumerate(((ac, 0), (ar, 3), (ap, 6))):
        rhs[:, x_row:x_row + 2] = mass[b] * (a - np.array([0.0, -g]))
        rhs[:, x_row + 2] = I[b] * alpha[:, b]
    rhs[:, 6] -= gas
    return np.linalg.solve(M, rhs[..., None])[..., 0]


def best(f, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def wall(args: list[str], repeat: int) -> float:
    def run() -> None:
        subprocess.run([sys.executable, "-m", "mbody", *args], cwd=ROOT, check=True,
                       capture_output=True)
    return best(run, repeat)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=20)
    p.add_argument("--wall-repeat", type=int, default=3)
    a = p.parse_args(argv)

    import mbody

    model = mbody.load(MODEL)
    fps = OMEGA / (2 * math.pi) * POSITIONS
    t_end = (POSITIONS - 1) / fps
    run = mbody.kinematic_run(model, t_end, fps, axes="world")  # warm: the workspace made
    assert len(run) == POSITIONS
    mass = np.asarray(model.mass)
    I = np.asarray(model.J)[:, 2, 2]
    ref = floor(run.t, mass, I)
    labels = ["O.Fx", "O.Fy", "A.Fx", "A.Fy", "B.Fx", "B.Fy", "P.Fy", "P.Mz", "motor.M"]
    got = np.stack([run.reactions[:, run.reaction_labels.index(lab)] for lab in labels],
                   axis=1)
    agree = float(np.abs(got - ref).max() / np.abs(ref).max())

    t_mbody = best(lambda: mbody.kinematic_run(model, t_end, fps), a.repeat)
    t_world = best(lambda: mbody.kinematic_run(model, t_end, fps, axes="world"), a.repeat)
    t_floor = best(lambda: floor(run.t, mass, I), a.repeat)
    print(f"one revolution of {MODEL.name} at {POSITIONS} positions (kinematics and "
          "kinetostatics), best of", a.repeat)
    print(f"  mbody.kinematic_run            {t_mbody * 1e3:8.2f} ms   (target 20 ms)  "
          f"{t_mbody / t_floor:6.2f} x the floor")
    print(f"  mbody.kinematic_run, world axes {t_world * 1e3:7.2f} ms             "
          f"{t_world / t_floor:6.2f} x the floor")
    print(f"  hand-written numpy floor       {t_floor * 1e3:8.2f} ms")
    print(f"  largest difference, mbody vs floor, relative to the largest load: {agree:.1e}")
    if a.wall_repeat:
        w_kin = wall(["kinematics", str(MODEL)], a.wall_repeat)
        w_check = wall(["check", str(MODEL)], a.wall_repeat)
        print(f"whole command, wall, best of {a.wall_repeat}:")
        print(f"  mbody kinematics {MODEL.name}      {w_kin:6.3f} s")
        try:
            w_sim = wall(["simulate", str(MODEL), "--t-end", "0.1"], a.wall_repeat)
            print(f"  mbody simulate {MODEL.name} --t-end 0.1 {w_sim:6.3f} s   (target 1 s)")
        except subprocess.CalledProcessError as exc:
            print(f"  mbody simulate: failed ({exc.stderr.decode()[-200:]})")
        print(f"  mbody check {MODEL.name} (start-up)  {w_check:6.3f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

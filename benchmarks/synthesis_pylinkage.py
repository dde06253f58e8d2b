"""pylinkage's path generation against mixdyn's on the same five points, timing-free.

pylinkage (``pylinkage.synthesis.path_generation``, Burmester theory over sampled coupler
orientations, each candidate checked by simulation) and ``md.synthesize`` (random starts
refined by Levenberg-Marquardt; kinematics only, and with the RMS motor torque in the
objective) get the five points of ``benchmarks/synthesis_torque.py``. Every linkage found is
measured by mixdyn alike: the path error ``sum_i min_theta |C(theta) - P_i|^2`` (the nearest
point of its coupler curve to each target: 20,000 input angles over a turn, refined by
Brent's method) and the RMS and peak motor torque over the input angles between the first
and last target (bars of 2 kg/m, 0.5 kg at the coupler point, one turn a second, under
gravity; the torque from the energy balance, equal to ``md.inverse``'s to 1e-9 in the
tests).

pylinkage is not one of mixdyn's dependencies: ``pip install pylinkage`` (1.3.0 measured), or
``--pylinkage-path`` a folder holding it.

Run: ``python benchmarks/synthesis_pylinkage.py [--starts 512] [--pylinkage-path DIR]``.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from scipy.optimize import minimize_scalar

from mixdyn.synthesis import FourBar, Masses, Objective, PathTask, coupler_curve, motor_torque

POINTS = np.array([[0.50, 0.30], [0.58, 0.42], [0.48, 0.55], [0.32, 0.50], [0.30, 0.36]])
MASSES = Masses(density=2.0, payload=0.5)
SPEED = 2 * np.pi


def from_pylinkage(sol) -> tuple[FourBar, float]:
    """A pylinkage FourBarSolution as a mixdyn FourBar and its input angle at its drawn
    position: ground pivots A (crank) and D, crank pin B, rocker pin C, coupler point P."""
    a, d, b, c, p = (np.asarray(x, dtype=float) for x in (sol.ground_pivot_a,
                     sol.ground_pivot_d, sol.crank_pivot_b, sol.coupler_pivot_c,
                     sol.coupler_point))  # fmt: skip
    r1, theta0 = np.linalg.norm(d - a), np.arctan2(*(d - a)[::-1])
    phi3 = np.arctan2(*(c - b)[::-1])
    rot = np.array([[np.cos(phi3), np.sin(phi3)], [-np.sin(phi3), np.cos(phi3)]])
    rc = rot @ (p - b)
    u = (d - b) / np.linalg.norm(d - b)
    branch = np.sign(np.dot(c - b, np.array([-u[1], u[0]])))
    v = [r1, np.linalg.norm(b - a), np.linalg.norm(c - b), np.linalg.norm(c - d), *rc, *a, theta0]
    theta = np.arctan2(*(b - a)[::-1]) - theta0
    return FourBar.from_vector(np.asarray(v), branch), float(theta)


def measure(fb: FourBar) -> tuple[float, float, float]:
    """Path error [m^2] (nearest curve point to each target: a grid over a turn, refined by
    Brent's method), RMS and peak torque [N m] over the arc from the first target to the
    last."""
    grid = np.linspace(0.0, 2 * np.pi, 20_000, endpoint=False)
    curve = np.asarray(coupler_curve(fb, grid))
    nearest = grid[np.argmin(np.linalg.norm(curve[None] - POINTS[:, None], axis=2), axis=1)]
    theta, error = [], 0.0
    for p, t0 in zip(POINTS, nearest, strict=True):  # refined about the nearest grid point
        found = minimize_scalar(
            lambda t, p=p: float(np.sum((np.asarray(coupler_curve(fb, [t]))[0] - p) ** 2)),
            bounds=(t0 - 1e-3, t0 + 1e-3),
            method="bounded",
            options={"xatol": 1e-12},
        )
        theta.append(found.x)
        error += found.fun
    theta = np.unwrap(theta)
    arc = np.linspace(theta.min(), theta.max(), 256)
    tau = np.asarray(motor_torque(fb, MASSES, arc, SPEED))
    return error, float(np.sqrt(np.mean(tau**2))), float(np.max(np.abs(tau)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=512)
    parser.add_argument("--pylinkage-path", default=None)
    args = parser.parse_args()
    if args.pylinkage_path:
        sys.path.insert(0, args.pylinkage_path)
    import pylinkage
    from pylinkage.synthesis import path_generation

    import mixdyn as md

    rows = []
    started = time.perf_counter()
    res = path_generation([tuple(p) for p in POINTS], max_solutions=10)
    seconds = time.perf_counter() - started
    for k, sol in enumerate(res.raw_solutions):
        fb, _ = from_pylinkage(sol)
        rows.append((f"pylinkage {pylinkage.__version__} solution {k + 1}", seconds, *measure(fb)))
    for label, weight in (("kinematics only", 0.0), ("with RMS torque, weight 1e-4", 1e-4)):
        objective = Objective(masses=MASSES, speed=SPEED, torque_weight=weight)
        out = md.synthesize(PathTask(POINTS), objective, starts=args.starts, seed=0)
        rows.append((f"mixdyn {label}, best", out.seconds, *measure(out.best.fourbar)))
    print(f"five points, timing-free; mixdyn {args.starts} starts (times include compiling)\n")
    print("| linkage | search [s] | path error [m^2] | RMS torque [N m] | peak torque [N m] |")
    print("|---|---|---|---|---|")
    for name, s, e, rms, peak in rows:
        print(f"| {name} | {s:.1f} | {e:.2e} | {rms:.3f} | {peak:.3f} |")


if __name__ == "__main__":
    main()

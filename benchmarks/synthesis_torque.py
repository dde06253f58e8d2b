"""Four-bar path generation with the motor torque in the objective, against the
kinematics-only optimum: the torque drops by a measured factor at the same path error.

The task: five points of a closed curve, timing-free (the input angles are found too), so
that many four-bars pass them exactly (a family of exact solutions: 14 unknowns, 10
equations). A kinematics-only search (what pylinkage, pyslvs or four_bar do, by other
optimizers) returns one of them; which one is the search's accident. With the RMS motor
torque in the objective (bars of 2 kg/m, a 0.5 kg payload at the coupler point, the crank at
one turn a second, under gravity) the search follows the family towards the lightest-driven
member, then polishes the path alone.

Both results are built as mixdyn models (what their model files hold) and run by mixdyn's own
inverse dynamics (``md.inverse``: Lagrange multipliers, not the search's energy balance);
the table compares the path error, the RMS and peak motor torque over the traversed motion.
Two baselines: the kinematics-only search's best-ranked linkage, and the lowest-torque one
among all its distinct linkages that reach the same path error (a designer picking by hand
from its list).

Run: ``python benchmarks/synthesis_torque.py [--starts 1024] [--seed 0]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import mixdyn as md
from mixdyn.synthesis import Masses, Objective, PathTask, synthesize

#: The targets [m]: five points of an egg-shaped closed curve, in order.
POINTS = np.array([[0.50, 0.30], [0.58, 0.42], [0.48, 0.55], [0.32, 0.50], [0.30, 0.36]])
MASSES = Masses(density=2.0, payload=0.5)
SPEED = 2 * np.pi  # rad/s: a turn a second
#: The path error that counts as "the same": [m^2], a micrometre over five points.
SAME_ERROR = 5e-12


def mixdyn_torque(out, k: int) -> tuple[float, float]:
    """RMS and peak motor torque [N*m] of candidate k by md.inverse of its model (the model
    its file describes)."""
    c = out.candidates[k]
    t = np.linspace(0.0, (c.angles[-1] - c.angles[0]) / SPEED, 257)
    tau = md.inverse(out.model(k), t)["motor"]
    return float(np.sqrt(np.mean(tau**2))), float(np.max(np.abs(tau)))


def run(starts: int, seed: int, show=print) -> dict:
    task = PathTask(POINTS)

    def progress(stage, done, total, best):
        show(f"  {stage}: {done}/{total} starts, best score {best:.3e}")

    started = time.perf_counter()
    kin = synthesize(
        task, Objective(masses=MASSES, speed=SPEED), starts=starts, seed=seed, progress=progress
    )
    kin_s = time.perf_counter() - started
    started = time.perf_counter()
    dyn = synthesize(
        task,
        Objective(masses=MASSES, speed=SPEED, torque_weight=1e-4),
        starts=starts,
        seed=seed,
        progress=progress,
    )
    dyn_s = time.perf_counter() - started
    same = [k for k, c in enumerate(kin.candidates) if c.error <= SAME_ERROR]
    lowest = min(same, key=lambda k: kin.candidates[k].torque_rms)
    dyn_k = next(k for k, c in enumerate(dyn.candidates) if c.error <= SAME_ERROR)
    rows = {
        "kinematics only, best ranked": (kin, 0),
        "kinematics only, lowest torque of its list": (kin, lowest),
        "with RMS torque (weight 1e-4 m^2/(N m)^2)": (dyn, dyn_k),
    }
    table = {}
    for name, (out, k) in rows.items():
        rms, peak = mixdyn_torque(out, k)
        table[name] = (out.candidates[k].error, rms, peak)
    show(f"\n{len(POINTS)} points, timing-free, {starts} starts, seed {seed}")
    show(f"searches: kinematics only {kin_s:.1f} s, with torque {dyn_s:.1f} s (compiling included)")
    show(f"{'linkage':46s} {'error [m^2]':>12s} {'RMS [N m]':>10s} {'peak [N m]':>10s}")
    for name, (e, rms, peak) in table.items():
        show(f"{name:46s} {e:12.2e} {rms:10.4f} {peak:10.4f}")
    ref = table["with RMS torque (weight 1e-4 m^2/(N m)^2)"]
    for name in list(table)[:2]:
        show(
            f"torque factor against '{name}': RMS {table[name][1] / ref[1]:.2f}, "
            f"peak {table[name][2] / ref[2]:.2f}"
        )
    return table


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=1024)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    run(args.starts, args.seed)

"""Four-bar path generation with the peak joint reaction in the objective, against the
kinematics-only optimum: the largest pin force drops by a measured factor at the same path
error.

The task is :mod:`synthesis_torque`'s: five points of a closed curve, timing-free, so that a
family of four-bars passes them exactly. Both searches get the links' masses (bars of 2 kg/m,
a 0.5 kg payload at the coupler point, gravity on) and the crank at one turn a second; one
scores the path alone, the other adds ``reaction_weight`` times the smooth peak of the
joints' force magnitudes over the motion (``Objective(reaction="peak")``), then polishes the
path alone. Both results are built as mixdyn models and run by mixdyn's own inverse dynamics
(``md.inverse``: the Lagrange multipliers' ``{joint}.Fx``, ``.Fy``), not by the search's
Newton-Euler solve; the table gives the path error and each joint's peak force.

The reaction-weighted search compiles for minutes on a 2-core CPU (a derivative through a
linear solve per angle under two ``vmap``); the starts are few.

Run: ``python benchmarks/synthesis_reactions.py [--starts 16] [--seed 3]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import mixdyn as md
from mixdyn.synthesis import Masses, Objective, PathTask, synthesize

#: The targets [m] (synthesis_torque.py's).
POINTS = np.array([[0.50, 0.30], [0.58, 0.42], [0.48, 0.55], [0.32, 0.50], [0.30, 0.36]])
MASSES = Masses(density=2.0, payload=0.5)
SPEED = 2 * np.pi  # rad/s
JOINTS = ("O2", "A", "B", "O4")


def peaks(out, k: int = 0) -> dict[str, float]:
    """Each joint's peak force magnitude [N] of candidate k by md.inverse of its model."""
    c = out.candidates[k]
    t = np.linspace(0.0, (c.angles[-1] - c.angles[0]) / SPEED, 257)
    r = md.inverse(out.model(k), t)
    return {j: float(np.max(np.hypot(r[f"{j}.Fx"], r[f"{j}.Fy"]))) for j in JOINTS}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=int, default=16)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--weight", type=float, default=1e-6, help="reaction_weight [m^2/N^2]")
    args = ap.parse_args()
    task = PathTask(POINTS)
    rows = []
    for label, objective in (
        ("kinematics only", Objective(masses=MASSES, speed=SPEED)),
        (f"reaction_weight = {args.weight:g} m²/N²",
         Objective(masses=MASSES, speed=SPEED, reaction_weight=args.weight, reaction="peak")),
    ):  # fmt: skip
        started = time.perf_counter()
        out = synthesize(task, objective, starts=args.starts, seed=args.seed)
        seconds = time.perf_counter() - started
        if not out.candidates:
            print(f"{label}: no feasible linkage among {args.starts} starts ({seconds:.0f} s)")
            return
        rows.append((label, out.best.error, peaks(out), seconds))
    print(f"{args.starts} starts, seed {args.seed}; peak pin forces by md.inverse [N]\n")
    print("| search | path error [m²] | " + " | ".join(f"{j} peak" for j in JOINTS)
          + " | largest | search [s] |")  # fmt: skip
    print("|---|---|" + "---|" * (len(JOINTS) + 2))
    for label, error, p, seconds in rows:
        cells = " | ".join(f"{p[j]:.2f}" for j in JOINTS)
        print(f"| {label} | {error:.2e} | {cells} | {max(p.values()):.2f} | {seconds:.0f} |")
    base, weighed = (max(r[2].values()) for r in rows)
    print(f"\nlargest pin force, reaction-weighted / kinematics only: {weighed / base:.3f}")


if __name__ == "__main__":
    main()

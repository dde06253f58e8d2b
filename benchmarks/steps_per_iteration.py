"""Several fixed steps per loop iteration: a bare RK4 loop over ``Problem.accelerations``
(Baumgarte stabilization), ``lax.fori_loop`` with ``unroll=k``, CPU time per step.

The loop is the step of ``md.forward(method="baumgarte")`` without diffrax around it, on the
linear solver ``--solver`` names (``auto``: ``md.forward``'s default; ``unrolled``: the
straight-line path at any size, ``UnrolledSolver(max_rows=1000)``); the per-step time is the
difference of 1,000 and 100 steps (fixed costs cancel), best of 7, the process's CPU time.

    python benchmarks/steps_per_iteration.py 2 4
    python benchmarks/steps_per_iteration.py 2 3 4 5 --unroll 1 --solver dense unrolled
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import mixdyn as md
from mixdyn.analysis._problem import Problem
from mixdyn.equations import Constraints

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
from fixtures import pendulum_chain

H = 1e-3


def rk4_loop(p: Problem, q0, qd0, steps: int, unroll: int):
    """A function running ``steps`` RK4 steps of ``H`` from ``(q0, qd0)``, compiled."""

    @eqx.filter_jit
    def run(p, q, qd):
        def f(t, q, qd):
            return qd, p.accelerations(q, qd, t, 5.0, 5.0)[0]

        def step(i, y):
            q, qd = y
            t = i * H
            k1 = f(t, q, qd)
            k2 = f(t + H / 2, q + H / 2 * k1[0], qd + H / 2 * k1[1])
            k3 = f(t + H / 2, q + H / 2 * k2[0], qd + H / 2 * k2[1])
            k4 = f(t + H, q + H * k3[0], qd + H * k3[1])
            return tuple(y[j] + H / 6 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]) for j in range(2))

        return jax.lax.fori_loop(0, steps, step, (q, qd), unroll=unroll)

    return lambda: jax.block_until_ready(run(p, q0, qd0))


def per_step(n: int, unroll: int, solver: str = "auto") -> tuple[str, float]:
    """``(linear solver, CPU us per step)`` of the loop on an ``n``-link chain."""
    model = pendulum_chain(n)
    choice = md.UnrolledSolver(max_rows=1000) if solver == "unrolled" else solver
    c = Constraints.of(model).with_linear_solver(choice)
    p = Problem(model, c)
    start = md.forward(model, np.array([0.0, H]), method="baumgarte", dt=H, energy_tol=None)
    q0, qd0 = jnp.asarray(start.q[0]), jnp.asarray(start.qd[0])
    runs = {N: rk4_loop(p, q0, qd0, N, unroll) for N in (100, 1000)}
    for run in runs.values():
        run()
    best = dict.fromkeys(runs, float("inf"))
    for _ in range(7):
        for N, run in runs.items():
            t0 = time.process_time()
            run()
            best[N] = min(best[N], time.process_time() - t0)
    return c.linear_solver.name, (best[1000] - best[100]) / 900 * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("links", nargs="*", type=int, default=[2, 4])
    ap.add_argument("--unroll", nargs="*", type=int, default=[1, 2, 4])
    ap.add_argument("--solver", nargs="*", default=["auto"], choices=("auto", "dense", "unrolled"))
    args = ap.parse_args()
    print("| links | linear solver | " + " | ".join(f"k = {k} [us]" for k in args.unroll) + " |")
    print("|---|---|" + "---|" * len(args.unroll))
    for n in args.links:
        for solver in args.solver:
            cells = [per_step(n, k, solver) for k in args.unroll]
            times = " | ".join(f"{t:.1f}" for _, t in cells)
            print(f"| {n} | {cells[0][0]} | {times} |", flush=True)


if __name__ == "__main__":
    main()

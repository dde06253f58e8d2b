"""Pendulum chains at matched accuracy: mixdyn against Exudyn's generalized-alpha.

The fixed-step tables of ``benchmarks/run.py`` compare cost per step. What a user pays for is
an answer of a given accuracy: here every run is scored by the error of the chain's free tip at
``T`` against a reference, and mixdyn's adaptive projection (Tsit5 with mass-weighted
projection, its sparse linear-solver path from 32 constraint rows) is run at the loosest
tolerance whose error is no larger than Exudyn's.

* Reference: mixdyn, projection with Dopri8 at rtol = atol = 1e-11; checked against a second
  mixdyn run at 1e-10 and against MuJoCo (minimal coordinates, RK4, h = 1e-4) where the chain
  is small enough: the three agree far below the errors compared.
* Exudyn: ``ObjectRigidBody2D`` + ``ObjectJointRevolute2D``, generalized-alpha
  (rho_inf = 0.9, modified Newton, ``EigenSparse``) at h = 1e-3 and 5e-4 (the ratio of its
  errors, ~4, shows the second order and that the reference is good enough).
* mixdyn: projection, Tsit5, rtol = atol from 1e-4 down; and generalized-alpha at Exudyn's step.

Run: ``python benchmarks/matched.py [--sizes 16 64 256] [--T 1.0]``; prints Markdown for
``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import os

os.environ["XLA_FLAGS"] = "--xla_cpu_enable_concurrency_optimized_scheduler=false"

import argparse
import pathlib
import sys
import warnings

import jax.numpy as jnp
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from run import chain_exudyn, chain_mixdyn, chain_mujoco, have


def tip_error(r: dict, ref: dict) -> float:
    return float(np.max(np.abs(np.asarray(r["tip_T"]) - np.asarray(ref["tip_T"]))))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[16, 64, 256])
    ap.add_argument("--T", type=float, default=1.0)
    ap.add_argument("--rtols", type=float, nargs="*", default=[1e-4, 1e-5, 1e-6, 1e-7, 1e-8])
    ap.add_argument("--mujoco-max", type=int, default=64)
    ap.add_argument("--no-galpha", action="store_true")
    args = ap.parse_args(argv)
    warnings.filterwarnings("ignore")
    T = args.T
    out = []
    for n in args.sizes:
        rows = []

        def adaptive(solver, rtol, n=n):
            r = chain_mixdyn(
                n,
                T,
                None,
                "projection",
                solver=solver,
                rtol=jnp.asarray(rtol),
                atol=jnp.asarray(rtol),
            )
            return dict(r, method=f"projection {solver} rtol={rtol:g}")

        ref = adaptive("dopri8", 1e-11)
        check = adaptive("dopri8", 1e-10)
        ref_note = f"reference check: dopri8 1e-10 differs by {tip_error(check, ref):.1e} m"
        if have("mujoco") and n <= args.mujoco_max:
            mj = chain_mujoco(n, T, 1e-4)
            ref_note += f", MuJoCo RK4 h=1e-4 by {tip_error(mj, ref):.1e} m"
        print(f"n={n}: {ref_note}", flush=True)
        if have("exudyn"):
            for h in (1e-3, 5e-4):
                r = chain_exudyn(n, T, h, sparse=True)
                rows.append(
                    dict(
                        r,
                        method=f"generalized-alpha h={h:g}",
                        err=tip_error(r, ref),
                        steps=round(T / h),
                    )
                )
                print(f"  {rows[-1]['method']}: {r['run_s']:.3g} s, {rows[-1]['err']:.2e} m")
        target = rows[0]["err"] if rows else float("inf")
        for rtol in args.rtols:
            r = adaptive("tsit5", rtol)
            rows.append(dict(r, err=tip_error(r, ref)))
            print(f"  {r['method']}: {r['run_s']:.3g} s, {rows[-1]['err']:.2e} m", flush=True)
        if not args.no_galpha:
            r = chain_mixdyn(n, T, 1e-3, "generalized-alpha")
            rows.append(dict(r, method="generalized-alpha h=0.001", err=tip_error(r, ref)))
            print(f"  mixdyn {rows[-1]['method']}: {r['run_s']:.3g} s, {rows[-1]['err']:.2e} m")
        matched = [r for r in rows if r["code"] == "mixdyn" and r["err"] <= target]
        best = min(matched, key=lambda r: r["run_s"]) if matched else None
        out.append((n, ref_note, rows, target, best))

    for n, note, rows, target, best in out:
        print(f"\n### {n} links, 0-{T:g} s ({note})\n")
        print("| code | method | linear solve | steps | run [s] | compile [s] | tip error [m] |")
        print("|---|---|---|---|---|---|---|")
        for r in rows:
            print(
                f"| {r['code']} | {r['method']} | {r.get('linear_solver', 'EigenSparse')} "
                f"| {r.get('steps', round(T / 1e-3))} | {r['run_s']:.3g} "
                f"| {r['compile_s']:.3g} | {r['err']:.2e} |"
            )
        if best is not None and np.isfinite(target):
            ex = rows[0]
            print(
                f"\nMatched accuracy (error <= Exudyn's {target:.2e} m at h = 1e-3): mixdyn "
                f"{best['method']}, {best['run_s']:.3g} s against {ex['run_s']:.3g} s: ratio "
                f"mixdyn / Exudyn = {best['run_s'] / ex['run_s']:.2f}"
            )


if __name__ == "__main__":
    main()

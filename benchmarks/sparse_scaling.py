"""Dense vs sparse linear-solver path on pendulum chains (issue 7).

Prints, for chains of 16..1024 bodies, microseconds per acceleration evaluation
(``Problem.accelerations``, jitted, after compilation) and per fixed-step RK4 step
(``dt = 1e-4``, 4 evaluations, steps run inside one jitted ``fori_loop``), for the dense path
(``jax.jacfwd`` Jacobian, dense Schur complement, LU), the sparse path (per-element Jacobian,
banded block Cholesky) and, when installed, klujax (KLU on the same sparse Schur complement);
then the log-log slope of each and the crossover.

Run: ``python benchmarks/sparse_scaling.py [--sizes 16 64 256 1024] [--max-dense 256]``.
"""

from __future__ import annotations

import os

os.environ.setdefault("XLA_FLAGS", "--xla_cpu_enable_concurrency_optimized_scheduler=false")

import argparse
import sys
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

from fixtures import horizontal_chain  # noqa: E402
from mixdyn.analysis._problem import Problem  # noqa: E402
from mixdyn.equations import Constraints  # noqa: E402


def klujax_problem(problem: Problem):
    """Accelerations with the Schur complement solved by klujax (KLU), for comparison."""
    import klujax

    c = problem.c
    rows, _ = c.coo()
    st = c.schur_structure()
    # unique entries (r, s) of S and the products adding to each
    r1, r2 = rows[st.k1_all], rows[st.k2_all]
    key = r1 * c.m + r2
    uniq, target = np.unique(key, return_inverse=True)
    Ai = jnp.asarray(uniq // c.m, dtype=jnp.int32)
    Aj = jnp.asarray(uniq % c.m, dtype=jnp.int32)

    @eqx.filter_jit
    def acc(problem, q, qd, t):
        Minv = problem.Minv
        v = c.jacobian_values(q, t)
        Sx = jax.ops.segment_sum(
            v[st.k1_all] * v[st.k2_all] * Minv[st.col_all], jnp.asarray(target), uniq.size
        )
        gam = c.gamma(q, qd, t)
        Q = problem.known_forces(q, qd, t)
        mu = klujax.solve(Ai, Aj, Sx, c.matvec(v, Minv * Q) - gam)
        return Minv * (Q - c.rmatvec(v, mu)), mu, jnp.ones(())

    return acc


def timeit(f, *args, repeat: int = 5, number: int | None = None) -> float:
    """Best wall time of ``f(*args)`` [s], after one call for compilation."""
    jax.block_until_ready(f(*args))
    if number is None:
        t0 = time.perf_counter()
        jax.block_until_ready(f(*args))
        number = max(1, int(0.2 / max(time.perf_counter() - t0, 1e-7)))
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            jax.block_until_ready(f(*args))
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def rk4_runner(acc, dt: float, steps: int):
    @eqx.filter_jit
    def run(problem, q, qd):
        def f(t, q, qd):
            return qd, acc(problem, q, qd, t)[0]

        def body(k, y):
            q, qd = y
            t = k * dt
            k1 = f(t, q, qd)
            k2 = f(t + dt / 2, q + dt / 2 * k1[0], qd + dt / 2 * k1[1])
            k3 = f(t + dt / 2, q + dt / 2 * k2[0], qd + dt / 2 * k2[1])
            k4 = f(t + dt, q + dt * k3[0], qd + dt * k3[1])
            q = q + dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            qd = qd + dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            return q, qd

        return jax.lax.fori_loop(0, steps, body, (q, qd))

    return run


def acc_runner(acc, count: int):
    """``count`` dependent acceleration evaluations inside one jitted loop (no dispatch)."""

    @eqx.filter_jit
    def run(problem, q, qd, t):
        def body(k, y):  # q and qd both carried: nothing is hoisted out of the loop
            q, qd = y
            qdd = acc(problem, q, qd, t)[0]
            return q + 1e-300 * qdd, qd + 1e-300 * qdd

        return jax.lax.fori_loop(0, count, body, (q, qd))

    return run


def _acc(problem, q, qd, t):
    return problem.accelerations(q, qd, t)


def slope(ns, ts) -> float:
    ok = [(n, t) for n, t in zip(ns, ts, strict=True) if np.isfinite(t)]
    if len(ok) < 2:
        return float("nan")
    x, y = np.log([n for n, _ in ok]), np.log([t for _, t in ok])
    return float(np.polyfit(x, y, 1)[0])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="*", default=[4, 8, 16, 32, 64, 128, 256, 1024])
    ap.add_argument("--max-dense", type=int, default=256, help="largest chain for the dense path")
    ap.add_argument("--no-klujax", action="store_true")
    args = ap.parse_args()
    try:
        import klujax  # noqa: F401

        use_klu = not args.no_klujax
    except ImportError:
        use_klu = False
    dt = 1e-4
    rows = []
    acc_jit = eqx.filter_jit(_acc)
    print(f"devices: {jax.devices()}  XLA_FLAGS={os.environ.get('XLA_FLAGS')}")
    hdr = (
        f"{'bodies':>6} {'rows':>5} {'bw':>3} {'B':>3} | {'acc dense':>10} {'acc sparse':>10} "
        f"{'acc klu':>9} | {'rk4 dense':>10} {'rk4 sparse':>10} {'rk4 klu':>9}  [us]  "
        f"max|dqdd| rel"
    )
    print(hdr)
    for n in args.sizes:
        model = horizontal_chain(n, mass_step=0.0)  # uniform links
        c = Constraints.of(model)
        pd = Problem(model, c)
        ps = Problem(model, c.with_linear_solver("sparse"))
        st = ps.c.schur_structure()
        rng = np.random.default_rng(0)
        q = jnp.asarray(np.asarray(model.q0)) + 1e-3 * rng.normal(size=model.nq)
        q, _ = ps.project_positions(q, 0.0, 1e-14, iters=8)
        qd = ps.project_velocities(q, jnp.asarray(rng.normal(size=model.nq)), 0.0)
        t = jnp.zeros(())
        count = max(4, min(2000, 200_000 // (n * 4)))
        a_s = timeit(acc_runner(_acc, count), ps, q, qd, t, number=1) / count
        qdd_s = acc_jit(ps, q, qd, t)[0]
        if n <= args.max_dense:
            dcount = max(1, count // max(1, n // 8))
            a_d = timeit(acc_runner(_acc, dcount), pd, q, qd, t, repeat=3, number=1) / dcount
            qdd_d = acc_jit(pd, q, qd, t)[0]
            err = float(jnp.max(jnp.abs(qdd_d - qdd_s)) / jnp.max(jnp.abs(qdd_s)))
        else:  # the dense path's compilation alone takes minutes at this size
            a_d = err = np.nan
        steps = max(10, min(2000, 200_000 // (n * 4)))
        run_s = rk4_runner(_acc, dt, steps)
        r_s = timeit(run_s, ps, q, qd, repeat=3, number=1) / steps
        if n <= args.max_dense:
            dsteps = max(2, steps // max(1, n // 8))
            run_d = rk4_runner(_acc, dt, dsteps)
            r_d = timeit(run_d, pd, q, qd, repeat=3, number=1) / dsteps
        else:
            r_d = np.nan
        a_k = r_k = np.nan
        if use_klu:
            acc_k = klujax_problem(ps)
            a_k = timeit(acc_runner(acc_k, count), ps, q, qd, t, number=1) / count
            run_k = rk4_runner(acc_k, dt, steps)
            r_k = timeit(run_k, ps, q, qd, repeat=3, number=1) / steps
        rows.append((n, a_d, a_s, a_k, r_d, r_s, r_k))
        print(
            f"{n:6d} {c.m:5d} {st.bandwidth:3d} {st.block:3d} | {a_d * 1e6:10.1f} "
            f"{a_s * 1e6:10.1f} {a_k * 1e6:9.1f} | {r_d * 1e6:10.1f} {r_s * 1e6:10.1f} "
            f"{r_k * 1e6:9.1f}  {err:.1e}",
            flush=True,
        )
    ns = [r[0] for r in rows]
    big = [i for i, n in enumerate(ns) if n >= 16]
    names = ["acc dense", "acc sparse", "acc klu", "rk4 dense", "rk4 sparse", "rk4 klu"]
    print("log-log slope over bodies >= 16:")
    for k, name in enumerate(names, start=1):
        print(f"  {name:10s} {slope([ns[i] for i in big], [rows[i][k] for i in big]):.2f}")
    cross = [n for n, a_d, a_s, *_ in rows if np.isfinite(a_d) and a_s < a_d]
    print(f"crossover (sparse faster per acceleration) from {min(cross) if cross else None} bodies")


if __name__ == "__main__":
    main()

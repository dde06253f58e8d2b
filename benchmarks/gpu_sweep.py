"""Batched forward runs of the paper's model on whatever JAX sees (a GPU when there is one):
member-simulations per second against the batch size.

Each member is the paper's mechanism (forward, 2 s, 201 outputs, rtol 1e-8) with its own
slider mass and F1 amplitude. The members' equations are built from one set-up: neither varied
number moves the consistent start (masses and force amplitudes do not enter the kinematics),
so a member's problem is the base problem with those two numbers replaced, stacked along a
leading axis; the script checks this against the full set-up and single run of three members
(relative difference printed, must be <= 1e-10). The time is that of the batched integration
(``sweep``'s one-program path, ``batch_size`` members vectorized at a time), measured on the
second call (the first compiles), ``block_until_ready`` included; set-up and finishing are
timed separately, per member, on 16 members.

The guard of the Schur complement at singular positions (a damped SVD solve) decides once
per batch in a sweep (the default). Diagnostics: ``--variant select`` guards member by member
(under ``vmap`` its ``lax.cond`` becomes a select that runs the SVD at every step of every
member: the program before the any-member guard); ``--variant nofallback`` removes the guard
(the floor).

``--full 1000 10000`` also times the whole ``md.sweep`` of that many members (set-up,
integration and finishing into Results, from ``Sweep.seconds``).

``--linear-solver dense`` factors with LAPACK (cuSOLVER on a GPU); ``unrolled:16`` writes the
factorizations out as straight-line code up to 16 rows (the paper's model has 10).

Run: ``python benchmarks/gpu_sweep.py 1024 10000 [--variant default|nofallback] [--full N]``
(``MIXDYN_NO_CACHE=1`` for a variant other than the default: programs are cached by structure).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("members", nargs="*", type=int, default=[1024])
    ap.add_argument("--variant", default="default", choices=["default", "select", "nofallback"])
    ap.add_argument("--batch-size", type=int, default=0, help="0: all members at once")
    ap.add_argument("--method", default="projection")
    ap.add_argument(
        "--linear-solver", default="auto", help="auto, dense, or unrolled:N (up to N rows)"
    )
    ap.add_argument("--full", nargs="*", type=int, default=[], help="whole md.sweep of these")
    a = ap.parse_args()

    import equinox as eqx
    import jax
    import jax.numpy as jnp

    import mixdyn as md
    from fixtures import paper_under_loads
    from mixdyn.analysis._keywords import from_keywords
    from mixdyn.analysis._schedule import _integrate_batch_jit, for_batch
    from mixdyn.analysis._simulate import finish, integrate

    if a.variant == "nofallback":
        import mixdyn.equations._jacobian as jac

        jac.guarded = lambda f, A, rank=None, batched=False: f

    print(f"jax {jax.__version__} on {jax.devices()[0].device_kind} ({jax.default_backend()})")
    print(f"variant {a.variant}, method {a.method}, linear solver {a.linear_solver}")
    solver = a.linear_solver
    if solver.startswith("unrolled:"):
        solver = md.linalg.UnrolledSolver(max_rows=int(solver.split(":")[1]))
    ts = np.linspace(0.0, 2.0, 201)
    opts = dict(method=a.method, rtol=1e-8, linear_solver=solver)
    if a.method == "baumgarte":
        opts = dict(method="baumgarte", dt=1e-3, linear_solver=solver)
    model = paper_under_loads()
    get_m, _ = md.paths.getter(model, "slider.mass")
    get_a, _ = md.paths.getter(model, "F1.law.amplitude")
    value, _ = from_keywords("forward", ts, opts)

    def case_of(m):
        """The integrator's case of member ``m``: prepared, not yet integrated."""
        return value._case(md.prepare(m, value, t0=ts[0]), ts)

    base = case_of(model)
    argument = base.options.as_argument()

    def members(n):
        return np.linspace(0.005, 0.02, n), np.linspace(5.0, 20.0, n)

    def stacked(n):
        mass, amp = members(n)
        problem = base.problem if a.variant == "select" else for_batch(base.problem)
        p = jax.tree.map(lambda x: jnp.broadcast_to(x, (n, *jnp.shape(x))), problem)
        p = eqx.tree_at(
            lambda p: (get_m(p.model), get_a(p.model)), p, (jnp.asarray(mass), jnp.asarray(amp))
        )
        q0 = jnp.broadcast_to(base.q0, (n, *base.q0.shape))
        qd0 = jnp.broadcast_to(base.qd0, (n, *base.qd0.shape))
        return p, q0, qd0

    def run(n, bs):
        p, q0, qd0 = stacked(n)
        out = _integrate_batch_jit(base.options.method, bs, p, ts, q0, qd0, argument)
        return jax.block_until_ready(out)

    # Set-up, single run and finishing of 16 members, each on its own.
    n_check = 16
    mass, amp = members(n_check)
    singles, t_setup, t_run, t_finish = [], 0.0, 0.0, 0.0
    for i in range(n_check):
        mi = eqx.tree_at(lambda m: (get_m(m), get_a(m)), model, (mass[i], amp[i]))
        t0 = time.perf_counter()
        case = case_of(mi)
        t1 = time.perf_counter()
        traj = jax.block_until_ready(integrate(case))
        t2 = time.perf_counter()
        finish(case, traj)
        t3 = time.perf_counter()
        if i > 0:  # the first traces and compiles
            t_setup, t_run, t_finish = t_setup + t1 - t0, t_run + t2 - t1, t_finish + t3 - t2
        singles.append(np.asarray(traj.q))
    k = n_check - 1
    print(
        f"per member, single runs ({k} after a warm-up): set-up {1e3 * t_setup / k:.1f} ms, "
        f"integration {1e3 * t_run / k:.1f} ms, finishing {1e3 * t_finish / k:.1f} ms"
    )
    batch = run(n_check, n_check)
    diff = max(
        float(np.max(np.abs(np.asarray(batch.q[i]) - singles[i])) / np.max(np.abs(singles[i])))
        for i in range(n_check)
    )
    print(f"batched vs single runs, {n_check} members: max relative difference {diff:.2e}")
    steps = np.asarray(batch.steps)
    print(f"accepted steps per member: {steps.min()}..{steps.max()}")

    print("| members | batch size | compile+run s | run s | ms per member | members/s |")
    print("|---|---|---|---|---|---|")
    for n in a.members:
        bs = a.batch_size or n
        t0 = time.perf_counter()
        run(n, bs)
        t1 = time.perf_counter()
        out = run(n, bs)
        t2 = time.perf_counter()
        ok = int(np.sum(np.asarray(out.status) == 0))
        print(
            f"| {n} | {bs} | {t1 - t0:.2f} | {t2 - t1:.3f} | {1e3 * (t2 - t1) / n:.3f} | "
            f"{n / (t2 - t1):,.0f} |" + ("" if ok == n else f" ({n - ok} failed)"),
            flush=True,
        )
    if a.full:
        print("whole md.sweep (set-up, integration, finishing into Results), second call:")
        print("| members | total s | set-up s | integration s | finishing s | ms per member |")
        print("|---|---|---|---|---|---|")
        for n in a.full:
            mass, amp = members(n)
            vary = {"slider.mass": mass, "F1.law.amplitude": amp}
            md.sweep(model, ts, vary=vary, batch_size=n, analysis=value)
            sw = md.sweep(model, ts, vary=vary, batch_size=n, analysis=value)
            sec = sw.seconds
            print(
                f"| {n} | {sec['total']:.2f} | {sec['setup']:.2f} | {sec['integration']:.2f} "
                f"| {sec['finishing']:.2f} | {1e3 * sec['total'] / n:.3f} |"
                + (f" ({len(sw.errors)} failed)" if sw.errors else ""),
                flush=True,
            )


if __name__ == "__main__":
    main()

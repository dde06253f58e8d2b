"""Dense vs sparse linear-solver path beyond the acceleration solve (issue 7), on a pendulum
chain of ``n`` links (default 256, ``tests/fixtures/models.py::horizontal_chain``):

* post-processing of a dynamic run (``_post``: accelerations, reactions, efforts, powers,
  energies) at 101 output times, first call (with compilation) and second call;
* a kinematic analysis of the chain with every link's angle driven (``n`` drivers, square
  Jacobian), 11 output times, first and second call;
* the first call of ``md.forward(chain, linspace(0, 0.01, 11), method="baumgarte", dt=1e-3)``
  (automatic choice: sparse), and a second call.

Run: ``python benchmarks/sparse_all.py [--n 256] [--skip-dense-kinematic]``. Times are wall
clock on this machine; compilation dominates every first call.
"""

from __future__ import annotations

import os

os.environ.setdefault("XLA_FLAGS", "--xla_cpu_enable_concurrency_optimized_scheduler=false")

import argparse
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import mixdyn as md
from fixtures import horizontal_chain as chain
from mixdyn.analysis._problem import Problem
from mixdyn.analysis._simulate import _post
from mixdyn.analysis._start import consistent_state
from mixdyn.equations import Constraints


def timed(f, *a, **k):
    t0 = time.perf_counter()
    out = f(*a, **k)
    if isinstance(out, tuple):
        jax.block_until_ready([x for x in out if isinstance(x, jax.Array)])
    return out, time.perf_counter() - t0


def bench_post(model, n_out=101):
    c = Constraints.of(model)
    q, _ = consistent_state(model, c, 0.0)
    rng = np.random.default_rng(0)
    ts = jnp.linspace(0.0, 0.1, n_out)
    Q = jnp.asarray(np.asarray(q) + 1e-4 * rng.normal(size=(n_out, model.nq)))
    QD = jnp.asarray(rng.normal(size=(n_out, model.nq)))
    out = {}
    for ls in ("dense", "sparse"):
        problem = Problem(model, c.with_linear_solver(ls))
        _, t1 = timed(_post, problem, ts, Q, QD, 0)
        r2, t2 = timed(_post, problem, ts, Q, QD, 0)
        out[ls] = r2
        print(f"_post {ls:6s} {n_out} outputs: first {t1:7.2f} s, second {t2:7.3f} s", flush=True)
    cols = out["dense"][3]
    err = max(
        float(np.max(np.abs(out["sparse"][3][k] - v)) / max(np.max(np.abs(v)), 1e-300))
        for k, v in cols.items()
        if k.endswith((".Fx", ".Fy"))
    )
    print(f"  largest relative difference of the reactions: {err:.1e}")


def bench_kinematic(model, skip_dense=False):
    n = len(model.bodies)
    drivers = [
        md.CoordinateDriver(f"d{i}", f"b{i}", "phi", law=md.Ramp(0.0, 0.1 + 0.001 * i))
        for i in range(n)
    ]
    driven = model.replace(drivers=drivers)
    ts = np.linspace(0.0, 0.1, 11)
    res = {}
    for ls in ("dense", "sparse"):
        if ls == "dense" and skip_dense:
            continue
        kw = {"linear_solver": ls}
        try:
            _, t1 = timed(md.kinematic, driven, ts, **kw)
        except TypeError:  # before issue 7: no linear_solver argument, dense only
            if ls == "sparse":
                continue
            kw = {}
            _, t1 = timed(md.kinematic, driven, ts)
        r2, t2 = timed(md.kinematic, driven, ts, **kw)
        res[ls] = r2
        print(f"kinematic {ls:6s} 11 outputs: first {t1:7.2f} s, second {t2:7.3f} s", flush=True)
    if len(res) == 2:
        d, s = res["dense"], res["sparse"]
        for what in ("q", "qd", "qdd"):
            a, b = getattr(s, what), getattr(d, what)
            e = float(np.max(np.abs(a - b)) / np.max(np.abs(b)))
            print(f"  {what}: largest relative difference {e:.1e}")


def bench_forward(model):
    ts = np.linspace(0.0, 0.01, 11)
    r1, t1 = timed(md.forward, model, ts, method="baumgarte", dt=1e-3)
    _, t2 = timed(md.forward, model, ts, method="baumgarte", dt=1e-3)
    print(
        f"forward baumgarte dt=1e-3 0..0.01 s ({r1.stats.get('linear_solver', 'auto')}): "
        f"first {t1:7.2f} s, second {t2:7.3f} s",
        flush=True,
    )


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--n", type=int, default=256)
    p.add_argument("--only", choices=("post", "kinematic", "forward"), nargs="*")
    p.add_argument("--skip-dense-kinematic", action="store_true")
    a = p.parse_args()
    model = chain(a.n)
    only = a.only or ("post", "kinematic", "forward")
    print(f"chain of {a.n} links: {model.nq} coordinates, {2 * a.n} joint equations")
    if "forward" in only:
        bench_forward(model)
    if "post" in only:
        bench_post(model)
    if "kinematic" in only:
        bench_kinematic(model, a.skip_dense_kinematic)


if __name__ == "__main__":
    main()

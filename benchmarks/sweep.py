"""Sweeps against single runs: the paper's model (forward, 2 s, 201 outputs, rtol 1e-8) over
its slider's mass and F1's amplitude, ``M`` members.

Compares, in one process and after a warm-up of each: ``M`` warm single ``md.forward`` runs
(the peer: what a user writes without a sweep) against ``md.sweep`` member by member (the
CPU default: the single run's program from a thread per core) and in one vectorized program
(``batch_size`` = 1, 8, M). Prints milliseconds per member and the ratio to the single runs.

With ``--cluster``: the same sweep on a local Dask cluster of 1 and of 2 worker processes
(one thread each), and the speed-up of 2 workers over 1; beside it, on the same clusters, the
machine's own: the same number of tasks of a pure NumPy loop (:func:`spin`, no mixdyn), whose
speed-up of 2 workers over 1 is what the processor and the other work on it allow.
``--cluster-only`` leaves out the in-process rows.

Run: ``python benchmarks/sweep.py [M] [--repeat 3] [--cluster] [--cluster-only]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import mixdyn as md
from fixtures import paper_under_loads
from mixdyn.analysis.sweep import vary_models


def model():
    return paper_under_loads()


def best(fn, repeat: int) -> float:
    fn()  # warm-up: traced, compiled or loaded
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def spin(steps: int = 100_000) -> float:
    """A pure NumPy CPU loop (small matrix products, no threads), the peer of a sweep's
    chunk on a cluster; returns a number so that nothing is left out."""
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((24, 24)), rng.standard_normal((24, 24)) / 5
    for _ in range(steps):
        a = a @ b
        a /= np.abs(a).max()
    return float(a.sum())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("members", nargs="?", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cluster", action="store_true")
    ap.add_argument("--cluster-only", action="store_true")
    a = ap.parse_args()
    a.cluster = a.cluster or a.cluster_only
    m, ts = model(), np.linspace(0.0, 2.0, 201)
    vary = {
        "slider.mass": np.linspace(0.005, 0.02, a.members),
        "F1.law.amplitude": np.linspace(5.0, 20.0, a.members),
    }
    members = vary_models(m, vary)
    opts = dict(rtol=1e-8)
    run = md.analyses.Forward(method=md.Projection(rtol=1e-8))
    single = best(lambda: [md.forward(x, ts, **opts) for x in members], a.repeat)
    rows = [("single runs (peer)", single)]
    if not a.cluster_only:
        rows.append(
            (
                "sweep, member by member",
                best(lambda: md.sweep(m, ts, vary=vary, analysis=run), a.repeat),
            )
        )
    for bs in [] if a.cluster_only else sorted({1, 8, a.members}):
        rows.append(
            (
                f"sweep, one program, batch_size {bs}",
                best(
                    lambda bs=bs: md.sweep(m, ts, vary=vary, batch_size=bs, analysis=run), a.repeat
                ),
            )
        )
    if a.cluster:
        from distributed import Client, LocalCluster

        per, pure = {}, {}
        tasks = 8  # the sweep's chunks on 2 workers (four a worker thread)
        for n in (1, 2):
            with (
                LocalCluster(
                    n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None
                ) as cl,
                Client(cl) as c,
            ):
                per[n] = best(
                    lambda c=c: md.sweep(m, ts, vary=vary, client=c, analysis=run), a.repeat
                )
                pure[n] = best(
                    lambda c=c: c.gather([c.submit(spin, pure=False) for _ in range(tasks)]),
                    a.repeat,
                )
                rows.append((f"Dask local cluster, {n} worker(s)", per[n]))
    print(f"{a.members} members, {os.cpu_count()} cores, best of {a.repeat}")
    print("| way | ms per member | ratio to single runs |")
    print("|---|---|---|")
    for name, s in rows:
        print(f"| {name} | {1e3 * s / a.members:.1f} | {s / single:.2f} |")
    if a.cluster:
        print(
            f"2 Dask workers over 1: the sweep {per[1] / per[2]:.2f}x; {tasks} tasks of a pure "
            f"NumPy loop on the same clusters {pure[1] / pure[2]:.2f}x "
            f"({pure[1]:.2f} s / {pure[2]:.2f} s); load {os.getloadavg()[0]:.1f}"
        )


if __name__ == "__main__":
    main()

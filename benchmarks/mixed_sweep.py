"""Mixed sweeps: the paper's mixed run (F1 unknown, the slider's x prescribed by the forward
run's motion; 2 s, 201 outputs, rtol 1e-8) over the crank's torque T2 and the coupler's mass,
``M`` members, on this machine's CPU.

Compares, in one process and after a warm-up: ``M`` single ``md.mixed`` runs (the peer: what
a user writes without a sweep), ``md.sweep`` setting every member up (its consistent start,
solvability and equations: the way before the twelfth session) and ``md.sweep`` sharing the
nominal model's set-up (neither number enters the start, and F1 is collocated with the
slider's motion: ``shares_start``). Prints milliseconds per member (the sweep's set-up part
too) and the ratio to the single runs; best of ``--repeat``.

Run: ``python benchmarks/mixed_sweep.py [M] [--repeat 2]``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import mixdyn as md
from fixtures import paper_under_loads
from mixdyn.analysis.sweep import vary_models

sweep_module = importlib.import_module("mixdyn.analysis.sweep")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("members", nargs="?", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=2)
    a = ap.parse_args()
    paper, ts = paper_under_loads(), np.linspace(0.0, 2.0, 201)
    fwd = md.forward(paper, ts, rtol=1e-10, atol=1e-10)
    kw = dict(prescribed=[md.prescribe(fwd, "slider.x")], unknown=["F1"], rtol=1e-8)
    vary = {
        "T2.law.value": np.linspace(480.0, 520.0, a.members),
        "coupler.mass": np.linspace(0.02, 0.03, a.members),
    }
    members = vary_models(paper, vary)

    def single():
        t0 = time.perf_counter()
        for m in members:
            md.mixed(m, ts, **kw)
        return {"total": time.perf_counter() - t0}

    def sweep():
        run = md.analyses.Mixed(
            prescribed=kw["prescribed"], unknown=kw["unknown"], method=md.Projection(rtol=1e-8)
        )
        return md.sweep(paper, ts, vary=vary, analysis=run).seconds

    def best(fn):
        fn()  # warm-up: traced, compiled or loaded
        return min((fn() for _ in range(a.repeat)), key=lambda s: s["total"])

    shares = sweep_module.shares_start
    rows = [("single md.mixed runs (peer)", best(single))]
    sweep_module.shares_start = lambda *args, **kwargs: False
    try:
        rows.append(("md.sweep, every member set up", best(sweep)))
    finally:
        sweep_module.shares_start = shares
    rows.append(("md.sweep, one shared set-up", best(sweep)))
    peer = rows[0][1]["total"]
    print(f"{a.members} members, best of {a.repeat}")
    print("| way | ms per member | of which set-up | ratio to single runs |")
    print("|---|---|---|---|")
    for name, s in rows:
        setup = f"{1e3 * s['setup'] / a.members:.1f}" if "setup" in s else ""
        ms = 1e3 * s["total"] / a.members
        print(f"| {name} | {ms:.1f} | {setup} | {s['total'] / peer:.2f} |")


if __name__ == "__main__":
    main()

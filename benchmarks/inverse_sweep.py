"""The CPU-side work of a large inverse-dynamics sweep held as arrays, against member by
member.

The slider-crank of the tests (crank driven at 2 rad/s, 51 outputs over 1 s), ``M``
members (default 10,000) over the slider's mass and the rod's inertia: the members share
the drivers' motion, so ``md.sweep`` runs member 0's kinematics once and one vectorized
program post-processes every member along that motion (its efforts and reactions). Prints,
in CPU seconds of this process (``time.process_time``) and wall seconds: the sweep's
set-up, its program (``post-processing``), its finishing and the whole call; every column
as (M, N) arrays (``Sweep.columns``); and the member-by-member path (each member's model,
its ``md.inverse`` run through the sweep's member-by-member runner, its ``Result``) on
``K`` members (default 256), scaled to ``M``, with the ratio of the two.

Run: ``python benchmarks/inverse_sweep.py [M] [--members-by-member K]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import mixdyn as md
from fixtures import slider_crank
from mixdyn.analysis import _members
from mixdyn.analysis.sweep import vary_models

T = np.linspace(0.0, 1.0, 51)
ANALYSIS = md.analyses.Inverse()


def vary(m: int) -> dict:
    rng = np.random.default_rng(0)
    return {"slider.mass": rng.uniform(0.5, 2.0, m), "rod.inertia": rng.uniform(0.005, 0.02, m)}


def timed(fn):
    c, w = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c, time.perf_counter() - w


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("members", nargs="?", type=int, default=10_000)
    ap.add_argument("--members-by-member", type=int, default=256)
    a = ap.parse_args()
    model = slider_crank()
    md.sweep(model, T, vary=vary(64), analysis=ANALYSIS)  # warm-up: the programs compiled
    print(f"load average: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    sw, cpu, wall = timed(lambda: md.sweep(model, T, vary=vary(a.members), analysis=ANALYSIS))
    assert not sw.errors, sw.errors
    _, cpu_cols, _ = timed(sw.columns)
    s = sw.seconds
    side = s["setup"] + s["finishing"]
    print(f"\narray path, {a.members:,} members [s]")
    print(f"  whole md.sweep: CPU {cpu:.3f}, wall {wall:.3f}")
    print(f"  set-up {s['setup']:.3f}, post-processing program {s['post-processing']:.3f}, "
          f"finishing {s['finishing']:.3f} (wall)")  # fmt: skip
    print(f"  CPU-side (set-up + finishing), wall: {side:.3f}")
    print(f"  every column as (M, N) arrays, CPU: {cpu_cols:.3f}")
    k = a.members_by_member
    members = vary_models(model, vary(k))
    _members.run_members(members[:8], T, ANALYSIS)  # warm-up
    outcomes, cpu_k, wall_k = timed(lambda: _members.run_members(members, T, ANALYSIS))
    assert all(r is not None for r, _ in outcomes)
    scale = a.members / k
    print(f"\nmember by member, {k} members scaled to {a.members:,} [s]: CPU {cpu_k * scale:.2f}, "
          f"wall {wall_k * scale:.2f}")  # fmt: skip
    print(f"whole sweep, member by member / array path (CPU): {cpu_k * scale / cpu:.0f}x")
    print(f"load average: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()

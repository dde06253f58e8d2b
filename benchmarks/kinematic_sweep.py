"""A kinematic sweep held as arrays against member by member.

``M`` slider-cranks (default 256) of other rod lengths, crank speeds and start angles (each
member its own start), kinematic over 1 s (51 outputs). In one process, after a warm-up of
each, taking turns: ``md.sweep(models=..., analysis=Kinematic())`` (the array path: each
member prepared, one vectorized program running the scan, results built when read; every
column read as (member, time) arrays by ``Sweep.columns``) against the member-by-member path
that ``md.sweep`` takes otherwise (:func:`mixdyn.analysis._members.run_members`: each member
prepared and run by the single run's program, its ``Result`` built; every column gathered
from the results). Prints CPU seconds of this process (``time.process_time``) and wall
seconds per repeat, and the largest difference between the two paths' columns.

Run: ``python benchmarks/kinematic_sweep.py [M] [--repeat 3] [--threads T]``.
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

T = np.linspace(0.0, 1.0, 51)
VALUE = md.analyses.Kinematic()


def models(m: int) -> list[md.Model]:
    rng = np.random.default_rng(0)
    return [
        slider_crank(l=float(l), omega=float(w), theta0=float(th))
        for l, w, th in zip(
            rng.uniform(0.2, 0.4, m), rng.uniform(1, 5, m), rng.uniform(0, 1, m), strict=True
        )
    ]


def as_arrays(members, threads):
    sw = md.sweep(models=members, t=T, analysis=VALUE, threads=threads)
    return sw.columns()[0]


def member_by_member(members, threads):
    outcomes = _members.run_members(members, T, VALUE, threads=threads)
    sw = md.Sweep([r for r, _ in outcomes], {}, [], {})
    return sw.columns()[0]


def timed(fn, *args) -> tuple[float, float, dict]:
    c, w = time.process_time(), time.perf_counter()
    out = fn(*args)
    return time.process_time() - c, time.perf_counter() - w, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("members", nargs="?", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=None)
    a = ap.parse_args()
    members = models(a.members)
    as_arrays(members, a.threads), member_by_member(members, a.threads)  # warm-up
    rows, diff = [], 0.0
    for _ in range(a.repeat):
        ca, wa, x = timed(as_arrays, members, a.threads)
        cb, wb, y = timed(member_by_member, members, a.threads)
        rows.append((ca, wa, cb, wb))
        diff = max(diff, max(float(np.max(np.abs(x[c] - y[c]))) for c in x))
    print(f"{a.members} members, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    print("| repeat | arrays CPU [s] | arrays wall [s] | member by member CPU [s] | wall [s] |")
    print("|---|---|---|---|---|")
    for k, (ca, wa, cb, wb) in enumerate(rows):
        print(f"| {k + 1} | {ca:.2f} | {wa:.2f} | {cb:.2f} | {wb:.2f} |")
    print(f"largest difference between the paths' columns: {diff:.1e}")


if __name__ == "__main__":
    main()

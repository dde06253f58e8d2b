"""A kinematic or quasi-static sweep held as arrays against member by member.

``M`` slider-cranks (default 256) of other rod lengths, crank speeds and start angles (each
member its own start), kinematic over 1 s (51 outputs). In one process, after a warm-up of
each on 64 members (the programs compiled), taking turns:
``md.sweep(models=..., analysis=Kinematic())`` (the array path: each member prepared, one
vectorized program running the scan, results built when read; every column read as
(member, time) arrays by ``Sweep.columns``) against the member-by-member path that
``md.sweep`` takes otherwise (:func:`mixdyn.analysis._members.run_members`: each member
prepared and run by the single run's program, its ``Result`` built; every column gathered
from the results). Prints CPU seconds of this process (``time.process_time``) and wall
seconds per repeat, their ratios, and the largest difference between the two paths'
columns.

``--statics``: the quasi-static analysis instead, over 1 s (``--outputs``, default 6
outputs), the slider pushed back by a gas force of 20-80 N: the array path's one program
running every member's Newton iterations at every output time, against each member's
single run (Newton's method driven from Python, a few compiled calls an iteration).
``--shared``: the members of one slider-crank over the gas force and the slider's mass
(``vary=``: forces and masses only, one start shared by every member) instead of other
geometries. The array path's set-up, program and finishing are printed too (its
``Sweep.seconds``, wall).

``--arrays-only``: the array path alone (no member-by-member run), its CPU and wall times and
their parts.

Run: ``python benchmarks/kinematic_sweep.py [M] [--repeat 3] [--threads T] [--statics
[--shared] [--outputs N]] [--arrays-only]``.
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
from mixdyn.analysis._schedule import CHUNK
from mixdyn.analysis.sweep import vary_models


def models(m: int, gas: bool) -> list[md.Model]:
    rng = np.random.default_rng(0)
    out = [
        slider_crank(l=float(l), omega=float(w), theta0=float(th))
        for l, w, th in zip(
            rng.uniform(0.2, 0.4, m), rng.uniform(1, 5, m), rng.uniform(0, 1, m), strict=True
        )
    ]
    if gas:
        push = rng.uniform(20.0, 80.0, m)
        out = [with_gas(x, float(f)) for x, f in zip(out, push, strict=True)]
    return out


def with_gas(model: md.Model, force: float) -> md.Model:
    """``model`` with a gas force ``force`` [N] pushing its slider back (along -x)."""
    gas = md.PointForce("gas", "slider", along=(-1, 0), law=md.Constant(force))
    return md.Model(
        bodies=model.bodies,
        joints=model.joints,
        drivers=model.drivers,
        forces=[gas],
        units=md.SI,
        name=model.name,
    )


def shared_vary(m: int) -> dict:
    rng = np.random.default_rng(0)
    return {"gas.law.value": rng.uniform(20.0, 80.0, m), "slider.mass": rng.uniform(0.5, 2, m)}


def as_arrays(case, value, t, threads):
    members, vary = case
    if vary is None:
        sw = md.sweep(models=members, t=t, analysis=value, threads=threads)
    else:
        sw = md.sweep(members, t, vary=vary, analysis=value, threads=threads)
    return sw.columns()[0], sw.seconds


def member_by_member(case, value, t, threads):
    members, vary = case
    if vary is not None:
        members = vary_models(members, vary)
    outcomes = _members.run_members(members, t, value, threads=threads)
    sw = md.Sweep([r for r, _ in outcomes], {}, [], {})
    return sw.columns()[0], {}


def timed(fn, *args) -> tuple[float, float, tuple]:
    c, w = time.process_time(), time.perf_counter()
    out = fn(*args)
    return time.process_time() - c, time.perf_counter() - w, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("members", nargs="?", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--statics", action="store_true")
    ap.add_argument("--shared", action="store_true")
    ap.add_argument("--outputs", type=int, default=None)
    ap.add_argument("--arrays-only", action="store_true", help="the array path alone")
    a = ap.parse_args()
    if a.statics:
        value = md.analyses.QuasiStatic()
        t = np.linspace(0.0, 1.0, a.outputs or 6)
    else:
        value = md.analyses.Kinematic()
        t = np.linspace(0.0, 1.0, a.outputs or 51)
    if a.shared:
        case = (with_gas(slider_crank(), 50.0), shared_vary(a.members))
    else:
        case = (models(a.members, a.statics), None)
    few = (case[0][:CHUNK], None) if case[1] is None else (case[0], shared_vary(CHUNK))
    if a.arrays_only:
        as_arrays(few, value, t, a.threads)  # warm-up
        for k in range(a.repeat):
            ca, wa, (_, parts) = timed(as_arrays, case, value, t, a.threads)
            split = ", ".join(f"{p} {parts[p]:.3f}" for p in ("setup", "equilibria", "finishing")
                              if p in parts)  # fmt: skip
            print(f"{a.members} members, array path, repeat {k + 1}: CPU {ca:.2f} s, wall "
                  f"{wa:.2f} s ({split} s wall), load {os.getloadavg()[0]:.1f}")  # fmt: skip
        return
    as_arrays(few, value, t, a.threads), member_by_member(few, value, t, a.threads)  # warm-up
    rows, diff = [], 0.0
    for _ in range(a.repeat):
        ca, wa, (x, parts) = timed(as_arrays, case, value, t, a.threads)
        cb, wb, (y, _) = timed(member_by_member, case, value, t, a.threads)
        rows.append((ca, wa, cb, wb, parts))
        diff = max(diff, max(float(np.max(np.abs(x[c] - y[c]), initial=0.0)) for c in x))
    what = "quasi-static" if a.statics else "kinematic"
    how = "one shared start" if a.shared else "each its own start"
    print(f"{a.members} members ({what}, {how}, {len(t)} outputs), {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.1f}")  # fmt: skip
    head = (
        "repeat",
        "arrays CPU [s]",
        "arrays wall [s]",
        "member by member CPU [s]",
        "wall [s]",
        "CPU ratio",
        "wall ratio",
        "arrays: set-up / program / finishing [s]",
    )
    print("| " + " | ".join(head) + " |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for k, (ca, wa, cb, wb, parts) in enumerate(rows):
        split = " / ".join(f"{parts[p]:.3f}" for p in ("setup", "equilibria", "finishing")
                           if p in parts)  # fmt: skip
        print(f"| {k + 1} | {ca:.2f} | {wa:.2f} | {cb:.2f} | {wb:.2f} | {cb / ca:.1f} "
              f"| {wb / wa:.1f} | {split} |")  # fmt: skip
    print(f"largest difference between the paths' columns: {diff:.1e}")


if __name__ == "__main__":
    main()

"""A model file's sweep against its members run singly: ``examples/antonya_sweep.yaml`` (the
paper's model, forward over 2 s, 101 outputs, rtol 1e-8, F1's amplitude x the slider's mass).

In one process, after a warm-up of each, taking turns: the sweep run executed as ``mixdyn
run`` executes it (members made, run, summaries; no files written) against the peer, each
member's model built from the file beforehand and run by ``md.forward`` with the swept run's
keywords (what a user writes without a sweep). Prints the seconds of both and their ratio
per repeat, the median and spread of the ratio, the sweep's first call (compiling or loading
its programs) and how far the members' columns are from their single runs.

Run: ``python benchmarks/file_sweep.py [--members 200] [--repeat 3] [--batch-size B]``
(``--members``: that many of the file's 1,000, spread over its grid).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pathlib
import time

import numpy as np

import mixdyn as md
import mixdyn.io as mio
from mixdyn.runs import Runner, setup
from mixdyn.runs import sweep as file_sweep

FILE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "antonya_sweep.yaml"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--members", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--batch-size", type=int, default=None)
    a = ap.parse_args()
    runner = Runner(mio.read(FILE))
    plan = runner.plans["sweep"]
    pick = np.unique(np.linspace(0, plan.members - 1, a.members).round().astype(int))
    spec = plan.spec.model_copy(update={"batch_size": a.batch_size})
    plan = dataclasses.replace(plan, spec=spec, values={k: v[pick] for k, v in plan.values.items()})
    calls = []
    for i in range(plan.members):  # the peer's models, built before timing
        member = file_sweep._member_runner(runner, plan, i)
        calls.append(setup.call(member, member.plans[plan.base.name], {}, checked=False))

    def singly():
        return [md.forward(model, plan.times, **kw) for _, model, kw in calls]

    def swept():
        return file_sweep.execute(runner, plan)

    t0 = time.perf_counter()
    first = swept()  # warm-up: compiled or loaded
    warm_up = time.perf_counter() - t0
    singles = singly()
    deviation = max(
        float(np.max(np.abs(first.sweep[i][c] - r[c])) / np.max(np.abs(r[c])))
        for i, r in enumerate(singles)
        for c in ("slider.x", "crank.phi", "D.Fx")
    )
    rows = []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        swept()
        t1 = time.perf_counter()
        singly()
        t2 = time.perf_counter()
        rows.append((t1 - t0, t2 - t1))
    ratios = [s / p for s, p in rows]
    load = os.getloadavg()[0]
    print(
        f"{plan.members} members, {os.cpu_count()} cores, load {load:.1f}, "
        f"batch_size {a.batch_size}"
    )
    print("| repeat | file sweep [s] | members singly [s] | file sweep / singly |")
    print("|---|---|---|---|")
    for k, ((s, p), r) in enumerate(zip(rows, ratios, strict=True)):
        print(f"| {k + 1} | {s:.2f} | {p:.2f} | {r:.2f} |")
    print(
        f"ratio median {np.median(ratios):.2f} (min {min(ratios):.2f}, max {max(ratios):.2f}); "
        f"the sweep's first call {warm_up:.1f} s; largest difference of a member's columns to "
        f"its single run {deviation:.1e} of the column's largest value"
    )


if __name__ == "__main__":
    main()

"""The CPU-side work of a large sweep held as arrays, against member by member.

The paper's model (forward, rtol 1e-8) over its slider's mass and F1's amplitude, ``M``
members (default 10,000) sharing one start. The integration is not the subject here (it is
the accelerator's part): the span is short (3 outputs over 10 ms) so that the run stays
short on a CPU. Prints, in CPU seconds of this process (``time.process_time``: on a machine
loaded by other work it moves far less than wall clock) and wall seconds:

- the array path (``md.sweep`` of ``M`` members): checking the varied values, the shared
  set-up and the stacked problem (set-up), the chunks' problems cut from it (stacking: timed
  alone), the screen of every member and the flagged ones finished (finishing), the
  integration, and every column of every member as (M, N) arrays (``Sweep.columns``);
- the member-by-member path on ``K`` members (default 256), run as ``md.sweep`` ran them
  before the array path (:func:`vary_models`, one model a member; the shared start swapped
  into each member's problem; each member's stacked leaf by leaf; each member's
  ``Result`` built and checked), scaled to ``M``; and the ratio.

With ``--mixed``: the paper's mixed run (F1 unknown, the slider's x prescribed by the
forward run) over the crank's torque T2 and the coupler's mass.

Run: ``python benchmarks/sweep_arrays.py [M] [--members-by-member K] [--mixed]``.
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
from mixdyn.analysis import _members, _stacked
from mixdyn.analysis._schedule import CHUNK
from mixdyn.analysis.sweep import varied_leaves, vary_models

T = np.linspace(0.0, 0.01, 3)
ANALYSIS = md.analyses.Forward(method=md.Projection(rtol=1e-8, atol=1e-10))


def vary(m: int) -> dict:
    rng = np.random.default_rng(0)
    if isinstance(ANALYSIS, md.analyses.Mixed):  # F1 is unknown: the crank's torque varies
        return {
            "T2.law.value": rng.uniform(480.0, 520.0, m),
            "coupler.mass": rng.uniform(0.02, 0.03, m),
        }
    return {
        "slider.mass": rng.uniform(0.005, 0.02, m),
        "F1.law.amplitude": rng.uniform(-25.0, 25.0, m),
    }


def mixed(model) -> md.analyses.Mixed:
    """The paper's mixed run: F1 unknown, the slider's x prescribed by the forward run."""
    fwd = md.forward(model, T, rtol=1e-10, atol=1e-10)
    return md.analyses.Mixed(
        prescribed=[md.prescribe(fwd, "slider.x")],
        unknown=["F1"],
        method=md.Projection(rtol=1e-8, atol=1e-10),
    )


class Clock:
    """CPU and wall seconds of a block."""

    def __enter__(self):
        self.cpu, self.wall = time.process_time(), time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.cpu = time.process_time() - self.cpu
        self.wall = time.perf_counter() - self.wall


def array_path(model, m: int) -> dict:
    v = vary(m)
    with Clock() as whole:
        sw = md.sweep(model, T, vary=v, analysis=ANALYSIS)
    assert not sw.errors, sw.errors
    # The phases' CPU time, each again alone: set-up, stacking, screen and finishing.
    with Clock() as setup:
        positions, values, _ = varied_leaves(model, v)
        stacked = _stacked.stack(model, list(v), positions, values, ANALYSIS, T, None)
    with Clock() as stacking:
        for first in range(0, m, CHUNK):
            stacked.problems(np.arange(first, min(first + CHUNK, m)))
    with Clock() as finishing:
        flagged = _stacked.screen(sw.stacked, sw.arrays)
    with Clock() as columns:
        cols, _ = sw.columns()
    with Clock() as table:
        sw.table()
    with Clock() as one:
        sw[m // 2]
    assert not flagged.any() and cols["slider.x"].shape == (m, len(T))
    return {
        "sweep (wall)": whole.wall,
        "sweep (CPU)": whole.cpu,
        "integration (wall)": sw.seconds["integration"],
        "set-up (CPU)": setup.cpu,
        "stacking (CPU)": stacking.cpu,
        "finishing (CPU)": finishing.cpu,
        "CPU-side (set-up + stacking + finishing)": setup.cpu + stacking.cpu + finishing.cpu,
        "every column as (M, N) arrays (CPU)": columns.cpu,
        "every column as a long table (CPU)": table.cpu,
        "one member's Result when read (CPU)": one.cpu,
    }


def member_by_member(model, k: int, m: int) -> dict:
    """The CPU-side work of ``k`` members as the member-by-member path does it (chunks of
    :data:`CHUNK`, one program shape), scaled to ``m`` members."""
    v = vary(k)
    models_cpu = setup_cpu = finishing_cpu = 0.0
    for first in range(0, k, CHUNK):
        part = {p: x[first : first + CHUNK] for p, x in v.items()}
        with Clock() as c:
            members = vary_models(model, part)
        models_cpu += c.cpu
        seconds: dict = {}
        cpu0 = time.process_time()
        _members.run_members(
            members, T, ANALYSIS, batch_size=CHUNK, same_start=True, seconds=seconds
        )
        whole = time.process_time() - cpu0
        # run_members' wall split, applied to its CPU time
        wall = seconds["setup"] + seconds["integration"] + seconds["finishing"]
        setup_cpu += whole * seconds["setup"] / wall
        finishing_cpu += whole * seconds["finishing"] / wall
    scale = m / k
    total = (models_cpu + setup_cpu + finishing_cpu) * scale
    return {
        "member models (CPU)": models_cpu * scale,
        "set-up (CPU)": setup_cpu * scale,
        "finishing, a Result a member (CPU)": finishing_cpu * scale,
        "CPU-side (models + set-up + finishing)": total,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("members", nargs="?", type=int, default=10_000)
    parser.add_argument("--members-by-member", type=int, default=4 * CHUNK)
    parser.add_argument("--mixed", action="store_true", help="the paper's mixed run")
    args = parser.parse_args()
    model = paper_under_loads()
    if args.mixed:
        global ANALYSIS
        ANALYSIS = mixed(model)
    md.sweep(model, T, vary=vary(CHUNK), analysis=ANALYSIS)  # warm-up: the chunk's program
    print(f"load average: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    arrays = array_path(model, args.members)
    print(f"\narray path, {args.members:,} members (s)")
    for name, s in arrays.items():
        print(f"  {name:44s} {s:8.3f}")
    old = member_by_member(model, args.members_by_member, args.members)
    print(f"\nmember by member, {args.members_by_member} members scaled to {args.members:,} (s)")
    for name, s in old.items():
        print(f"  {name:44s} {s:8.3f}")
    ratio = (
        old["CPU-side (models + set-up + finishing)"]
        / arrays["CPU-side (set-up + stacking + finishing)"]
    )
    print(f"\nCPU-side work, member by member / array path: {ratio:.0f}x")
    print(f"load average: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()

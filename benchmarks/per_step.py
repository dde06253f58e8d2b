"""Per-step speed of small mechanisms: this tree against another revision of mixdyn.

Each case runs warm (after a first, compiling call) in a fresh process per revision, best of
``--repeat`` calls; with ``--rounds`` the two revisions' processes take turns that many times
and each case keeps its best. The table gives the time per call and the ratio this / other:
wall clock, or with ``--cpu`` the process's CPU time (on a machine loaded by other work, CPU
time moves far less than wall clock). The other revision is checked out into a temporary git
worktree (default: ``HEAD``, i.e. the last commit, so the ratio measures uncommitted work;
pass ``--rev`` for another). Set
``XLA_FLAGS=--xla_cpu_enable_concurrency_optimized_scheduler=false`` as the tests do.

    python benchmarks/per_step.py --rev 8576fb5 --rounds 3 --cpu
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]

CASE_CODE = r"""
import json, sys, time
sys.path.insert(0, {tests!r})
import numpy as np
import mixdyn as md
from fixtures import four_bar, pendulum_chain, slider_crank

def chain(method, n, T, **kw):
    m = pendulum_chain(n)
    t = np.linspace(0, T, 11)
    return lambda: md.forward(m, t, method=method, dt=1e-3, energy_tol=None, **kw)

def projection():
    m = slider_crank()
    free = m.replace(drivers=())
    t = np.linspace(0, 2, 201)
    return lambda: md.forward(free, t, rtol=1e-8, atol=1e-10, energy_tol=None)

def moving(method):
    m = pendulum_chain(5)
    t = np.linspace(0, 2, 201)
    return lambda: md.forward(m, t, method=method, rtol=1e-8, atol=1e-10, energy_tol=None)

def kinematic():
    m = four_bar()
    t = np.linspace(0, 2, 1001)
    return lambda: md.kinematic(m, t)

CASES = {{
    "chain-2 baumgarte 1 s (1000 steps)": chain("baumgarte", 2, 1.0),
    "chain-3 baumgarte 1 s (1000 steps)": chain("baumgarte", 3, 1.0),
    "chain-3 generalized-alpha 1 s (1000 steps)": chain("generalized-alpha", 3, 1.0),
    "chain-4 baumgarte 1 s (1000 steps)": chain("baumgarte", 4, 1.0),
    "chain-4 generalized-alpha 1 s (1000 steps)": chain("generalized-alpha", 4, 1.0),
    "chain-16 baumgarte 0.2 s (200 steps)": chain("baumgarte", 16, 0.2),
    "slider-crank projection tsit5 2 s": projection(),
    "chain-5 projection tsit5 2 s (272 steps)": moving("projection"),
    "chain-5 partitioning tsit5 2 s (272 steps)": moving("partitioning"),
    "four-bar kinematic 1001 times": kinematic(),
}}
out = {{}}
for name, run in CASES.items():
    try:
        r = run()
        best = float("inf")
        for _ in range({repeat}):
            t0 = {clock}()
            run()
            best = min(best, {clock}() - t0)
        out[name] = {{"s": best, "steps": r.stats.get("steps", r.stats.get("newton_iterations"))}}
    except Exception as e:  # a case the other revision cannot run
        out[name] = {{"error": f"{{type(e).__name__}}: {{e}}"}}
print("JSON" + json.dumps(out))
"""


def run_tree(src: pathlib.Path, tests: pathlib.Path, repeat: int, cpu: bool = False) -> dict:
    clock = "time.process_time" if cpu else "time.perf_counter"
    code = CASE_CODE.format(tests=str(tests), repeat=repeat, clock=clock)
    env = dict(os.environ, PYTHONPATH=str(src), MIXDYN_NO_CACHE="1")
    env.setdefault("XLA_FLAGS", "--xla_cpu_enable_concurrency_optimized_scheduler=false")
    p = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=False
    )
    for line in p.stdout.splitlines():
        if line.startswith("JSON"):
            return json.loads(line[4:])
    raise RuntimeError(p.stderr[-3000:])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default="HEAD", help="the other revision (default HEAD)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=1, help="turns of the two revisions")
    ap.add_argument("--cpu", action="store_true", help="CPU time of the process, not wall")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        wt = pathlib.Path(tmp) / "other"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(wt), args.rev],
            check=True,
            capture_output=True,
        )
        other, this = {}, {}
        try:
            for _ in range(args.rounds):
                turn = {
                    "other": run_tree(wt / "src", wt / "tests", args.repeat, args.cpu),
                    "this": run_tree(ROOT / "src", ROOT / "tests", args.repeat, args.cpu),
                }  # each with its own fixtures
                for best, got in ((other, turn["other"]), (this, turn["this"])):
                    for name, r in got.items():
                        if "s" not in best.get(name, {}) or r.get("s", 1e300) < best[name]["s"]:
                            best[name] = r
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(wt)], check=False
            )
    what = "CPU" if args.cpu else "wall"
    print(f"| case | this tree, {what} [ms] | {args.rev} [ms] | ratio this / {args.rev} |")
    print("|---|---|---|---|")
    for name in this:
        a, b = this[name], other.get(name, {"error": "missing"})
        if "s" in a and "s" in b:
            print(f"| {name} | {1e3 * a['s']:.2f} | {1e3 * b['s']:.2f} | {a['s'] / b['s']:.2f} |")
        else:
            print(f"| {name} | {a.get('error', a.get('s'))} | {b.get('error', b.get('s'))} | - |")


if __name__ == "__main__":
    main()

"""mixdyn against peers, in one run: pendulum chains, the IFToMM double four-bar, and a
work–precision table on Andrews' squeezing mechanism.

Peers (the ``bench`` extra of ``pyproject.toml``; this script installs nothing and skips a peer
that is missing): Exudyn (redundant coordinates like mixdyn: ``ObjectRigidBody2D`` +
``ObjectJointRevolute2D``, its implicit generalized-alpha solver) and MuJoCo (minimal
coordinates: a hinge chain, its RK4 integrator).

1. Chains of 4, 16, 64, 256 links (1 m, 1 kg, released straight at 0.5 rad from the vertical),
   the same fixed step for every code, reported as CPU seconds per simulated second, with the
   energy drift |E(T) - E(0)| to show the runs are comparable (and the tip position after
   0.1 s, the same in every code up to each method's error). mixdyn runs ``baumgarte``
   (classical RK4, like MuJoCo) and ``generalized-alpha`` (like Exudyn); its simulated time
   is capped for the larger chains so that the whole script finishes in ~10 minutes.
2. The IFToMM double four-bar over 10 s against Exudyn (generalized-alpha, rho_inf = 0.95,
   h = 1e-3, as in Exudyn's published example), errors against the exact 1-DOF reduction.
3. Andrews' squeezing mechanism (t = 0.03 s): error against the Test Set for IVP Solvers'
   reference versus CPU time, for each mixdyn integrator and a few tolerances or steps.

Every mixdyn configuration is called twice: the first call's extra time is the compilation
(and model setup), reported apart; the second call is the run time. Tolerances and steps are
passed as JAX scalars, so that one compilation serves every tolerance of a method.

Run: ``python benchmarks/run.py [--quick] [--cpu] [--json out.json]``; the tables are printed as
Markdown. Results and their discussion: ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import os

# Known deadlock of XLA's concurrency-optimized scheduler on this machine (vmapped scans).
os.environ["XLA_FLAGS"] = "--xla_cpu_enable_concurrency_optimized_scheduler=false"

import argparse
import importlib.util
import json
import math
import pathlib
import platform
import sys
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np

import mixdyn as md

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: The clock of the timed runs: wall clock, or with ``--cpu`` the process's CPU time (on a
#: machine loaded by other work, CPU time moves far less than wall clock).
CLOCK = time.perf_counter
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import nfourbar  # noqa: E402

from fixtures import (  # noqa: E402
    ANDREWS_BODIES,
    andrews_angles,
    andrews_mechanism,
    pendulum_chain,
)

G = 9.81
THETA0 = 0.5  # initial angle of the chains from the downward vertical [rad]
ANDREWS_REF = np.array(
    [
        0.1581077119629904e2,
        -0.1575637105984298e2,
        0.4082224013073101e-1,
        -0.5347301163226948e0,
        0.5244099658805304e0,
        0.5347301163226948e0,
        0.1048080741042263e1,
    ]
)  # Test Set for IVP Solvers, andrews.f, q(0.03)


def have(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


def machine() -> dict:
    cpu = "unknown"
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    info = {
        "cpu": cpu,
        "nproc": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "python": platform.python_version(),
        "jax": jax.__version__,
        "mixdyn": md.__version__,
    }
    for peer in ("exudyn", "mujoco"):
        if have(peer):
            mod = __import__(peer)
            info[peer] = getattr(mod, "__version__", None) or _exudyn_version(mod)
    return info


def _exudyn_version(exu) -> str:
    try:
        return exu.config.Version()
    except Exception:  # older Exudyn
        return exu.GetVersionString()


def timed(fn, repeat: int = 2):
    """``(first, best_of_rest, result)``: times of ``fn()`` by :data:`CLOCK` [s]."""
    t0 = CLOCK()
    out = fn()
    first = CLOCK() - t0
    rest = []
    for _ in range(repeat - 1):
        t0 = CLOCK()
        out = fn()
        rest.append(CLOCK() - t0)
    return first, (min(rest) if rest else first), out


# --------------------------------------------------------------------------- chains
def chain_energy(x, y, vx, vy, omega, m=1.0, J=1.0 / 12.0):
    """Total energy of uniform links from centre states (arrays over links)."""
    return float(np.sum(0.5 * m * (vx**2 + vy**2) + 0.5 * J * omega**2 + m * G * y))


def chain_mixdyn(n: int, T: float, h: float | None, method: str, **extra) -> dict:
    """mixdyn on the chain of ``n`` links over ``T`` s: fixed step ``h`` or, for the adaptive
    methods, ``extra`` options (``solver``, ``rtol``, ``atol``)."""
    model = pendulum_chain(n, theta0=THETA0)
    ts = np.array([0.0, min(0.1, T), T]) if T > 0.1 else np.array([0.0, T])
    opts = dict(method=method, **extra)
    if h is not None:
        opts["dt"] = jnp.asarray(h)
    if method == "generalized-alpha":
        opts.setdefault("rho_inf", 0.9)
    first, run, res = timed(lambda: md.forward(model, ts, **opts))
    E = res["energy.total"]
    tip = res.point(f"link{n - 1}.B")[0]
    return {
        "code": "mixdyn",
        "method": method,
        "linear_solver": res.stats["linear_solver"],  # the path the run took
        "n": n,
        "T": T,
        "compile_s": first - run,
        "run_s": run,
        "s_per_sim_s": run / T,
        "E0": float(E[0]),
        "drift": float(abs(E[-1] - E[0])),
        "tip_0.1": tip[1].tolist() if len(ts) == 3 else None,
        "tip_T": tip[-1].tolist(),
        "steps": int(res.stats["steps"]),
    }


def chain_exudyn(n: int, T: float, h: float, sparse: bool | None = None) -> dict:
    """Exudyn's generalized-alpha on the chain (``EigenSparse`` from 16 links unless
    ``sparse`` says otherwise)."""
    import exudyn as exu
    from exudyn.itemInterface import (
        LoadMassProportional,
        MarkerBodyMass,
        MarkerBodyPosition,
        MarkerBodyRigid,
        NodeRigidBody2D,
        ObjectGround,
        ObjectJointRevolute2D,
        ObjectRigidBody2D,
    )

    def build():
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        s, c = math.sin(THETA0), math.cos(THETA0)
        ground = mbs.AddObject(ObjectGround())
        upper = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
        nodes = []
        for k in range(n):
            node = mbs.AddNode(
                NodeRigidBody2D(
                    referenceCoordinates=[(k + 0.5) * s, -(k + 0.5) * c, THETA0 - math.pi / 2]
                )
            )
            body = mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=1.0, inertia=1 / 12))
            mass = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
            mbs.AddLoad(LoadMassProportional(markerNumber=mass, loadVector=[0, -G, 0]))
            a = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[-0.5, 0, 0]))
            mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[upper, a]))
            upper = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0.5, 0, 0]))
            nodes.append(node)
        mbs.Assemble()
        return SC, mbs, nodes

    def settings(t_end):
        ss = exu.SimulationSettings()
        ss.timeIntegration.numberOfSteps = round(t_end / h)
        ss.timeIntegration.endTime = t_end
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        ss.solution.sensors.writePeriod = t_end
        ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
        ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
        ss.timeIntegration.newton.useModifiedNewton = True
        if (n >= 16) if sparse is None else sparse:
            ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse
        return ss

    def energy(mbs, nodes):
        ov = exu.OutputVariableType
        p = np.array([mbs.GetNodeOutput(nd, ov.Position) for nd in nodes])
        v = np.array([mbs.GetNodeOutput(nd, ov.Velocity) for nd in nodes])
        w = np.array([mbs.GetNodeOutput(nd, ov.AngularVelocity)[2] for nd in nodes])
        return chain_energy(p[:, 0], p[:, 1], v[:, 0], v[:, 1], w), p, nodes

    def tip(mbs, nodes):
        ov = exu.OutputVariableType
        p = mbs.GetNodeOutput(nodes[-1], ov.Position)
        phi = mbs.GetNodeOutput(nodes[-1], ov.Coordinates)[2] + THETA0 - math.pi / 2
        return [p[0] + 0.5 * math.cos(phi), p[1] + 0.5 * math.sin(phi)]

    _sc, mbs, nodes = build()  # keep the system container alive while solving
    E0 = energy(mbs, nodes)[0]
    t0 = CLOCK()
    mbs.SolveDynamic(settings(T))
    run = CLOCK() - t0
    E1 = energy(mbs, nodes)[0]
    tip_T = tip(mbs, nodes)
    _sc2, mbs2, nodes2 = build()
    mbs2.SolveDynamic(settings(min(0.1, T)))
    return {
        "code": "exudyn",
        "method": "generalized-alpha",
        "n": n,
        "T": T,
        "compile_s": 0.0,
        "run_s": run,
        "s_per_sim_s": run / T,
        "E0": E0,
        "drift": abs(E1 - E0),
        "tip_0.1": tip(mbs2, nodes2),
        "tip_T": tip_T,
    }


def mujoco_chain_xml(n: int, h: float) -> str:
    body = ""
    for k in reversed(range(n)):
        pos = "0 0 0" if k == 0 else "0 0 -1"
        body = (
            f'<body name="link{k}" pos="{pos}"><joint name="j{k}" type="hinge" axis="0 1 0"/>'
            f'<inertial pos="0 0 -0.5" mass="1" diaginertia="{1 / 12} {1 / 12} 1e-6"/>'
            f"{body}</body>"
        )
    return (
        f'<mujoco><option timestep="{h}" integrator="RK4" gravity="0 0 {-G}">'
        '<flag contact="disable" energy="enable"/></option>'
        f"<worldbody>{body}</worldbody></mujoco>"
    )


def chain_mujoco(n: int, T: float, h: float) -> dict:
    import mujoco

    model = mujoco.MjModel.from_xml_string(mujoco_chain_xml(n, h))

    def start():
        data = mujoco.MjData(model)
        data.qpos[0] = -THETA0  # rotation about +y by -theta0 tilts the chain towards +x
        mujoco.mj_forward(model, data)
        return data

    def tip(data):
        R = data.xmat[n].reshape(3, 3)  # body 0 is the world
        p = data.xpos[n] + R @ np.array([0.0, 0.0, -1.0])
        return [float(p[0]), float(p[2])]

    data = start()
    E0 = float(np.sum(data.energy))
    steps = round(T / h)
    t0 = CLOCK()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    run = CLOCK() - t0
    mujoco.mj_forward(model, data)
    E1 = float(np.sum(data.energy))
    tip_T = tip(data)
    d2 = start()
    for _ in range(round(min(0.1, T) / h)):
        mujoco.mj_step(model, d2)
    mujoco.mj_forward(model, d2)
    return {
        "code": "mujoco",
        "method": "RK4",
        "n": n,
        "T": T,
        "compile_s": 0.0,
        "run_s": run,
        "s_per_sim_s": run / T,
        "E0": E0,
        "drift": abs(E1 - E0),
        "tip_0.1": tip(d2),
        "tip_T": tip_T,
    }


# ------------------------------------------------------------------ double four-bar
# The N-four-bar's exact solution and Exudyn model live in benchmarks/nfourbar.py (N = 2 here).


def fourbar_mixdyn(method: str, **opts) -> dict:
    r = nfourbar.run_mixdyn(2, 10.0, method, **opts)
    label = ", ".join(f"{k}={float(v):g}" for k, v in opts.items() if k != "solver")
    if "solver" in opts:
        label = f"{opts['solver']}, {label}"
    return dict(r, method=f"{method} ({label})")


def fourbar_exudyn(h: float = 1e-3) -> dict:
    return nfourbar.run_exudyn(2, h, 10.0, sparse=False)


# --------------------------------------------------------------------------- Andrews
ANDREWS_RUNS = [
    ("projection", {"solver": "tsit5"}, "rtol", (1e-6, 1e-8, 1e-10)),
    ("projection", {"solver": "dopri8"}, "rtol", (1e-8, 1e-10, 1e-12)),
    ("partitioning", {"solver": "tsit5"}, "rtol", (1e-6, 1e-8, 1e-10)),
    ("baumgarte", {}, "dt", (4e-6, 2e-6, 1e-6)),
    ("generalized-alpha", {"rho_inf": 0.9}, "dt", (1e-5, 2.5e-6, 1e-6)),
]


def andrews_work_precision(quick: bool) -> list[dict]:
    model = andrews_mechanism()
    idx = [model.coordinate_index(f"{b}.phi") for b in ANDREWS_BODIES]
    rows = []
    for method, extra, knob, values in ANDREWS_RUNS:
        compile_s = None
        for v in values[:2] if quick else values:
            opts = dict(extra)
            if knob == "rtol":
                opts["rtol"] = opts["atol"] = jnp.asarray(v)
            else:
                opts["dt"] = jnp.asarray(v)
            first, run, res = timed(
                lambda o=opts, m=method: md.forward(model, [0.0, 0.03], method=m, **o)
            )
            if compile_s is None:
                compile_s = first - run
            got = np.array(andrews_angles(res.q[-1, idx]))
            err = float(np.max(np.abs(got - ANDREWS_REF) / np.abs(ANDREWS_REF)))
            name = method + (f" {extra['solver']}" if "solver" in extra else "")
            rows.append(
                {
                    "method": name,
                    "setting": f"{knob}={v:g}",
                    "error": err,
                    "run_s": run,
                    "compile_s": compile_s,
                    "steps": res.stats["steps"],
                }
            )
            print(f"  andrews {name} {knob}={v:g}: error {err:.2e}, {run:.3f} s", flush=True)
    return rows


# ----------------------------------------------------------------------------- report
def fmt(x, spec=".3g"):
    return "-" if x is None else format(x, spec)


def chain_tables(rows: list[dict]) -> str:
    out = [
        "| links | code | method | linear solve | simulated [s] | first-call extra (compile) [s] "
        "| run [s] | CPU s per simulated s | E(0) [J] | drift abs(E(T)-E(0)) [J] | tip at 0.1 s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        tip = "-" if r["tip_0.1"] is None else f"({r['tip_0.1'][0]:.6f}, {r['tip_0.1'][1]:.6f})"
        out.append(
            f"| {r['n']} | {r['code']} | {r['method']} | {r.get('linear_solver', '-')} "
            f"| {r['T']:g} | {fmt(r['compile_s'], '.1f')} "
            f"| {fmt(r['run_s'], '.3g')} | {fmt(r['s_per_sim_s'], '.3g')} | {r['E0']:.6g} "
            f"| {r['drift']:.2e} | {tip} |"
        )
    out.append("")
    out.append("| links | mixdyn RK4 / MuJoCo RK4 | mixdyn gen-alpha / Exudyn gen-alpha |")
    out.append("|---|---|---|")
    by = {(r["n"], r["code"], r["method"]): r["s_per_sim_s"] for r in rows}
    ns = sorted({r["n"] for r in rows})
    for n in ns:
        a = by.get((n, "mixdyn", "baumgarte"))
        b = by.get((n, "mujoco", "RK4"))
        c = by.get((n, "mixdyn", "generalized-alpha"))
        d = by.get((n, "exudyn", "generalized-alpha"))
        r1 = fmt(a / b, ".2g") if a and b else "-"
        r2 = fmt(c / d, ".2g") if c and d else "-"
        out.append(f"| {n} | {r1} | {r2} |")
    out.append("")
    out.append("Log-log slope of CPU time per simulated second against the number of links:")
    out.append("")
    for key in sorted({(r["code"], r["method"]) for r in rows}):
        pts = [(r["n"], r["s_per_sim_s"]) for r in rows if (r["code"], r["method"]) == key]
        if len(pts) >= 2:
            x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
            slope = np.polyfit(x, y, 1)[0]
            last = np.diff(y[-2:])[0] / np.diff(x[-2:])[0]
            out.append(
                f"- {key[0]} {key[1]}: {slope:.2f} (fit over n = "
                f"{', '.join(str(p[0]) for p in pts)}; last pair {last:.2f})"
            )
    return "\n".join(out)


def simple_table(rows: list[dict], cols: list[tuple[str, str, str]]) -> str:
    out = ["| " + " | ".join(c[1] for c in cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        out.append(
            "| " + " | ".join(fmt(r[c[0]], c[2]) if c[2] else str(r[c[0]]) for c in cols) + " |"
        )
    return "\n".join(out)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes only (a smoke run)")
    ap.add_argument("--json", type=pathlib.Path, help="write the raw results here")
    ap.add_argument("--skip", nargs="*", default=(), choices=("chains", "fourbar", "andrews"))
    ap.add_argument("--cpu", action="store_true", help="CPU time of the process, not wall")
    args = ap.parse_args(argv)
    if args.cpu:
        global CLOCK
        CLOCK = time.process_time
    warnings.filterwarnings("ignore", category=DeprecationWarning)
    t_start = time.perf_counter()
    results = {"machine": machine()}
    print("machine:", json.dumps(results["machine"]), flush=True)
    peers = {p: have(p) for p in ("exudyn", "mujoco")}
    for p, ok in peers.items():
        if not ok:
            print(f"{p} not installed: skipped (pip install -e '.[bench]')", flush=True)

    h = 1e-3
    if "chains" not in args.skip:
        # (links, simulated time of mixdyn's RK4, of its generalized-alpha); peers run 1 s.
        plan = (
            [(4, 1.0, 1.0), (16, 1.0, 0.2)]
            if args.quick
            else [
                (4, 1.0, 1.0),
                (16, 1.0, 0.2),
                (64, 0.2, 0.2),
                (256, 0.2, 0.2),
            ]
        )
        rows = []
        for n, T_rk4, T_ga in plan:
            runs = [lambda n=n, T=T_rk4: chain_mixdyn(n, T, h, "baumgarte")]
            if T_ga:
                runs.append(lambda n=n, T=T_ga: chain_mixdyn(n, T, h, "generalized-alpha"))
            if peers["mujoco"]:
                runs.append(lambda n=n: chain_mujoco(n, 1.0, h))
            if peers["exudyn"]:
                runs.append(lambda n=n: chain_exudyn(n, 1.0, h))
            for run in runs:
                r = run()
                rows.append(r)
                print(
                    f"  chain {n:4d} {r['code']:7s} {r['method']:18s} "
                    f"{r['s_per_sim_s']:10.3g} s/s  (compile {r['compile_s']:.1f} s, "
                    f"drift {r['drift']:.1e} J, {time.perf_counter() - t_start:.0f} s so far)",
                    flush=True,
                )
        results["chains"] = rows
    if "fourbar" not in args.skip:
        rows = [
            fourbar_mixdyn("generalized-alpha", dt=jnp.asarray(1e-3), rho_inf=0.95),
            fourbar_mixdyn("baumgarte", dt=jnp.asarray(1e-3)),
            fourbar_mixdyn("projection", rtol=1e-9, atol=1e-9, solver="dopri8"),
        ]
        if peers["exudyn"]:
            rows.append(fourbar_exudyn(1e-3))
        for r in rows:
            print(f"  four-bar {r['code']} {r['method']}: {r['run_s']:.3f} s", flush=True)
        results["fourbar"] = rows
    if "andrews" not in args.skip:
        results["andrews"] = andrews_work_precision(args.quick)
    results["total_s"] = time.perf_counter() - t_start

    print("\n## Machine\n")
    print(json.dumps(results["machine"], indent=1))
    if "chains" in results:
        print(f"\n## Pendulum chains (h = {h:g} s)\n")
        print(chain_tables(results["chains"]))
    if "fourbar" in results:
        print("\n## IFToMM double four-bar, 0-10 s\n")
        print(
            simple_table(
                results["fourbar"],
                [
                    ("code", "code", ""),
                    ("method", "method", ""),
                    ("compile_s", "first-call extra [s]", ".1f"),
                    ("run_s", "run [s]", ".3g"),
                    ("tip_error", "crank-tip error at 10 s [m]", ".2e"),
                    ("energy_error", "max energy error [J]", ".2e"),
                ],
            )
        )
    if "andrews" in results:
        print("\n## Andrews' squeezer, work-precision at t = 0.03 s\n")
        print(
            simple_table(
                results["andrews"],
                [
                    ("method", "method", ""),
                    ("setting", "setting", ""),
                    ("steps", "steps", "d"),
                    ("error", "max rel. angle error", ".2e"),
                    ("run_s", "run [s]", ".3g"),
                    ("compile_s", "first-call extra [s]", ".1f"),
                ],
            )
        )
    print(f"\ntotal {results['total_s']:.0f} s")
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    return results


if __name__ == "__main__":
    main()

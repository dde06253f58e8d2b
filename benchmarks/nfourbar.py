"""The IFToMM N-four-bar (N parallelograms, 2N + 1 bars; N = 2 is the "double four-bar"):
mixdyn against Exudyn, crank-0 tip error at the end against the exact 1-DOF reduction.

Run: ``python benchmarks/nfourbar.py [N ...] [--t-end 10] [--exudyn-h 1e-3 5e-4]
[--rtol 1e-9] [--solver dopri8]``. Prints a Markdown table for ``benchmarks/RESULTS.md``.
Peers come from the ``bench`` extra; nothing is installed here. ``benchmarks/run.py`` reuses
the builders below for its N = 2 table.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

os.environ.setdefault("XLA_FLAGS", "--xla_cpu_enable_concurrency_optimized_scheduler=false")

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import mixdyn as md
from fixtures import double_four_bar

G = 9.81


def exact_tip(n: int, t_end: float = 10.0) -> np.ndarray:
    """Crank-0 tip (x, y) [m] at ``t_end`` from the exact reduction ``thetaddot = k sin(theta)``,
    ``k = g 3(3N+1) / (2(4N+1))`` (``theta`` from the upward vertical; derivation in
    ``tests/validation/test_validation.py``)."""
    k = G * 3 * (3 * n + 1) / (2 * (4 * n + 1))
    sol = solve_ivp(
        lambda t, y: [y[1], k * math.sin(y[0])],
        (0.0, t_end),
        [0.0, 1.0],
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
    )
    th = sol.y[0, -1]
    return np.array([math.sin(th), math.cos(th)])


def run_mixdyn(n: int, t_end: float = 10.0, method: str = "projection", **opts) -> dict:
    """mixdyn's run, called twice (the first call's extra time is the compilation)."""
    model, qd0 = double_four_bar(n)
    ts = np.linspace(0.0, t_end, round(10 * t_end) + 1)
    t0 = time.perf_counter()
    md.forward(model, ts, method=method, qd0=qd0, **opts)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = md.forward(model, ts, method=method, qd0=qd0, **opts)
    run = time.perf_counter() - t0
    E = np.asarray(res["energy.total"])
    return {
        "code": "mixdyn",
        "run_s": run,
        "compile_s": first - run,
        "tip_error": float(np.max(np.abs(res.point("crank0.B")[0][-1] - exact_tip(n, t_end)))),
        "energy_error": float(np.max(np.abs(E - E[0]))),
        "steps": int(res.stats["steps"]),
        "linear_solver": res.stats.get("linear_solver", "?"),
    }


def run_exudyn(
    n: int, h: float = 1e-3, t_end: float = 10.0, sparse: bool | None = None, rho_inf=0.95
) -> dict:
    """Exudyn's N-four-bar (its ``TestModels/fourBarMechanismIftomm.py`` generalised to N):
    ``ObjectRigidBody2D`` + ``ObjectJointRevolute2D``, generalized-alpha with modified Newton;
    ``sparse`` picks its ``EigenSparse`` linear solver (default: from N = 8 on)."""
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
        SensorBody,
    )

    sparse = n >= 8 if sparse is None else sparse
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    m0, m1, bodies = [], [], []
    for i in range(2 * n + 1):  # even: crank i/2 at x = i/2; odd: coupler between cranks
        crank = i % 2 == 0
        ref = [i / 2, 0.5, 0.5 * math.pi] if crank else [i / 2, 1.0, 0.0]
        vel = [0.5, 0, -1] if crank else [1, 0, 0]
        nd = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=ref, initialVelocities=vel))
        b = mbs.AddObject(ObjectRigidBody2D(nodeNumber=nd, mass=1.0, inertia=1 / 12))
        mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=b))
        mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0, -G, 0]))
        m0.append(mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[-0.5, 0, 0])))
        m1.append(mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[0.5, 0, 0])))
        bodies.append(b)
    gnd = mbs.AddObject(ObjectGround())
    for k in range(n + 1):
        mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=gnd, localPosition=[k, 0, 0]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mg, m0[2 * k]]))
    for k in range(n):
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m1[2 * k], m0[2 * k + 1]]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m1[2 * k + 2], m1[2 * k + 1]]))
    ov = exu.OutputVariableType

    def sensor(b, kind, local=None):
        extra = {} if local is None else {"localPosition": local}
        return mbs.AddSensor(
            SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=kind, **extra)
        )

    states = [(sensor(b, ov.Position), sensor(b, ov.Velocity)) for b in bodies]
    omegas = [sensor(b, ov.AngularVelocity) for b in bodies]
    tip = sensor(bodies[0], ov.Position, [0.5, 0, 0])
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = round(t_end / h)
    ss.timeIntegration.endTime = t_end
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 0.1
    ss.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.newton.useModifiedNewton = True
    if sparse:
        ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    t0 = time.perf_counter()
    try:
        mbs.SolveDynamic(ss)
    except Exception as exc:
        return {
            "code": "exudyn",
            "run_s": float("nan"),
            "tip_error": float("nan"),
            "energy_error": float("nan"),
            "failed": f"{type(exc).__name__}: {exc}",
        }
    run = time.perf_counter() - t0
    E = 0.0
    for (sp, sv), sw in zip(states, omegas, strict=True):
        p = mbs.GetSensorStoredData(sp)[:, 1:3]
        v = mbs.GetSensorStoredData(sv)[:, 1:3]
        w = mbs.GetSensorStoredData(sw)[:, 3]
        E = E + 0.5 * np.sum(v**2, axis=1) + 0.5 / 12 * w**2 + G * p[:, 1]
    pos = mbs.GetSensorStoredData(tip)[-1, 1:3]
    return {
        "code": "exudyn",
        "method": f"generalized-alpha (h={h:g}, rho_inf={rho_inf:g})",
        "linear_solver": "EigenSparse" if sparse else "dense",
        "compile_s": 0.0,
        "run_s": run,
        "tip_error": float(np.max(np.abs(pos - exact_tip(n, t_end)))),
        "energy_error": float(np.max(np.abs(E - E[0]))),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="*", type=int, default=[2, 4, 8, 16])
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--rtol", type=float, nargs="*", default=[1e-9])
    ap.add_argument("--solver", default="dopri8", help="RK method of the adaptive runs")
    ap.add_argument("--exudyn-h", type=float, nargs="*", default=[1e-3])
    ap.add_argument("--linear-solver", default="auto")
    ap.add_argument(
        "--fixed",
        nargs="*",
        default=[],
        help="fixed-step mixdyn runs as method:dt[:option=value...], e.g. "
        "generalized-alpha:1e-3 generalized-alpha:6e-4:project_velocities=0 baumgarte:1e-3",
    )
    ap.add_argument("--max-steps", type=int, default=20_000)
    args = ap.parse_args(argv)
    rows = []
    for n in args.n:
        for spec in args.fixed:
            method, dt, *extra = spec.split(":")
            opts = {"rho_inf": 0.95} if method == "generalized-alpha" else {}
            for kv in extra:  # numbers; 0/1 for flags
                key, value = kv.split("=")
                opts[key] = bool(int(value)) if key == "project_velocities" else float(value)
            r = run_mixdyn(
                n, args.t_end, method, dt=float(dt), linear_solver=args.linear_solver, **opts
            )
            r["method"] = f"{method} dt={float(dt):g}" + "".join(
                f" {k}={v:g}" if isinstance(v, float) else f" {k}={v}" for k, v in opts.items()
            )
            rows.append((n, r))
            print(f"N={n}: {r}", flush=True)
        for rtol in args.rtol:
            try:
                r = run_mixdyn(
                    n,
                    args.t_end,
                    rtol=rtol,
                    atol=rtol,
                    solver=args.solver,
                    linear_solver=args.linear_solver,
                    max_steps=args.max_steps,
                )
            except md.NumericalError as exc:  # a failure is a result to report
                nan = float("nan")
                r = {"code": "mixdyn", "run_s": nan, "tip_error": nan, "energy_error": nan}
                r["failed"] = f"{type(exc).__name__}: {exc}"
            r["method"] = f"projection {args.solver} rtol={rtol:g}"
            rows.append((n, r))
            print(f"N={n}: {r}", flush=True)
        for h in args.exudyn_h:
            try:
                r = run_exudyn(n, h, args.t_end)
            except ImportError:
                break
            rows.append((n, r))
            print(f"N={n}: {r}", flush=True)
    print(f"\n0-{args.t_end:g} s\n")
    print(
        "| N | bars | code | method | linear solve | run [s] | compile [s] | tip error [m] "
        "| max energy error [J] |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for n, r in rows:
        print(
            f"| {n} | {2 * n + 1} | {r['code']} | {r.get('method', '')} "
            f"| {r.get('linear_solver', '')} | {r['run_s']:.3g} | {r.get('compile_s', 0):.3g} "
            f"| {r['tip_error']:.2e} | {r['energy_error']:.2e} |"
            + (f" failed: {r['failed']}" if "failed" in r else "")
        )


if __name__ == "__main__":
    main()

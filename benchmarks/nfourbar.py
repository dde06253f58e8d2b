"""The IFToMM N-four-bar of growing N (N parallelograms, 2N + 1 bars): mixdyn against Exudyn,
0-10 s, crank-0 tip error at 10 s against the exact 1-DOF reduction.

Run: ``python benchmarks/nfourbar.py [N ...]`` (default 2 4 8 16). Prints a markdown table
for ``benchmarks/RESULTS.md``. Peers come from the ``bench`` extra; nothing is installed here.
"""

from __future__ import annotations

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
T_END = 10.0


def exact_tip(n: int) -> np.ndarray:
    """Crank-0 tip at 10 s from ``thetaddot = k sin(theta)``, ``k = g 3(3N+1) / (2(4N+1))``."""
    k = G * 3 * (3 * n + 1) / (2 * (4 * n + 1))
    sol = solve_ivp(
        lambda t, y: [y[1], k * math.sin(y[0])],
        (0.0, T_END),
        [0.0, 1.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
    )
    th = sol.y[0, -1]
    return np.array([math.sin(th), math.cos(th)])


def run_mixdyn(n: int, **opts) -> dict:
    model, qd0 = double_four_bar(n)
    ts = np.linspace(0.0, T_END, 101)
    t0 = time.perf_counter()
    md.forward(model, ts, qd0=qd0, **opts)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = md.forward(model, ts, qd0=qd0, **opts)
    run = time.perf_counter() - t0
    err = float(np.max(np.abs(res.point("crank0.B")[0][-1] - exact_tip(n))))
    return {"run_s": run, "compile_s": first - run, "err": err, "steps": res.stats["steps"]}


def run_exudyn(n: int, h: float = 1e-3) -> dict:
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
    tip = mbs.AddSensor(
        SensorBody(
            bodyNumber=bodies[0],
            localPosition=[0.5, 0, 0],
            storeInternal=True,
            outputVariableType=exu.OutputVariableType.Position,
        )
    )
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = round(T_END / h)
    ss.timeIntegration.endTime = T_END
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 0.1
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.95
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.newton.useModifiedNewton = True
    t0 = time.perf_counter()
    mbs.SolveDynamic(ss)
    run = time.perf_counter() - t0
    pos = mbs.GetSensorStoredData(tip)[-1, 1:3]
    return {"run_s": run, "err": float(np.max(np.abs(pos - exact_tip(n))))}


def main(argv=None):
    ns = [int(a) for a in (argv or sys.argv[1:])] or [2, 4, 8, 16]
    rows = []
    for n in ns:
        mx = run_mixdyn(n, rtol=1e-9, atol=1e-9, solver="dopri8")
        try:
            ex = run_exudyn(n)
        except ImportError:
            ex = {"run_s": float("nan"), "err": float("nan")}
        rows.append((n, mx, ex))
        print(f"N={n}: mixdyn {mx} exudyn {ex}", flush=True)
    print(
        "\n| N | bars | mixdyn projection dopri8 rtol 1e-9: run [s] | compile [s] | tip error [m] "
        "| Exudyn gen-alpha h=1e-3: run [s] | tip error [m] | run ratio mixdyn/Exudyn |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for n, mx, ex in rows:
        print(
            f"| {n} | {2 * n + 1} | {mx['run_s']:.3g} | {mx['compile_s']:.3g} | {mx['err']:.2e} "
            f"| {ex['run_s']:.3g} | {ex['err']:.2e} | {mx['run_s'] / ex['run_s']:.2g} |"
        )
    if len(rows) > 1:
        x = np.log([2 * n + 1 for n, _, _ in rows])
        for label, key in (("mixdyn", 1), ("Exudyn", 2)):
            y = np.log([r[key]["run_s"] for r in rows])
            print(f"\n{label}: log-log slope of run time against bars {np.polyfit(x, y, 1)[0]:.2f}")


if __name__ == "__main__":
    main()

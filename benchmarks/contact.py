"""Contact against peers, in one run: a ball dropped on the ground, and Flores' slider-crank
with a revolute clearance joint.

Peers (the ``bench`` extra of ``pyproject.toml``; this script installs nothing and skips a peer
that is missing): Exudyn and MuJoCo.

1. **A ball dropped on the ground** (radius 10 mm, 0.1 kg, steel on steel: E = 200 GPa,
   nu = 0.3; its bottom released 50 mm above the ground; restitution 0.9), 1 s simulated
   (five bounces), the state sampled every 1 ms.

   - mixdyn: ``md.CircleLineContact`` (Hertz's stiffness, Hunt-Crossley damping with
     ``impact_speed`` the first impact's speed), adaptive ``projection`` (Tsit5) at a few
     tolerances, with ``energy_tol=None``: through five stiff impacts the energy balance
     holds to 2.3e-5 of the energy at rtol 1e-8, beyond the default check's 1000 rtol.
   - Exudyn: ``ObjectContactCoordinate`` on the ball's vertical coordinate with the same
     Hertz stiffness and exponent 1.5 and its ``impactModel`` 1 (Hunt-Crossley, the
     impact's own speed stored at contact) or 2 (Gonthier et al. / Carvalho-Martins); its
     adaptive DOPRI5 (the contact's default settings: the step shortened at the contact's
     onset) and its RK4 at ``t_c / 20`` and ``t_c / 100`` (``t_c`` the Hertz contact's
     duration).
   - MuJoCo: a sphere on a plane (slide x, slide z, hinge y: a planar body), its soft contact
     a linear spring-damper of the Hertz contact's duration and the damping ratio of a linear
     oscillator that rebounds with e = 0.9 (``solref`` in its direct form, ``-stiffness
     -damping``; default ``solimp``), step ``t_c / 20``; and MuJoCo with its default contact
     and step (2 ms).

   For each: the first rebound's apex ``h1`` (from the first sample in free flight after the
   impact, ``y + vy**2 / (2 g)``, exact in free flight) and the restitution it achieves
   ``sqrt(h1 / h0)``; the first impact's time (from the last sample in free flight before
   it, the root of the free-flight parabola) against the closed form ``sqrt(2 h0 / g)``; and
   CPU time per simulated second.
2. **Flores' slider-crank with a revolute clearance** (``examples/clearance_slider_crank.yaml``,
   the parameters in ``tests/data/flores_clearance_slider_crank.txt``): one turn at 5000 rpm
   (12 ms), the crank's motion prescribed and its torque sought (``md.mixed``), CPU time per
   simulated second with the clearance and with the ideal joint. Exudyn: planar rigid bodies,
   the crank's speed a velocity-level ``CoordinateConstraint``, the clearance an
   ``ObjectContactSphereSphere`` between the journal and a hollow sphere (the bearing) with
   the same Hertz stiffness, Hunt-Crossley damping (it has no Lankarani-Nikravesh law),
   generalized-alpha at the paper's step 1e-5 s and at 2e-6 and 5e-7 s; the slider's position
   against mixdyn's (the ideal joints agree to round-off; with the clearance the two
   contact laws' paths part within the clearance).

Timing: ``time.process_time`` (the process's CPU time: the machine may be loaded by other
work), the median of ``--repeat`` calls after a first call; mixdyn's first call's extra time
is its compilation, reported apart. The load average is printed with the tables.

Run: ``python benchmarks/contact.py [--quick] [--repeat 3]``; the tables are printed as
Markdown. Results: ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import os

# Known deadlock of XLA's concurrency-optimized scheduler on this machine (vmapped scans).
os.environ.setdefault("XLA_FLAGS", "--xla_cpu_enable_concurrency_optimized_scheduler=false")

import argparse
import importlib.util
import math
import pathlib
import platform
import statistics
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
CLOCK = time.process_time

G = 9.81  # [m/s^2]
R = 0.01  # ball radius [m]
M = 0.1  # ball mass [kg]
H0 = 0.05  # drop height of the ball's bottom [m]
E_STEEL = 2.0e11  # [Pa]
NU = 0.3
RESTITUTION = 0.9
T_BALL = 1.0  # simulated time of the dropped ball [s]
DT_OUT = 1e-3  # output interval [s]
V0 = math.sqrt(2 * G * H0)  # the first impact's speed [m/s]
#: Hertz's stiffness of a sphere of radius R on a plane, both of steel [N/m^1.5].
K_HERTZ = 4.0 / 3.0 * E_STEEL / (2 * (1 - NU**2)) * math.sqrt(R)


# ------------------------------------------------------------------------------ closed forms
def impact_time(h0: float, g: float = G) -> float:
    """The time [s] a body released at rest ``h0`` [m] above the ground takes to reach it."""
    return math.sqrt(2 * h0 / g)


def hertz_duration(m: float, k: float, v: float) -> float:
    """The duration [s] of an elastic Hertz impact ``F = k delta**1.5`` of a mass ``m`` [kg]
    at the speed ``v`` [m/s]: ``2.94 delta_max / v``, ``delta_max = (5 m v**2 / (4 k))**0.4``
    (Johnson, Contact Mechanics, 1985, sec. 11.4)."""
    return 2.94 * (5 * m * v**2 / (4 * k)) ** 0.4 / v


def linear_damping_ratio(e: float) -> float:
    """The damping ratio of a linear spring-damper whose half-period rebound has the
    restitution ``e``: ``e = exp(-zeta pi / sqrt(1 - zeta**2))``."""
    log = math.log(e)
    return -log / math.sqrt(math.pi**2 + log**2)


def law_restitution(damping_factor: float) -> float:
    """The restitution of the first impact under the Hertz law with hysteresis damping
    ``F = K delta**1.5 (1 + c delta_dot / V0)`` (``c`` the model's ``damping_factor``,
    gravity acting through the contact), from SciPy's integration of the one coordinate
    ``delta``: the law's own rebound, apart from any integrator's error."""
    from scipy.integrate import solve_ivp

    def rhs(_, y):
        d, v = y
        F = max(K_HERTZ * max(d, 0.0) ** 1.5 * (1 + damping_factor * v / V0), 0.0)
        return [v, G - F / M]

    def separation(_, y):
        return y[0]

    separation.terminal, separation.direction = True, -1
    sol = solve_ivp(
        rhs, (0.0, 1e-2), [0.0, V0], method="DOP853", rtol=1e-12, atol=1e-15, events=separation
    )
    return -float(sol.y_events[0][0][1]) / V0


def first_bounce(t, gap, vy, g: float = G) -> tuple[float, float]:
    """``(t_impact, h1)`` of a ball sampled at the times ``t`` (n,) [s]: the height ``gap``
    (n,) [m] of its bottom above the ground (negative: penetration) and its upward velocity
    ``vy`` (n,) [m/s].

    ``t_impact``: the first contact, the root of the free-flight parabola through the last
    sample in free flight before the first rebound. ``h1``: the apex after it,
    ``gap + vy**2 / (2 g)`` at the first sample in free flight and rising after the impact
    (exact in free flight); 0 where the ball does not leave the ground again.
    """
    t, gap, vy = (np.asarray(a, dtype=float) for a in (t, gap, vy))
    rising = np.flatnonzero((vy > 0) & (np.arange(len(t)) > 0))
    falling = np.flatnonzero((vy < 0) & (gap > 0))
    if len(falling) == 0:
        raise ValueError("the ball never falls freely")
    # the impact: between the last free-fall sample and the first sample after it not in
    # free fall (in contact, or already rising)
    after = np.flatnonzero((np.arange(len(t)) > falling[0]) & ((gap <= 0) | (vy >= 0)))
    if len(after) == 0:
        raise ValueError("the ball never reaches the ground")
    k = falling[falling < after[0]][-1]
    t_impact = t[k] + (vy[k] + math.sqrt(vy[k] ** 2 + 2 * g * gap[k])) / g
    up = rising[(rising > k) & (gap[rising] > 0)]
    h1 = float(gap[up[0]] + vy[up[0]] ** 2 / (2 * g)) if len(up) else 0.0
    return float(t_impact), h1


def _row(code, method, t, gap, vy, run_s, compile_s=None, steps=None) -> dict:
    t_impact, h1 = first_bounce(t, gap, vy)
    return {
        "code": code,
        "method": method,
        "h1/h0": h1 / H0,
        "e": math.sqrt(h1 / H0),
        "t_error": abs(t_impact - impact_time(H0)),
        "compile_s": compile_s,
        "s_per_sim_s": run_s / T_BALL,
        "steps": steps,
    }


def timed(fn, repeat: int) -> tuple[float, float, object]:
    """``(first, median of the next repeat calls, result)``: CPU times of ``fn()`` [s]."""
    t0 = CLOCK()
    out = fn()
    first = CLOCK() - t0
    times = []
    for _ in range(repeat):
        t0 = CLOCK()
        out = fn()
        times.append(CLOCK() - t0)
    return first, statistics.median(times), out


def have(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


# ------------------------------------------------------------------------------ the ball
def ball_mixdyn(rtols, repeat: int) -> list[dict]:
    import mixdyn as md

    md.set_cache(False)  # the first call's extra time: the compilation
    ball = md.Body("ball", M, 0.4 * M * R**2, q0=(0.0, R + H0, 0.0))
    floor = md.CircleLineContact(
        "floor", "ball", R, "ground", young_modulus=E_STEEL, poisson=NU,
        restitution=RESTITUTION, impact_speed=V0, contact_model="hunt_crossley",
    )  # fmt: skip
    model = md.Model([ball], forces=[floor], gravity=(0.0, -G))
    ts = np.linspace(0.0, T_BALL, round(T_BALL / DT_OUT) + 1)
    rows = []
    for rtol in rtols:
        first, run, r = timed(
            lambda rtol=rtol: md.forward(model, ts, rtol=rtol, atol=rtol * 1e-2, energy_tol=None),
            repeat,
        )
        rows.append(
            _row(
                "mixdyn",
                f"Hunt-Crossley, projection tsit5, rtol {rtol:g}",
                ts,
                r["ball.y"] - R,
                r["ball.vy"],
                run,
                None if rows else first - run,
                int(r.stats["steps"]),
            )
        )  # one compilation: the tolerances are traced
    return rows


def ball_exudyn(repeat: int, quick: bool) -> list[dict]:
    import exudyn as exu
    from exudyn.itemInterface import (
        LoadMassProportional,
        MarkerBodyMass,
        MarkerNodeCoordinate,
        NodeGenericData,
        NodePointGround,
        NodeRigidBody2D,
        ObjectContactCoordinate,
        ObjectRigidBody2D,
        SensorNode,
    )

    def build(impact_model):
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
        m_ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
        node = mbs.AddNode(
            NodeRigidBody2D(referenceCoordinates=[0, 0, 0], initialCoordinates=[0, R + H0, 0])
        )
        body = mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=M, inertia=0.4 * M * R**2))
        m_y = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=1))
        m_mass = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
        mbs.AddLoad(LoadMassProportional(markerNumber=m_mass, loadVector=[0, -G, 0]))
        # the contact state (the gap, > 0 at the start: free) and the last impact's speed
        data = mbs.AddNode(NodeGenericData(initialCoordinates=[H0, 0], numberOfDataCoordinates=2))
        mbs.AddObject(
            ObjectContactCoordinate(
                markerNumbers=[m_ground, m_y], nodeNumber=data, contactStiffness=K_HERTZ,
                contactStiffnessExponent=1.5, restitutionCoefficient=RESTITUTION,
                impactModel=impact_model, offset=R,
            )
        )  # fmt: skip
        ov = exu.OutputVariableType
        sensors = [
            mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=v, storeInternal=True))
            for v in (ov.Coordinates, ov.Coordinates_t)
        ]
        mbs.Assemble()
        return SC, mbs, sensors

    def settings(h=None, rtol=None):
        ss = exu.SimulationSettings()
        ss.timeIntegration.endTime = T_BALL
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        ss.solution.sensors.writePeriod = DT_OUT
        if h is not None:
            # RK4 at a fixed step: the contact state follows the gap after each step (the
            # default's step reduction at the contact's onset stops at its minimum step)
            ss.timeIntegration.numberOfSteps = round(T_BALL / h)
            ss.timeIntegration.discontinuous.useRecommendedStepSize = False
            ss.timeIntegration.discontinuous.iterationTolerance = 1e100
        else:
            ss.timeIntegration.numberOfSteps = round(T_BALL / 1e-4)  # the first step
            ss.timeIntegration.automaticStepSize = True
            ss.timeIntegration.relativeTolerance = rtol
            ss.timeIntegration.absoluteTolerance = rtol * 1e-2
            ss.timeIntegration.minimumStepSize = 1e-12
        return ss

    t_c = hertz_duration(M, K_HERTZ, V0)
    st = exu.DynamicSolverType
    runs = [
        (1, "Hunt-Crossley, DOPRI5, rtol 1e-8", st.DOPRI5, dict(rtol=1e-8)),
        (1, "Hunt-Crossley, RK4", st.RK44, dict(h=t_c / 20)),
        (1, "Hunt-Crossley, RK4", st.RK44, dict(h=t_c / 100)),
        (2, "Gonthier / Carvalho-Martins, RK4", st.RK44, dict(h=t_c / 100)),
    ]
    rows = []
    for impact_model, label, solver, opts in runs[:2] if quick else runs:
        h_label = f" h {opts['h']:.2g}" if "h" in opts else ""

        def solve(impact_model=impact_model, solver=solver, opts=opts):
            sc, mbs, sensors = build(impact_model)
            mbs.SolveDynamic(settings(**opts), solverType=solver)
            return sc, mbs, sensors

        _, run, (_sc, mbs, sensors) = timed(solve, repeat)
        q, qd = (mbs.GetSensorStoredData(s) for s in sensors)
        steps = round(T_BALL / opts["h"]) if "h" in opts else None
        rows.append(
            _row("Exudyn", label + h_label, q[:, 0], q[:, 2] - R, qd[:, 2], run, None, steps)
        )
    return rows


def mujoco_ball_xml(h: float, solref: str | None) -> str:
    contact = f' solref="{solref}"' if solref else ""
    return (
        f'<mujoco><option timestep="{h}" gravity="0 0 {-G}"/><worldbody>'
        '<geom type="plane" size="1 1 0.1"/>'
        f'<body name="ball" pos="0 0 {R + H0}">'
        '<joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>'
        '<joint type="hinge" axis="0 1 0"/>'
        f'<geom type="sphere" size="{R}" mass="{M}"{contact}/></body></worldbody></mujoco>'
    )


def ball_mujoco(repeat: int) -> list[dict]:
    import mujoco

    t_c = hertz_duration(M, K_HERTZ, V0)
    omega = math.pi / t_c  # the linear contact's half period is the Hertz contact's duration
    zeta = linear_damping_ratio(RESTITUTION)
    matched = (t_c / 20, f"{-(omega**2)} {-2 * zeta * omega}")
    rows = []
    for (h, solref), label in (
        (matched, "linear spring-damper, t_c and zeta(e) matched"),
        ((2e-3, None), "default contact"),
    ):
        model = mujoco.MjModel.from_xml_string(mujoco_ball_xml(h, solref))
        steps = round(T_BALL / h)
        every = max(1, round(DT_OUT / h))

        def run(model=model, steps=steps, every=every):
            data = mujoco.MjData(model)
            out = []
            for i in range(steps):
                mujoco.mj_step(model, data)
                if (i + 1) % every == 0:
                    out.append((data.time, data.qpos[1], data.qvel[1]))
            return np.array(out)

        _, run_s, out = timed(run, repeat)
        # qpos[1]: the slide's displacement from the body's position R + H0
        rows.append(
            _row("MuJoCo", f"{label}, Euler h {h:.2g}", out[:, 0], out[:, 1] + H0, out[:, 2],
                 run_s, steps=steps)
        )  # fmt: skip
    return rows


# ------------------------------------------------------------------------------ slider-crank
def slider_crank_mixdyn(repeat: int) -> list[dict]:
    """mixdyn on the example's slider-crank, with its clearance (the example's tolerance and
    a finer one) and with the ideal joint; each row with the slider's x (241,) [m]."""
    import mixdyn as md
    import mixdyn.io as mio

    md.set_cache(False)  # the first call's extra time: the compilation
    model = mio.load(ROOT / "examples" / "clearance_slider_crank.yaml")
    ts = np.linspace(0.0, T_TURN, 241)
    drive = md.CoordinateDriver("drive", "crank", "phi", law=md.Polynomial([0.0, OMEGA]))
    # the clearance joint is a journal-bearing contact (a force) in place of the revolute
    ideal = model.replace(
        joints=(*model.joints, md.Revolute("B", "rod.B", "slider")),
        forces=tuple(f for f in model.forces if f.name != "B"),
    )
    rows = []
    compiled = set()
    for label, m, clearance, rtol in (
        ("clearance 0.5 mm (Lankarani-Nikravesh)", model, True, 1e-7),
        ("clearance 0.5 mm (Lankarani-Nikravesh)", model, True, 1e-9),
        ("ideal joint", ideal, False, 1e-7),
    ):
        first, run, r = timed(
            lambda m=m, rtol=rtol: md.mixed(
                m, ts, prescribed=[drive], unknown=["motor"], rtol=rtol, atol=rtol * 1e-2
            ),
            repeat,
        )
        rows.append(
            {
                "code": "mixdyn",
                "case": f"{label}, projection tsit5, rtol {rtol:g}",
                "clearance": clearance,
                "compile_s": None if clearance in compiled else first - run,
                "s_per_sim_s": run / T_TURN,
                "steps": int(r.stats["steps"]),
                "x": np.asarray(r["slider.x"]),
            }
        )
        compiled.add(clearance)
        print(f"  slider-crank mixdyn {label} rtol {rtol:g}: {run / T_TURN:.3g} CPU s / sim. s")
    return rows


def compare_paths(rows: list[dict]) -> None:
    """Add to each row of the slider-crank ``self``, the largest difference [m] of its
    slider's x from the same code's last (finest) row of the same joint, and ``mixdyn``,
    from mixdyn's last row of the same joint."""

    def diff(a, b):
        n = min(len(a), len(b))  # the same output times (a peer may add the end's sample)
        return float(np.max(np.abs(a[:n] - b[:n])))

    for r in rows:
        same = [o for o in rows if o["code"] == r["code"] and o["clearance"] == r["clearance"]]
        ref = [o for o in rows if o["code"] == "mixdyn" and o["clearance"] == r["clearance"]]
        r["self"] = diff(r["x"], same[-1]["x"]) if r is not same[-1] else None
        r["mixdyn"] = (
            float(np.max(np.abs(r["x"] - ref[-1]["x"]))) if r["code"] != "mixdyn" else None
        )


#: Flores' slider-crank (tests/data/flores_clearance_slider_crank.txt): lengths [m], masses
#: [kg], inertias [kg m^2] of crank, rod and slider; the clearance and journal radius [m].
L1, L2 = 0.05, 0.12
MASSES, INERTIAS = (0.30, 0.21, 0.14), (1e-4, 2.5e-4, 1e-4)
CLEARANCE, JOURNAL_RADIUS, E_FLORES = 0.5e-3, 9.5e-3, 207e9
OMEGA = 5000 * 2 * math.pi / 60  # [rad/s]
T_TURN = 2 * math.pi / OMEGA  # one turn [s]


def slider_crank_exudyn(repeat: int) -> list[dict]:
    """Exudyn's slider-crank: planar rigid bodies, revolute and prismatic joints, the crank's
    speed a velocity-level ``CoordinateConstraint``; the clearance an
    ``ObjectContactSphereSphere`` between the slider's journal and the rod's hollow sphere
    (the bearing) with the same Hertz stiffness and exponent 1.5, its ``impactModel`` 1
    (Hunt-Crossley with the stored impact speed; Exudyn has no Lankarani-Nikravesh law);
    generalized-alpha (spectral radius 0.9), the paper's step 1e-5 s and finer ones."""
    import exudyn as exu
    from exudyn.itemInterface import (
        CoordinateConstraint,
        LoadMassProportional,
        MarkerBodyMass,
        MarkerBodyPosition,
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        NodeGenericData,
        NodePointGround,
        NodeRigidBody2D,
        ObjectContactSphereSphere,
        ObjectGround,
        ObjectJointPrismatic2D,
        ObjectJointRevolute2D,
        ObjectRigidBody2D,
        SensorNode,
    )

    bearing = JOURNAL_RADIUS + CLEARANCE
    k = 4.0 / 3.0 * E_FLORES / (2 * (1 - NU**2)) * math.sqrt(JOURNAL_RADIUS * bearing / CLEARANCE)

    def build(clearance: bool):
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.AddObject(ObjectGround())
        # the ideal mechanism's start: crank along the guide, turning at OMEGA
        start = [(L1 / 2, 0.0), (L1 + L2 / 2, 0.0), (L1 + L2, 0.0)]
        speed = [(0, OMEGA * L1 / 2, OMEGA), (0, OMEGA * L1 / 2, -OMEGA * L1 / L2), (0, 0, 0)]
        nodes, bodies = [], []
        for p, v, m, J in zip(start, speed, MASSES, INERTIAS, strict=True):
            node = mbs.AddNode(
                NodeRigidBody2D(referenceCoordinates=[*p, 0.0], initialVelocities=list(v))
            )
            body = mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=m, inertia=J))
            mass = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
            mbs.AddLoad(LoadMassProportional(markerNumber=mass, loadVector=[0, -9.81, 0]))
            nodes.append(node)
            bodies.append(body)
        crank, rod, slider = bodies

        def at(body, x):
            return mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[x, 0, 0]))

        def frame(body, x):
            return mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[x, 0, 0]))

        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[at(ground, 0), at(crank, -L1 / 2)]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[at(crank, L1 / 2), at(rod, -L2 / 2)]))
        if clearance:
            data = mbs.AddNode(
                NodeGenericData(initialCoordinates=[CLEARANCE, 0, 0, 0], numberOfDataCoordinates=4)
            )
            mbs.AddObject(
                ObjectContactSphereSphere(
                    markerNumbers=[frame(slider, 0), frame(rod, L2 / 2)], nodeNumber=data,
                    spheresRadii=[JOURNAL_RADIUS, bearing], isHollowSphere1=True,
                    contactStiffness=k, contactStiffnessExponent=1.5,
                    restitutionCoefficient=0.9, impactModel=1,
                )
            )  # fmt: skip
        else:
            mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[at(rod, L2 / 2), at(slider, 0)]))
        mbs.AddObject(
            ObjectJointPrismatic2D(
                markerNumbers=[frame(ground, L1 + L2), frame(slider, 0)], axisMarker0=[1, 0, 0],
                normalMarker1=[0, 1, 0], constrainRotation=True,
            )
        )  # fmt: skip
        origin = mbs.AddNode(NodePointGround())
        mbs.AddObject(
            CoordinateConstraint(
                markerNumbers=[
                    mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=origin, coordinate=0)),
                    mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=2)),
                ],
                velocityLevel=True,
                offset=OMEGA,
            )
        )
        sensor = mbs.AddSensor(
            SensorNode(
                nodeNumber=nodes[2], outputVariableType=exu.OutputVariableType.Position,
                storeInternal=True,
            )
        )  # fmt: skip
        mbs.Assemble()
        return SC, mbs, sensor

    def settings(h):
        ss = exu.SimulationSettings()
        ss.timeIntegration.endTime = T_TURN
        ss.timeIntegration.numberOfSteps = round(T_TURN / h)
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        ss.solution.sensors.writePeriod = T_TURN / 240
        ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
        ss.timeIntegration.newton.useModifiedNewton = True
        # the contact state follows the gap after each step (no step-size control on it)
        ss.timeIntegration.discontinuous.useRecommendedStepSize = False
        ss.timeIntegration.discontinuous.iterationTolerance = 1e100
        return ss

    rows = []
    for label, clearance, h in (
        ("clearance 0.5 mm (Hunt-Crossley)", True, 1e-5),
        ("clearance 0.5 mm (Hunt-Crossley)", True, 2e-6),
        ("clearance 0.5 mm (Hunt-Crossley)", True, 5e-7),
        ("ideal joint", False, 1e-5),
    ):

        def solve(clearance=clearance, h=h):
            sc, mbs, sensor = build(clearance)
            mbs.SolveDynamic(settings(h))
            return sc, mbs, sensor

        _, run, (_sc, mbs, sensor) = timed(solve, repeat)
        rows.append(
            {
                "code": "Exudyn",
                "case": f"{label}, generalized-alpha h {h:g}",
                "clearance": clearance,
                "compile_s": None,
                "s_per_sim_s": run / T_TURN,
                "steps": round(T_TURN / h),
                "x": mbs.GetSensorStoredData(sensor)[:, 1],
            }
        )
        print(f"  slider-crank Exudyn {label} h {h:g}: {run / T_TURN:.3g} CPU s / sim. s")
    return rows


# ------------------------------------------------------------------------------ report
def versions() -> dict:
    import jax

    import mixdyn as md

    out = {"python": platform.python_version(), "jax": jax.__version__, "mixdyn": md.__version__}
    if have("exudyn"):
        import exudyn

        out["exudyn"] = exudyn.config.Version()
    if have("mujoco"):
        import mujoco

        out["mujoco"] = mujoco.__version__
    return out


def fmt(x, spec=".3g") -> str:
    return "-" if x is None else format(x, spec)


def ball_table(rows: list[dict]) -> str:
    out = [
        f"| code | contact, integrator | h1/h0 | e achieved (asked {RESTITUTION}) "
        "| impact time error [s] | compile [s] | CPU s per simulated s | steps |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        out.append(
            f"| {r['code']} | {r['method']} | {r['h1/h0']:.4f} | {r['e']:.4f} "
            f"| {r['t_error']:.1e} | {fmt(r['compile_s'], '.1f')} "
            f"| {r['s_per_sim_s']:.3g} | {fmt(r['steps'], 'd')} |"
        )
    return "\n".join(out)


def slider_table(rows: list[dict]) -> str:
    out = [
        "| code | case, integrator | compile [s] | CPU s per simulated s | steps "
        "| slider's x: max difference to the same code's finest run [m] "
        "| to mixdyn's finest run [m] |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        out.append(
            f"| {r['code']} | {r['case']} | {fmt(r['compile_s'], '.1f')} "
            f"| {r['s_per_sim_s']:.3g} | {r['steps']} | {fmt(r['self'], '.1e')} "
            f"| {fmt(r['mixdyn'], '.1e')} |"
        )
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer tolerances and runs")
    ap.add_argument("--repeat", type=int, default=3, help="timed calls after the first")
    ap.add_argument("--skip", nargs="*", default=[], choices=["ball", "slider-crank"])
    args = ap.parse_args()
    repeat = 1 if args.quick else args.repeat
    print("versions:", versions())
    print("load average at the start:", os.getloadavg())
    t_c = hertz_duration(M, K_HERTZ, V0)
    print(
        f"ball: K = {K_HERTZ:.4g} N/m^1.5, impact speed {V0:.4f} m/s, Hertz contact "
        f"{1e6 * t_c:.1f} us, first impact at {impact_time(H0):.6f} s"
    )
    if "ball" not in args.skip:
        rows = ball_mixdyn((1e-8,) if args.quick else (1e-6, 1e-8, 1e-10), repeat)
        for peer, fn in (("exudyn", lambda: ball_exudyn(repeat, args.quick)),
                         ("mujoco", lambda: ball_mujoco(repeat))):  # fmt: skip
            if have(peer):
                rows += fn()
            else:
                print(f"  {peer} is not installed: skipped")
        print()
        e_law = law_restitution(1.5 * (1 - RESTITUTION))
        print(f"The Hunt-Crossley law's own restitution at this impact (SciPy): {e_law:.4f}")
        print()
        print(ball_table(rows))
        print()
    if "slider-crank" not in args.skip:
        rows = slider_crank_mixdyn(repeat)
        if have("exudyn"):
            rows += slider_crank_exudyn(repeat)
        else:
            print("  exudyn is not installed: skipped")
        compare_paths(rows)
        print()
        print(slider_table(rows))
    print()
    print("load average at the end:", os.getloadavg())


if __name__ == "__main__":
    main()

"""A synthesized linkage as a mixdyn model, and as a model file that ``mixdyn run`` runs.

:func:`four_bar_model` builds the :class:`mixdyn.Model` of a :class:`~._fourbar.FourBar`: three
bodies (crank, coupler, rocker) with the masses of :class:`~._dynamics.Masses`, four revolute
joints, the coupler point ``coupler.P``, and the crank driven at a constant speed from the
first input angle. :func:`slider_crank_model` builds a :class:`~._slidercrank.SliderCrank`'s:
crank, rod and slider, three revolute joints and a translational one along the slide, the
coupler point ``rod.P``. :func:`six_bar_model` builds a six-bar's (Stephenson III, Watt I:
five links, seven revolute joints, the coupler point ``tracer.P``).
:func:`linkage_model` picks the builder by the linkage's type;
:func:`model_file_text` writes the model with a kinematic run (the achieved path) and an
inverse run (the motor torque) over the traversed input angles.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..model import Body, CoordinateDriver, Model, Ramp, Revolute, Translational
from ..units import SI
from ._dynamics import Masses, link_inertia
from ._fourbar import FourBar, link_angles
from ._linkage import Linkage
from ._sixbar import SixBar
from ._slidercrank import SliderCrank, rod_and_slider
from ._stephenson import StephensonI, StephensonIII
from ._watt import WattI, WattII


def _numbers(lk: Linkage) -> Linkage:
    return type(lk)(*(np.asarray(x, dtype=float) for x in lk.vector()), np.asarray(lk.branch))


def _rot(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def _body(name, inertia, origin, phi, points, turn=0.0) -> Body:
    """The body of a link whose frame origin ``origin`` (2,) [length] and angle ``phi``
    [rad] are given, with ``inertia`` ``(mass, centre of mass in that frame, inertia about
    it)`` and ``points`` in that frame; the body's own frame is at the centre of mass,
    turned by ``turn`` [rad] from the link's."""
    m, g, j = inertia
    q0 = (*(origin + _rot(phi) @ g), phi + turn)
    back = _rot(-turn)
    points = {k: tuple(back @ (np.asarray(p) - g)) for k, p in points.items()}
    return Body(name, m, j, q0=q0, points=points)


def four_bar_model(
    fb: FourBar,
    masses: Masses | None = None,
    *,
    start: float = 0.0,
    speed: float = 1.0,
    name="synthesized four-bar",
    coupler_angle: float = 0.0,
):
    """The mixdyn model of ``fb``, its crank at ``start`` at t = 0 turning at ``speed``.

    Args:
        fb: the four-bar (unbatched), model units.
        masses: how its links weigh (None: massless links, for kinematics only).
        start: the input angle ``theta2`` at t = 0 [rad].
        speed: the crank's constant speed [rad / time].
        name: the model's name.
        coupler_angle: the angle [rad] of the coupler body's frame (its ``phi``) from the
            coupler's line ``A -> B`` (a motion task's carried body:
            :attr:`~._search.Candidate.coupler_angle`); 0: along it.

    Returns:
        A :class:`mixdyn.Model` in SI units (the numbers read as m, kg, s), with the points
        ``crank.O``, ``crank.A``, ``coupler.A``, ``coupler.B``, ``coupler.P`` (the coupler
        point), ``rocker.O``, ``rocker.B`` and the driver ``motor``.
    """
    fb = _numbers(fb)
    o2, o4 = (np.asarray(p, dtype=float) for p in fb.pivots())
    phi2 = float(fb.theta0) + start
    phi3, phi4 = (float(x) for x in link_angles(fb, start))
    a = np.asarray(fb.crank_pin(start), dtype=float)
    r2, r3, r4 = float(fb.r2), float(fb.r3), float(fb.r4)
    c = np.array([float(fb.rcx), float(fb.rcy)])
    inertia = _inertia(fb, masses)
    ex = np.array([1.0, 0.0])
    turn = float(coupler_angle)
    bodies = [
        _body("crank", inertia["crank"], o2, phi2, {"O": 0 * ex, "A": r2 * ex}),
        _body("coupler", inertia["coupler"], a, phi3, {"A": 0 * ex, "B": r3 * ex, "P": c}, turn),
        _body("rocker", inertia["rocker"], o4, phi4, {"O": 0 * ex, "B": r4 * ex}),
    ]
    gravity = (0.0, 0.0) if masses is None else tuple(float(x) for x in masses.gravity)
    return Model(
        bodies=bodies,
        ground={"O2": tuple(o2), "O4": tuple(o4)},
        joints=[
            Revolute("O2", "ground.O2", "crank.O"),
            Revolute("A", "crank.A", "coupler.A"),
            Revolute("B", "coupler.B", "rocker.B"),
            Revolute("O4", "ground.O4", "rocker.O"),
        ],
        drivers=[CoordinateDriver("motor", "crank", "phi", law=Ramp(phi2, speed))],
        gravity=gravity,
        units=SI,
        name=name,
    )


def _inertia(lk: Linkage, masses: Masses | None) -> dict:
    """Each link's ``(mass, centre of mass in its frame, inertia)`` as floats
    (:func:`~._dynamics.link_inertia`; massless links at their midpoints without masses)."""
    if masses is None:
        return {k: (0.0, v, 0.0) for k, v in _centroids(lk).items()}
    return {
        k: (float(m), np.asarray(g, float), float(j))
        for k, (m, g, j) in link_inertia(lk, masses).items()
    }


def _centroids(lk: Linkage) -> dict:
    """The links' frame origins used for massless links: their midpoints (a slider's pin)."""
    if isinstance(lk, SixBar):
        names = ("crank", "coupler", "rocker", "tracer", "follower")
        return {
            k: np.array([float(getattr(lk, f"r{i}")) / 2, 0.0])
            for i, k in enumerate(names, start=2)
        }
    if isinstance(lk, SliderCrank):
        return {
            "crank": np.array([float(lk.r2) / 2, 0.0]),
            "rod": np.array([float(lk.r3) / 2, 0.0]),
            "slider": np.zeros(2),
        }
    return {
        "crank": np.array([float(lk.r2) / 2, 0.0]),
        "coupler": np.array([float(lk.r3) / 2, 0.0]),
        "rocker": np.array([float(lk.r4) / 2, 0.0]),
    }


def slider_crank_model(
    sc: SliderCrank,
    masses: Masses | None = None,
    *,
    start: float = 0.0,
    speed: float = 1.0,
    name="synthesized slider-crank",
    coupler_angle: float = 0.0,
):
    """The mixdyn model of ``sc``, its crank at ``start`` at t = 0 turning at ``speed``.

    Args:
        sc: the slider-crank (unbatched), model units.
        masses: how its links weigh (None: massless links, for kinematics only); the
            slider's mass ``masses.slider`` > 0 (a dynamic analysis needs every body's).
        start: the input angle ``theta2`` at t = 0 [rad] (from the slide's direction).
        speed: the crank's constant speed [rad / time].
        name: the model's name.
        coupler_angle: the rod body's frame from the rod's line ``A -> B`` [rad]
            (:func:`four_bar_model`'s); 0: along it.

    Returns:
        A :class:`mixdyn.Model` in SI units (the numbers read as m, kg, s), with the points
        ``crank.O``, ``crank.A``, ``rod.A``, ``rod.B``, ``rod.P`` (the coupler point),
        ``slider.B``, the ground's ``O2`` and ``S`` (the slide's point nearest ``O2``), the
        joints ``O2``, ``A``, ``B`` and ``slide`` (translational along the slide, the
        slider's frame along it) and the driver ``motor``. The slider's moment of inertia,
        which its held angle keeps out of every result, is a square block's a tenth of the
        rod's length wide: ``m (r3 / 10)^2 / 6``.

    Raises:
        ModelError: masses whose slider weighs nothing.
    """
    if masses is not None and not masses.slider > 0:
        raise ModelError(
            "a slider-crank's slider needs a mass > 0 with the links' masses: give "
            "Masses(slider=...)",
            "masses",
        )
    sc = _numbers(sc)
    o2 = np.array([float(sc.x0), float(sc.y0)])
    p0, d = (np.asarray(v, dtype=float) for v in sc.slide())
    theta0 = float(sc.theta0)
    phi2 = theta0 + start
    phi3, s = (float(x) for x in rod_and_slider(sc, start))
    a = np.asarray(sc.crank_pin(start), dtype=float)
    r2, r3 = float(sc.r2), float(sc.r3)
    c = np.array([float(sc.rcx), float(sc.rcy)])
    ex = np.array([1.0, 0.0])
    inertia = _inertia(sc, masses)
    turn = float(coupler_angle)
    bodies = [
        _body("crank", inertia["crank"], o2, phi2, {"O": 0 * ex, "A": r2 * ex}),
        _body("rod", inertia["rod"], a, phi3, {"A": 0 * ex, "B": r3 * ex, "P": c}, turn),
        _body("slider", inertia["slider"], p0 + s * d, theta0, {"B": 0 * ex}),
    ]
    gravity = (0.0, 0.0) if masses is None else tuple(float(x) for x in masses.gravity)
    return Model(
        bodies=bodies,
        ground={"O2": tuple(o2), "S": tuple(p0)},
        joints=[
            Revolute("O2", "ground.O2", "crank.O"),
            Revolute("A", "crank.A", "rod.A"),
            Revolute("B", "rod.B", "slider.B"),
            Translational("slide", "ground.S", "slider.B", axis=tuple(d), angle=theta0),
        ],
        drivers=[CoordinateDriver("motor", "crank", "phi", law=Ramp(phi2, speed))],
        gravity=gravity,
        units=SI,
        name=name,
    )


def six_bar_model(
    sb: SixBar,
    masses: Masses | None = None,
    *,
    start: float = 0.0,
    speed: float = 1.0,
    name=None,
    coupler_angle: float = 0.0,
):
    """The mixdyn model of a six-bar (:class:`~._stephenson.StephensonIII`,
    :class:`~._watt.WattI` or :class:`~._watt.WattII`), its crank at ``start`` at t = 0
    turning at ``speed``.

    Args:
        sb: the six-bar (unbatched), model units.
        masses: how its links weigh (:func:`~._dynamics.link_inertia`: the links that carry
            a third point and the tracer triangles of bars, the payload at the coupler
            point);
            None: massless links, for kinematics only.
        start: the input angle ``theta2`` at t = 0 [rad].
        speed: the crank's constant speed [rad / time].
        name: the model's name (default: "synthesized" and the linkage's title).
        coupler_angle: the tracer body's frame from its line ``D -> E`` [rad]
            (:func:`four_bar_model`'s); 0: along it.

    Returns:
        A :class:`mixdyn.Model` in SI units (the numbers read as m, kg, s): the bodies
        ``crank`` (points ``O``, ``A``), ``coupler`` (``A``, ``B``, and ``D`` where it
        carries it), ``rocker`` (``O``, ``B``, and a Watt I's ``F`` or a Watt II's ``D``),
        ``tracer`` (``D``, ``E`` and the coupler point ``P``) and ``follower`` (``E``, and
        ``O`` at the ground pivot ``O6`` or ``F`` at a Watt I's rocker point); the revolute
        joints ``O2``, ``A``, ``B``, ``O4``, ``D``, ``E`` and ``O6`` (Stephenson III, Watt II)
        or ``F`` (Watt I); the driver ``motor``.
    """
    sb = _numbers(sb)
    j = {k: np.asarray(v, dtype=float) for k, v in sb.joints(start).items()}
    phi2 = float(sb.theta0) + start
    r = {n: float(getattr(sb, n)) for n in sb.NAMES}
    ex = np.array([1.0, 0.0])
    d = np.array([r["dx"], r["dy"]])
    c = np.array([r["rcx"], r["rcy"]])
    inertia = _inertia(sb, masses)
    watt = sb.PIVOT_BODY == "rocker"  # the follower's other end F on the rocker
    crank = {"O": 0 * ex, "A": r["r2"] * ex}
    coupler = {"A": 0 * ex, "B": r["r3"] * ex}
    rocker = {"O": 0 * ex, "B": r["r4"] * ex}
    {"crank": crank, "coupler": coupler, "rocker": rocker}[sb.DYAD_BODY]["D"] = d
    if watt:
        rocker["F"] = np.array([r["fx"], r["fy"]])
    end = "F" if watt else "O"
    points = {
        "crank": crank,
        "coupler": coupler,
        "rocker": rocker,
        "tracer": {"D": 0 * ex, "E": r["r5"] * ex, "P": c},
        "follower": {end: 0 * ex, "E": r["r6"] * ex},
    }
    frames = {
        "crank": (j["O2"], phi2),
        "coupler": (j["A"], j["phi3"]),
        "rocker": (j["O4"], j["phi4"]),
        "tracer": (j["D"], j["phi5"]),
        "follower": (j["X"], j["phi6"]),
    }
    bodies = [
        _body(k, inertia[k], *frames[k], points[k], float(coupler_angle) if k == "tracer" else 0)
        for k in points
    ]
    ground = {"O2": tuple(j["O2"]), "O4": tuple(j["O4"])}
    last = Revolute("F", "rocker.F", "follower.F")
    if not watt:
        ground["O6"] = tuple(j["X"])
        last = Revolute("O6", "ground.O6", "follower.O")
    return Model(
        bodies=bodies,
        ground=ground,
        joints=[
            Revolute("O2", "ground.O2", "crank.O"),
            Revolute("A", "crank.A", "coupler.A"),
            Revolute("B", "coupler.B", "rocker.B"),
            Revolute("O4", "ground.O4", "rocker.O"),
            Revolute("D", f"{sb.DYAD_BODY}.D", "tracer.D"),
            Revolute("E", "tracer.E", "follower.E"),
            last,
        ],
        drivers=[CoordinateDriver("motor", "crank", "phi", law=Ramp(phi2, speed))],
        gravity=(0.0, 0.0) if masses is None else tuple(float(x) for x in masses.gravity),
        units=SI,
        name=name or f"synthesized {sb.TITLE}",
    )


#: Each linkage type's model builder and the body that carries its coupler point ``P``.
BUILDERS = {
    FourBar: (four_bar_model, "coupler"),
    SliderCrank: (slider_crank_model, "rod"),
    StephensonI: (six_bar_model, "tracer"),
    StephensonIII: (six_bar_model, "tracer"),
    WattI: (six_bar_model, "tracer"),
    WattII: (six_bar_model, "tracer"),
}


#: The model's column of each function-generating linkage's output
#: (:meth:`~._linkage.Linkage.output`), its crank's pivot at the origin and its ground link
#: (slide) along x: the rocker's angle, the slider's position (its pin's x: the slide's point
#: ``P0`` at x = 0), the follower's angle.
FUNCTION_OUTPUTS = {
    FourBar: "rocker.phi",
    SliderCrank: "slider.x",
    StephensonIII: "follower.phi",
    WattII: "follower.phi",
}


def linkage_model(lk: Linkage, masses: Masses | None = None, **options):
    """The mixdyn model of ``lk`` by its type (:func:`four_bar_model`,
    :func:`slider_crank_model` or :func:`six_bar_model`, which take the ``options``:
    ``start``, ``speed``...)."""
    build, _ = BUILDERS[type(lk)]
    return build(lk, masses, **options)


def model_file_text(
    fb: Linkage,
    masses: Masses | None,
    *,
    start: float,
    end: float,
    speed: float = 1.0,
    targets=None,
    steps: int = 101,
    header: str = "",
    run: tuple | None = None,
    coupler_angle: float = 0.0,
) -> str:
    """YAML text of ``fb``'s model file: a kinematic run (the coupler point's path) and,
    with ``masses``, an inverse run (the motor torque) from ``start`` to ``end`` [rad].

    Args:
        fb: the linkage (a four-bar or a slider-crank: :func:`linkage_model`).
        masses: how its links weigh (None: a kinematic run only).
        start, end: the first and last input angle [rad].
        speed: the crank's speed [rad/s], of the sign of ``end - start``.
        targets: (N, 2) the target points, written in the header as a comment.
        steps: output times of each run.
        header: comment lines above the file (without ``#``).
        run: the kinematic run's ``(name, plotted columns, figure file, output points)``
            (default: ``path``, the coupler point ``P``'s x and y, ``coupler_point.png``).
        coupler_angle: the coupler body's frame from its line ``A -> B`` [rad]
            (:func:`four_bar_model`).
    """
    import yaml

    from ..io.dump import _Dumper, describe, to_data

    if run is None:
        p = f"{BUILDERS[type(fb)][1]}.P"
        run = ("path", [f"{p}.x", f"{p}.y"], "coupler_point.png", [p])
    model = linkage_model(fb, masses, start=start, speed=speed, coupler_angle=coupler_angle)
    data = to_data(describe(model))
    span = [0.0, float(end - start) / speed]
    name, columns, figure, points = run
    runs = [
        {
            "name": name,
            "kind": "kinematic",
            "time": {"span": list(span), "n": steps},
            "plots": [{"file": figure, "columns": list(columns)}],
            **({"outputs": list(points)} if points else {}),
        }
    ]
    if masses is not None:
        runs.append(
            {
                "name": "torque",
                "kind": "inverse",
                "time": {"span": list(span), "n": steps},
                "plots": [{"file": "motor_torque.png", "columns": ["motor"]}],
            }
        )
    data["runs"] = runs
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    if targets is not None:
        lines.append("# targets (x, y) [m]:")
        lines += [f"#   [{x:.6g}, {y:.6g}]" for x, y in np.asarray(targets, dtype=float)]
    text = yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=100)
    return "\n".join(lines) + ("\n" if lines else "") + text


__all__ = [
    "BUILDERS",
    "FUNCTION_OUTPUTS",
    "four_bar_model",
    "linkage_model",
    "model_file_text",
    "six_bar_model",
    "slider_crank_model",
]

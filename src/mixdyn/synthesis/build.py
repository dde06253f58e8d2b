"""A synthesized four-bar as a mixdyn model, and as a model file that ``mixdyn run`` runs.

:func:`four_bar_model` builds the :class:`mixdyn.Model` of a :class:`~._fourbar.FourBar`: three
bodies (crank, coupler, rocker) with the masses of :class:`~._dynamics.Masses`, four revolute
joints, the coupler point ``coupler.P``, and the crank driven at a constant speed from the
first input angle. :func:`model_file_text` writes it with a kinematic run (the achieved path)
and an inverse run (the motor torque) over the traversed input angles.
"""

from __future__ import annotations

import numpy as np

from ..model import Body, CoordinateDriver, Model, Ramp, Revolute
from ..units import SI
from ._dynamics import Masses, link_inertia
from ._fourbar import FourBar, link_angles


def _numbers(fb: FourBar) -> FourBar:
    return FourBar(*(np.asarray(x, dtype=float) for x in fb.vector()), np.asarray(fb.branch))


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
    if masses is None:
        inertia = {k: (0.0, v, 0.0) for k, v in _centroids(fb).items()}
    else:
        inertia = {
            k: (float(m), np.asarray(g, float), float(j))
            for k, (m, g, j) in link_inertia(fb, masses).items()
        }

    def rot(a):
        return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])

    def body(name, origin, phi, points, turn=0.0):
        """The body of a link at angle ``phi`` whose frame is turned by ``turn`` from it."""
        m, g, j = inertia[name]
        q0 = (*(origin + rot(phi) @ g), phi + turn)
        back = rot(-turn)
        return Body(
            name,
            m,
            j,
            q0=q0,
            points={k: tuple(back @ (np.asarray(p) - g)) for k, p in points.items()},
        )

    ex = np.array([1.0, 0.0])
    bodies = [
        body("crank", o2, phi2, {"O": 0 * ex, "A": r2 * ex}),
        body("coupler", a, phi3, {"A": 0 * ex, "B": r3 * ex, "P": c}, float(coupler_angle)),
        body("rocker", o4, phi4, {"O": 0 * ex, "B": r4 * ex}),
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


def _centroids(fb: FourBar) -> dict:
    """The links' frame origins used for massless links: their midpoints."""
    return {
        "crank": np.array([float(fb.r2) / 2, 0.0]),
        "coupler": np.array([float(fb.r3) / 2, 0.0]),
        "rocker": np.array([float(fb.r4) / 2, 0.0]),
    }


def model_file_text(
    fb: FourBar,
    masses: Masses | None,
    *,
    start: float,
    end: float,
    speed: float = 1.0,
    targets=None,
    steps: int = 101,
    header: str = "",
    run: tuple = ("path", ["coupler.P.x", "coupler.P.y"], "coupler_point.png", ["coupler.P"]),
    coupler_angle: float = 0.0,
) -> str:
    """YAML text of ``fb``'s model file: a kinematic run (the coupler point's path) and,
    with ``masses``, an inverse run (the motor torque) from ``start`` to ``end`` [rad].

    Args:
        fb: the four-bar.
        masses: how its links weigh (None: a kinematic run only).
        start, end: the first and last input angle [rad].
        speed: the crank's speed [rad/s], of the sign of ``end - start``.
        targets: (N, 2) the target points, written in the header as a comment.
        steps: output times of each run.
        header: comment lines above the file (without ``#``).
        run: the kinematic run's ``(name, plotted columns, figure file, output points)``.
        coupler_angle: the coupler body's frame from its line ``A -> B`` [rad]
            (:func:`four_bar_model`).
    """
    import yaml

    from ..io.dump import _Dumper, describe, to_data

    model = four_bar_model(fb, masses, start=start, speed=speed, coupler_angle=coupler_angle)
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


__all__ = ["four_bar_model", "model_file_text"]

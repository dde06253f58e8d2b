"""Forces drawn as arrows over a motion: joint reactions, point forces (known or unknown) and
contact forces.

An arrow starts at the point the force acts on and is drawn to one scale for every arrow of
an animation, chosen so that the largest force over the whole motion is a quarter of the
scene's size (:func:`arrow_scale`).
"""

from __future__ import annotations

import numpy as np

from ..model import PointForce
from ..model._compliant import contacts
from ._draw import COLORS

#: The largest arrow of an animation, as a fraction of the scene's largest extent.
ARROW_FRACTION = 0.25


def _place(q: np.ndarray, b: int, s) -> np.ndarray:
    """(N, 2) global positions of the body-frame point ``s`` of body ``b`` (ground: b < 0)."""
    s = np.asarray(s, dtype=float)
    if b < 0:
        return np.broadcast_to(s, (len(q), 2)).copy()
    x, y, phi = q[:, 3 * b], q[:, 3 * b + 1], q[:, 3 * b + 2]
    c, sn = np.cos(phi), np.sin(phi)
    return np.stack([x + c * s[0] - sn * s[1], y + sn * s[0] + c * s[1]], axis=-1)


def force_arrows(result, names=True) -> list[dict]:
    """The forces of a result as arrows.

    A reaction-dependent force (:class:`~mixdyn.model.ReactionDependent`) is drawn where its
    element puts it (its ``arrow``), or not at all where it has none.

    Args:
        result: a :class:`mixdyn.Result` of a forward, inverse or mixed run.
        names: ``True`` for every joint's reaction and every point force; or the names of
            joints (their reaction on body j, at the joint; a contact's force at its contact
            point: a gear's tooth force on gear j, a rolling disk's or a pinion's force on the
            wheel, a cam's push on its follower), of point forces and of reaction-dependent
            forces, and of compliant contacts (their force on body j at the contact point).

    Returns:
        Per arrow: ``name``, ``color``, ``at`` (N, 2) [length], ``F`` (N, 2) [force] and
        ``unit`` (the force's unit).

    Raises:
        ValueError: a kinematic result (no forces), or a name that is neither a joint, a
            point force nor a reaction-dependent force of the model.
    """
    model = result.model
    if result.kind == "kinematic":
        raise ValueError(
            "a kinematic result has no forces to draw; run an inverse, forward or mixed analysis"
        )
    joints = {j.name: j for j in model.joints}
    forces = {f.name: f for f in model.forces if isinstance(f, PointForce)}
    dependent = {f.name: f for f in model.forces if f.needs_reactions}
    touching = {f.name: f for f in contacts(model)}
    wanted = (
        list(joints) + list(forces) + list(dependent) + list(touching)
        if names is True
        else list(names)
    )
    cols, units = result.columns(), result.units()
    q = np.asarray(result.q)
    out = []
    for k, name in enumerate(wanted):
        if name in joints and not joints[name].generic_reaction:  # a contact's own arrow
            drawn = joints[name].arrow(q, cols)
            if drawn is None:
                continue
            at, F = drawn
            key = next(iter(joints[name].contact_kinds))
            out.append(
                {
                    "name": name,
                    "color": COLORS[(k + 3) % len(COLORS)],
                    "at": at,
                    "F": np.asarray(F, dtype=float),
                    "unit": units[f"{name}.{key}"],
                }
            )
            continue
        if name in touching:  # a compliant contact's force on body j, at its contact point
            at, F = touching[name].arrow(
                q, np.asarray(result.qd), cols.get(f"{name}.normal"), cols.get(f"{name}.friction")
            )
            out.append(
                {
                    "name": name,
                    "color": COLORS[(k + 3) % len(COLORS)],
                    "at": at,
                    "F": F,
                    "unit": units[f"{name}.normal"],
                }
            )
            continue
        if name in joints:
            if f"{name}.Fx" not in cols:
                continue
            b, s = joints[name].reaction_point()
            F = np.stack([cols[f"{name}.Fx"], cols[f"{name}.Fy"]], axis=-1)
            unit = units[f"{name}.Fx"]
        elif name in dependent:
            drawn = dependent[name].arrow(model, q)
            if drawn is None or name not in cols:
                continue
            b, s, u = drawn
            F = np.asarray(cols[name])[:, None] * u
            unit = units[name]
        elif name in forces:
            f = forces[name]
            if name not in cols:
                continue
            b, s = f.b, f.s
            u = np.asarray(f.u, dtype=float)
            if f.frame == "body":
                phi = q[:, 3 * b + 2]
                c, sn = np.cos(phi), np.sin(phi)
                u = np.stack([c * u[0] - sn * u[1], sn * u[0] + c * u[1]], axis=-1)
            F = np.asarray(cols[name])[:, None] * u
            unit = units[name]
        else:
            from .._hints import did_you_mean

            raise ValueError(
                f"cannot draw the force {name!r}: it is neither a joint, a point force, a "
                "reaction-dependent force nor a contact; "
                + did_you_mean(name, [*joints, *forces, *dependent, *touching])
            )
        out.append(
            {
                "name": name,
                "color": COLORS[(k + 3) % len(COLORS)],
                "at": _place(q, int(b), s),
                "F": np.asarray(F, dtype=float),
                "unit": unit,
            }
        )
    return out


def arrow_scale(arrows: list[dict], bounds) -> float:
    """Length per unit of force [length/force] so that the largest force is
    :data:`ARROW_FRACTION` of the scene ``bounds`` ``(xmin, xmax, ymin, ymax)``; 0 when
    every force is zero."""
    biggest = max(
        (float(np.max(np.hypot(a["F"][:, 0], a["F"][:, 1]))) for a in arrows), default=0.0
    )
    span = max(bounds[1] - bounds[0], bounds[3] - bounds[2])
    return ARROW_FRACTION * span / biggest if biggest > 0 else 0.0


__all__ = ["ARROW_FRACTION", "arrow_scale", "force_arrows"]

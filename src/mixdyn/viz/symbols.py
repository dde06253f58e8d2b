"""Force elements drawn as symbols over a motion: a spring as a coil, a damper as a cylinder and
piston, a rotary spring as a spiral, a torque (an element's or a motor's effort) as an arc with
an arrowhead, and an applied point force as an arrow.

Every symbol is one polyline per instant, ``(N, k, 2)`` [length], whose pieces are separated by
NaN rows (a pen lift), so that the GIF painter, ``mixdyn show`` and the HTML player draw them
alike. Sizes are fractions of the scene's extent ``span``.
"""

from __future__ import annotations

import numpy as np

from ..model import PointForce
from ..model._forces import RotarySpringDamper, SpringDamper, Torque

#: Half the width of a coil or damper, as a fraction of the scene's extent.
WIDTH = 0.018
#: The radius of a torque's arc, as a fraction of the scene's extent.
ARC = 0.06
#: The largest sweep of a torque's arc [rad] (its largest magnitude over the motion).
SWEEP = 1.5 * np.pi
#: The colour of springs and dampers.
INK = "#333333"

_LIFT = np.full((1, 2), np.nan)


def _frame(p0: np.ndarray, p1: np.ndarray):
    """Unit vector along ``p0 -> p1``, its normal and the distance (per instant, (N, 2))."""
    d = p1 - p0
    L = np.hypot(d[..., 0], d[..., 1])
    safe = np.where(L > 0, L, 1.0)[..., None]
    u = np.where(L[..., None] > 0, d / safe, np.array([1.0, 0.0]))
    n = np.stack([-u[..., 1], u[..., 0]], axis=-1)
    return u, n, L


def _local(p0, u, n, along, across) -> np.ndarray:
    """Points ``p0 + along u + across n``: (N, k, 2) from (N, 2) frames and (k,) or (N, k)."""
    along, across = np.broadcast_arrays(np.atleast_2d(along), np.atleast_2d(across))
    return p0[:, None, :] + along[..., None] * u[:, None, :] + across[..., None] * n[:, None, :]


def coil(p0, p1, width: float, turns: int = 6, lead: float = 0.15) -> np.ndarray:
    """A spring's coil from ``p0`` to ``p1`` (N, 2) [length]: straight leads of ``lead`` of the
    length at both ends and ``turns`` zigzags of half-width ``width`` between them.

    Returns:
        (N, 2 turns + 4, 2): the polyline, its first point ``p0`` and its last ``p1``.
    """
    p0, p1 = np.atleast_2d(p0).astype(float), np.atleast_2d(p1).astype(float)
    u, n, L = _frame(p0, p1)
    k = 2 * turns
    s = np.concatenate(
        [[0.0, lead], lead + (1 - 2 * lead) * (np.arange(k) + 0.5) / k, [1 - lead, 1]]
    )
    side = np.concatenate([[0.0, 0.0], width * (-1.0) ** np.arange(k), [0.0, 0.0]])
    return _local(p0, u, n, s[None] * L[:, None], np.broadcast_to(side, (len(L), len(s))))


def damper(p0, p1, width: float) -> np.ndarray:
    """A damper from ``p0`` to ``p1`` (N, 2): a rod from ``p0`` to a piston plate, a cylinder
    open towards ``p0`` and a rod from its bottom to ``p1``. The cylinder (a third of the
    distance at the first instant long) moves with ``p1``, the piston with ``p0``: it slides
    in the cylinder as the distance changes.

    Returns:
        (N, k, 2) with NaN rows between the pieces.
    """
    p0, p1 = np.atleast_2d(p0).astype(float), np.atleast_2d(p1).astype(float)
    u, n, L = _frame(p0, p1)
    L0 = L[0] if len(L) else 0.0
    c = L0 / 3
    bottom = L - 0.3 * L0  # the cylinder's bottom, from p0 (fixed to p1)
    mouth = bottom - c
    piston = np.clip(0.7 * L0 - 0.55 * c, mouth, bottom)  # fixed to p0, inside the cylinder
    w = width
    pieces = [
        (np.stack([0 * L, piston], 1), np.zeros((len(L), 2))),  # rod to the piston
        (np.stack([piston, piston], 1), np.tile([-0.8 * w, 0.8 * w], (len(L), 1))),  # plate
        (np.stack([mouth, bottom, bottom, mouth], 1), np.tile([w, w, -w, -w], (len(L), 1))),
        (np.stack([bottom, L], 1), np.zeros((len(L), 2))),  # rod from the bottom to p1
    ]
    out = []
    for along, across in pieces:
        if out:
            out.append(np.broadcast_to(_LIFT, (len(L), 1, 2)))
        out.append(_local(p0, u, n, along, across))
    return np.concatenate(out, axis=1)


def arc_arrow(centre, radius: float, turn, start=None) -> np.ndarray:
    """A torque's arc about ``centre`` (N, 2): radius ``radius``, sweeping ``turn`` (N,) [rad]
    (positive: counter-clockwise), from the angle ``start`` (N,) (default: pi/4 behind the
    arc's middle, at the top), with an arrowhead at its end.

    Returns:
        (N, 40, 2): 36 points of arc, a pen lift and the head's three points.
    """
    centre = np.atleast_2d(centre).astype(float)
    turn = np.broadcast_to(np.asarray(turn, dtype=float), (len(centre),))
    if start is None:
        start = np.pi / 2 - turn / 2
    a = np.asarray(start, dtype=float)[:, None] + turn[:, None] * np.linspace(0, 1, 36)[None]
    ring = centre[:, None, :] + radius * np.stack([np.cos(a), np.sin(a)], axis=-1)
    tip = ring[:, -1]
    sign = np.where(turn >= 0, 1.0, -1.0)[:, None]
    tangent = sign * np.stack([-np.sin(a[:, -1]), np.cos(a[:, -1])], axis=-1)
    radial = np.stack([np.cos(a[:, -1]), np.sin(a[:, -1])], axis=-1)
    h = 0.35 * radius * np.minimum(1.0, np.abs(turn) / 0.6)[:, None]
    head = np.stack(
        [tip - h * tangent + 0.5 * h * radial, tip, tip - h * tangent - 0.5 * h * radial], axis=1
    )
    return np.concatenate([ring, np.broadcast_to(_LIFT, (len(centre), 1, 2)), head], axis=1)


def spiral(centre, angle, radius: float, turns: float = 2.5) -> np.ndarray:
    """A rotary spring's spiral about ``centre`` (N, 2), turning with ``angle`` (N,) [rad].

    Returns:
        (N, 60, 2).
    """
    centre = np.atleast_2d(centre).astype(float)
    s = np.linspace(0.0, 1.0, 60)
    a = np.asarray(angle, dtype=float)[:, None] + 2 * np.pi * turns * s[None]
    r = radius * (0.25 + 0.75 * s)[None]
    return centre[:, None, :] + np.stack([r * np.cos(a), r * np.sin(a)], axis=-1)


def arrow(at, F, length: float) -> np.ndarray:
    """A force's arrow from ``at`` (N, 2) along ``F`` (N, 2), ``length`` [length] per unit
    of ``F``, with a head a fifth of the largest arrow's length.

    Returns:
        (N, 6, 2): the shaft, a pen lift, the head's three points.
    """
    at, F = np.atleast_2d(at).astype(float), np.atleast_2d(F).astype(float)
    tip = at + length * F
    u, n, L = _frame(at, tip)
    h = 0.2 * np.minimum(L, float(np.max(L, initial=0.0)))[:, None]
    head = np.stack([tip - h * u + 0.45 * h * n, tip, tip - h * u - 0.45 * h * n], axis=1)
    return np.concatenate(
        [np.stack([at, tip], 1), np.broadcast_to(_LIFT, (len(at), 1, 2)), head], axis=1
    )


# --------------------------------------------------------------------------- a model's symbols
def _point(q, b, s):
    from .arrows import _place

    return _place(q, b, s)


def _motor_centre(model, q, bi: int, bj: int) -> np.ndarray:
    """Where a torque between bodies ``bi`` and ``bj`` is drawn: a pin joining them, else
    body ``bj``'s reference point."""
    for j in model.joints:
        if {getattr(j, "bi", None), getattr(j, "bj", None)} == {bi, bj}:
            pins = j.drawing().get("pins", ())
            if pins:
                b, s = pins[0]
                return _point(q, b, s)
    return _point(q, bj, (0.0, 0.0))


def symbols(model, q, span: float, cols: dict | None = None, units: dict | None = None):
    """The force elements of ``model`` as symbols over the coordinates ``q`` (N, nq).

    Springs, dampers and rotary springs are always drawn; torques (torque elements and
    drivers whose effort is a torque) and point forces are drawn from their magnitudes in
    ``cols`` (the result's columns at the same instants), or without them (a model drawn at
    rest) as a torque's half turn counter-clockwise and a force's arrow of fixed length
    along its direction.

    Args:
        model: the mechanism.
        q: (N, nq) coordinates.
        span: the scene's largest extent [length] (the symbols' sizes are fractions of it).
        cols: the result's columns at the instants of ``q``, or None.
        units: the columns' units (named in each symbol's ``label``).

    Returns:
        Per symbol: ``name``, ``kind`` (``spring``, ``damper``, ``spring_damper``,
        ``rotary_spring``, ``torque``, ``force``), ``color``, ``path`` (N, k, 2) [length],
        ``label`` (the name, with the largest magnitude and its unit where known) and
        ``anchor`` (N, 2), where its name is written.
    """
    from ._draw import COLORS

    q = np.atleast_2d(np.asarray(q, dtype=float))
    units = units or {}
    w, radius = WIDTH * span, ARC * span
    out = []

    def add(name, kind, color, path, anchor, label=None):
        out.append(
            {
                "name": name,
                "kind": kind,
                "color": color,
                "path": path,
                "anchor": anchor,
                "label": label or name,
            }
        )

    torques = []  # (name, centre (N, 2), magnitude (N,) or None)
    forces = []  # (name, at, direction (N, 2), magnitude or None)
    for f in model.forces:
        if isinstance(f, SpringDamper):
            p0, p1 = _point(q, f.bi, f.si), _point(q, f.bj, f.sj)
            k, c = float(f.stiffness) != 0.0, float(f.damping) != 0.0
            if k and c:  # the coil and the damper side by side, joined at both ends
                u, n, L = _frame(p0, p1)
                lead = 0.12 * L[:, None]
                a0, a1 = p0 + lead * u, p1 - lead * u
                parts = [
                    np.stack([p0, a0], 1),
                    np.stack([a0 + 1.6 * w * n, a0 - 1.6 * w * n], 1),
                    coil(a0 + 1.6 * w * n, a1 + 1.6 * w * n, w, turns=5, lead=0.05),
                    damper(a0 - 1.6 * w * n, a1 - 1.6 * w * n, w),
                    np.stack([a1 + 1.6 * w * n, a1 - 1.6 * w * n], 1),
                    np.stack([a1, p1], 1),
                ]
                lift = np.broadcast_to(_LIFT, (len(q), 1, 2))
                path = np.concatenate([x for p in parts for x in (p, lift)][:-1], axis=1)
                kind = "spring_damper"
            elif c:
                path, kind = damper(p0, p1, w), "damper"
            else:
                path, kind = coil(p0, p1, w), "spring"
            add(f.name, kind, INK, path, 0.5 * (p0 + p1))
            if cols is not None and f.name in cols and np.any(np.asarray(cols[f.name]) != 0):
                u, _, _ = _frame(p0, p1)  # the actuator pushes the points apart: on j along u
                forces.append((f.name, p1, u, np.asarray(cols[f.name], dtype=float)))
        elif isinstance(f, RotarySpringDamper):
            centre = _motor_centre(model, q, f.bi, f.bj)
            phi = q[:, 3 * f.bj + 2] if f.bj >= 0 else np.zeros(len(q))
            add(f.name, "rotary_spring", INK, spiral(centre, phi, 0.8 * radius), centre)
            if cols is not None and f.name in cols and np.any(np.asarray(cols[f.name]) != 0):
                torques.append((f.name, centre, np.asarray(cols[f.name], dtype=float)))
        elif isinstance(f, Torque):
            centre = _motor_centre(model, q, f.br, f.b)
            torques.append((f.name, centre, None if cols is None else cols.get(f.name)))
        elif isinstance(f, PointForce):
            at = _point(q, f.b, f.s)
            u = np.broadcast_to(np.asarray(f.u, dtype=float), (len(q), 2))
            if f.frame == "body":
                phi = q[:, 3 * f.b + 2]
                c, s = np.cos(phi), np.sin(phi)
                u = np.stack([c * u[:, 0] - s * u[:, 1], s * u[:, 0] + c * u[:, 1]], axis=-1)
            forces.append((f.name, at, u, None if cols is None else cols.get(f.name)))
    for d in model.drivers:
        if d.effort_kind != "torque" or cols is None or d.name not in cols:
            continue
        bi, bj = (-1, d.b) if hasattr(d, "b") else (d.bi, d.bj)
        torques.append((d.name, _motor_centre(model, q, bi, bj), np.asarray(cols[d.name])))

    def label(name, m):
        if m is None:
            return name
        big = float(np.max(np.abs(m)))
        return f"{name} (max {big:.3g} {units.get(name, '')})".replace(" )", ")")

    for k, (name, centre, m) in enumerate(torques):
        m = None if m is None else np.asarray(m, dtype=float)
        big = float(np.max(np.abs(m))) if m is not None and m.size else 0.0
        turn = np.full(len(q), np.pi) if m is None else (SWEEP * m / big if big else 0 * m)
        color = COLORS[(k + 5) % len(COLORS)]
        add(name, "torque", color, arc_arrow(centre, radius, turn), centre, label(name, m))
    if forces:
        mags = [np.abs(m) for _, _, _, m in forces if m is not None]
        big = max((float(np.max(m)) for m in mags if m.size), default=0.0)
        for k, (name, at, u, m) in enumerate(forces):
            if m is None:
                path = arrow(at, u, 0.12 * span)
            else:
                m = np.asarray(m, dtype=float)
                path = arrow(at, m[:, None] * u, 0.2 * span / big if big else 0.0)
            color = COLORS[(k + 7) % len(COLORS)]
            add(name, "force", color, path, at, label(name, m))
    return out


__all__ = ["arc_arrow", "arrow", "coil", "damper", "spiral", "symbols"]

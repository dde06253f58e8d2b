"""The scene of a motion: each body's outline (its points' convex hull, a bar, a small block,
or a shape its joints give it: a gear's circle, a cam's profile), the pins, the ground's points
and guide lines, traced paths, and the bounds, over the output times; what the GIF painter and
the HTML player draw."""

from __future__ import annotations

import numpy as np

from ..model import Model
from ..model._compliant import contacts
from ..model._element import Resolver
from .symbols import symbols


def _hull(points: np.ndarray) -> np.ndarray:
    """Convex hull (counter-clockwise) of (n, 2) points; a bar's two ends if collinear."""
    pts = np.unique(np.round(points, 12), axis=0)
    if len(pts) <= 2:
        return pts
    pts = pts[np.lexsort((pts[:, 1], pts[:, 0]))]

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    scale = float(np.ptp(pts, axis=0).max()) or 1.0
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 1e-12 * scale**2:
            lower.pop()
        lower.append(p)
    for p in pts[::-1]:
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 1e-12 * scale**2:
            upper.pop()
        upper.append(p)
    hull = np.array(lower[:-1] + upper[:-1])
    return hull


class Scene:
    """Global drawing data of a model over a motion.

    Args:
        model: the mechanism.
        q: (N, nq) coordinates at N instants.
        trace: point references whose paths are drawn.
        cols: the result's columns at the instants of ``q`` (the torques' and forces'
            magnitudes), or None (a model drawn at rest).
        units: the columns' units.

    Attributes:
        outlines: per body, (N, k, 2) outline vertices (closed polygon, bar or block).
        pins: (N, P, 2) positions of the revolute-type joints.
        ground: (G, 2) ground points.
        guides: (L, 2, 2) guide lines of sliding joints on the ground.
        traces: per traced point, (N, 2).
        symbols: the force elements as symbols (springs' coils, dampers, torques' arcs,
            point forces' arrows; :func:`mixdyn.viz.symbols.symbols`).
        bounds: ``(xmin, xmax, ymin, ymax)`` of the whole scene.
    """

    def __init__(self, model: Model, q: np.ndarray, trace=(), cols=None, units=None):
        q = np.atleast_2d(np.asarray(q, dtype=float))
        self.model = model
        self.names = [b.name for b in model.bodies]
        scale = self._scale(model, q)
        drawings = [j.drawing() for j in model.joints] + [f.drawing() for f in contacts(model)]
        rims = {b: [] for b in range(len(model.bodies))}  # circles' samples per body
        ring = np.linspace(0.0, 2 * np.pi, 48, endpoint=False)
        for d in drawings:
            for b, s, radius in d.get("circles", ()):
                if b >= 0:  # the circle, with a tooth on the body's x axis to show its turning
                    c = np.asarray(s, dtype=float) + float(radius) * np.stack(
                        [np.cos(ring), np.sin(ring)], axis=1
                    )
                    tooth = np.asarray(s, dtype=float) + np.array([1.15 * float(radius), 0.0])
                    rims[b].append(np.vstack([c, tooth]))
        shapes = {b: np.asarray(s, dtype=float) for d in drawings for b, s in d.get("shapes", ())}
        self.outlines = []
        for b, body in enumerate(model.bodies):
            if b in shapes:  # a body drawn by its own outline (a cam's profile)
                self.outlines.append(self._place(q, b, shapes[b]))
                continue
            local = np.array([[0.0, 0.0], *[np.asarray(p) for p in body.points.values()]])
            if rims[b]:
                local = np.concatenate([local, *rims[b]])
            hull = _hull(local)
            if len(hull) == 1:
                h = 0.03 * scale
                hull = np.array([[-h, -h * 0.6], [h, -h * 0.6], [h, h * 0.6], [-h, h * 0.6]])
            self.outlines.append(self._place(q, b, hull))
        pins = []
        for d in drawings:
            for b, s in d.get("pins", ()):
                s = np.asarray(s, dtype=float)
                pins.append(
                    self._place(q, b, s[None])[:, 0] if b >= 0 else np.broadcast_to(s, (len(q), 2))
                )
        self.pins = np.stack(pins, axis=1) if pins else np.zeros((len(q), 0, 2))
        self.ground = np.array([np.asarray(p) for p in model.ground.points.values()]).reshape(-1, 2)
        self.traces = []
        resolver = Resolver(model.ground, model.bodies)
        for ref in trace:
            b, s = resolver.point(ref, "trace")
            s = np.asarray(s, dtype=float)
            if b < 0:
                self.traces.append(np.broadcast_to(s, (len(q), 2)).copy())
            else:
                self.traces.append(self._place(q, b, s[None])[:, 0])
        rings = [  # circles on the ground (a ring a wheel rolls in)
            np.asarray(s, dtype=float) + float(radius) * np.stack([np.cos(ring), np.sin(ring)], 1)
            for d in drawings
            for b, s, radius in d.get("circles", ())
            if b < 0
        ]
        edges = [  # sides on the ground (a fixed shape's outline, a polyline)
            np.asarray(e, dtype=float).reshape(2, 2) for d in drawings for e in d.get("edges", ())
        ]
        outlines = [o.reshape(-1, 2) for o in self.outlines]
        allpts = [*outlines, self.ground, *self.traces, *rings, *edges]
        allpts = np.concatenate([a for a in allpts if a.size], axis=0)
        lo, hi = allpts.min(axis=0), allpts.max(axis=0)
        span = max(float((hi - lo).max()), 1e-9)
        pad = 0.08 * span
        self.bounds = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
        guides = []
        for d in drawings:
            for p0, u in d.get("guides", ()):
                p0, u = np.asarray(p0, dtype=float), np.asarray(u, dtype=float)
                guides.append([p0 - 2 * span * u, p0 + 2 * span * u])
        guides += [list(e) for e in edges]
        for c in rings:  # drawn as its chords
            guides += [[c[k], c[(k + 1) % len(c)]] for k in range(len(c))]
        self.guides = np.array(guides).reshape(-1, 2, 2)
        self.symbols = symbols(model, q, span, cols, units)

    @staticmethod
    def _scale(model, q):
        vals = [1e-9]
        for b in model.bodies:
            vals += [float(np.abs(np.asarray(p)).max()) for p in b.points.values()]
        vals += [float(np.abs(np.asarray(p)).max()) for p in model.ground.points.values()]
        vals.append(float(np.ptp(q[:, 0::3])) if q.size else 0.0)
        vals.append(float(np.ptp(q[:, 1::3])) if q.size else 0.0)
        return max(vals)

    @staticmethod
    def _place(q, b, local):
        """(N, k, 2) global positions of body-frame points ``local`` (k, 2) of body ``b``."""
        x, y, phi = q[:, 3 * b], q[:, 3 * b + 1], q[:, 3 * b + 2]
        c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
        gx = x[:, None] + c * local[None, :, 0] - s * local[None, :, 1]
        gy = y[:, None] + s * local[None, :, 0] + c * local[None, :, 1]
        return np.stack([gx, gy], axis=-1)


def _frames(n: int, frames: int) -> np.ndarray:
    return np.unique(np.round(np.linspace(0, n - 1, max(2, min(frames, n)))).astype(int))


def _motion(result=None, model=None, t=None, q=None):
    if result is not None:
        return result.model, np.asarray(result.t), np.asarray(result.q)
    if model is None or t is None or q is None:
        raise ValueError("give a result, or a model with t and q")
    return model, np.asarray(t, dtype=float), np.asarray(q, dtype=float)


__all__ = ["Scene"]

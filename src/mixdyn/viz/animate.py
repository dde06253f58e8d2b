"""The mechanism moving: an animated GIF (or MP4, if ffmpeg exists) and a self-contained HTML
page (an inline script drawing on a canvas; no network access needed).

Each body is drawn as the outline of its points (their convex hull, or a bar when they are in a
line, or a small block when it has none), joints as pins, the ground's points as small
triangles, and a sliding joint on the ground as its guide line.
"""

from __future__ import annotations

import json
import pathlib
import shutil

import numpy as np

from ..model import Model, PinInSlot, Revolute, Translational
from ..model._element import Resolver
from . import _draw
from ._draw import COLORS as _COLORS

ANIMATION_SUFFIXES = (".gif", ".mp4", ".html")


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

    Attributes:
        outlines: per body, (N, k, 2) outline vertices (closed polygon, bar or block).
        pins: (N, P, 2) positions of the revolute-type joints.
        ground: (G, 2) ground points.
        guides: (L, 2, 2) guide lines of sliding joints on the ground.
        traces: per traced point, (N, 2).
        bounds: ``(xmin, xmax, ymin, ymax)`` of the whole scene.
    """

    def __init__(self, model: Model, q: np.ndarray, trace=()):
        q = np.atleast_2d(np.asarray(q, dtype=float))
        self.model = model
        self.names = [b.name for b in model.bodies]
        scale = self._scale(model, q)
        self.outlines = []
        for b, body in enumerate(model.bodies):
            local = np.array([[0.0, 0.0], *[np.asarray(p) for p in body.points.values()]])
            hull = _hull(local)
            if len(hull) == 1:
                h = 0.03 * scale
                hull = np.array([[-h, -h * 0.6], [h, -h * 0.6], [h, h * 0.6], [-h, h * 0.6]])
            self.outlines.append(self._place(q, b, hull))
        pins = []
        for j in model.joints:
            if isinstance(j, Revolute | PinInSlot):
                b, s = j.bj, np.asarray(j.sj)
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
        allpts = [o.reshape(-1, 2) for o in self.outlines] + [self.ground] + self.traces
        allpts = np.concatenate([a for a in allpts if a.size], axis=0)
        lo, hi = allpts.min(axis=0), allpts.max(axis=0)
        span = max(float((hi - lo).max()), 1e-9)
        pad = 0.08 * span
        self.bounds = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
        guides = []
        for j in model.joints:
            if isinstance(j, Translational) and j.bi < 0 and j.u is not None:
                p0, u = np.asarray(j.si), np.asarray(j.u)
                guides.append([p0 - 2 * span * u, p0 + 2 * span * u])
        self.guides = np.array(guides).reshape(-1, 2, 2)

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


def animate(
    result=None,
    path="animation.gif",
    *,
    model: Model | None = None,
    t=None,
    q=None,
    fps: int = 20,
    frames: int = 80,
    trace=(),
    title: str | None = None,
    size: tuple[float, float] | None = None,
    dpi: int = 80,
) -> pathlib.Path:
    """Write an animation of a motion: ``.gif`` (Pillow), ``.mp4`` (needs ffmpeg) or
    ``.html`` (see :func:`html`).

    Args:
        result: a :class:`mixdyn.Result`; or give ``model``, ``t`` (N,) and ``q`` (N, nq).
        path: the output file.
        fps: frames per second.
        frames: the largest number of frames (evenly spaced output times).
        trace: point references (``"coupler.C"``) whose paths are drawn.
        title: a title (default: the model's name).
        size, dpi: figure size [inch] (default: from the scene's proportions) and resolution.

    Returns:
        The path written.
    """
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix == ".html":
        return html(
            result, path, model=model, t=t, q=q, fps=fps, frames=frames, trace=trace, title=title
        )
    if suffix not in (".gif", ".mp4"):
        raise ValueError(
            f"cannot write an animation to {path.name!r}; use {', '.join(ANIMATION_SUFFIXES)}"
        )
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ValueError("writing MP4 needs ffmpeg, which is not installed; write a .gif or .html")
    return _draw.movie(
        movie_data(result, model=model, t=t, q=q, frames=frames, trace=trace, title=title),
        path,
        fps=fps,
        size=size,
        dpi=dpi,
    )


def movie_data(result=None, *, model=None, t=None, q=None, frames=80, trace=(), title=None):
    """What :func:`animate` draws, as plain data (NumPy arrays, strings): the scene at the
    frames' times, their times, the title and units (see :func:`mixdyn.viz._draw.movie`)."""
    model, ts, qs = _motion(result, model, t, q)
    idx = _frames(len(ts), frames)
    scene = Scene(model, qs[idx], trace)
    return {
        "outlines": scene.outlines,
        "names": scene.names,
        "pins": scene.pins,
        "ground": scene.ground,
        "guides": scene.guides,
        "traces": scene.traces,
        "bounds": scene.bounds,
        "times": ts[idx],
        "title": title if title is not None else model.name,
        "length_unit": model.units.length,
        "time_unit": model.units.time,
    }


def html(
    result=None,
    path="animation.html",
    *,
    model: Model | None = None,
    t=None,
    q=None,
    fps: int = 20,
    frames: int = 200,
    trace=(),
    title: str | None = None,
) -> pathlib.Path:
    """Write a self-contained HTML page that plays the motion (play/pause, time slider).

    Arguments as in :func:`animate`. The page holds its data and script inline.
    """
    model, ts, qs = _motion(result, model, t, q)
    idx = _frames(len(ts), frames)
    scene = Scene(model, qs[idx], trace)

    def r(a):
        return np.round(np.asarray(a, dtype=float), 6).tolist()

    data = {
        "title": title if title is not None else model.name,
        "t": r(ts[idx]),
        "units": {"length": model.units.length, "time": model.units.time},
        "bounds": r(scene.bounds),
        "fps": int(fps),
        "bodies": [
            {"name": n, "color": _COLORS[k % len(_COLORS)], "outline": r(o)}
            for k, (n, o) in enumerate(zip(scene.names, scene.outlines, strict=True))
        ],
        "pins": r(scene.pins),
        "ground": r(scene.ground),
        "guides": r(scene.guides),
        "traces": [r(tr) for tr in scene.traces],
    }
    page = _HTML.replace("__TITLE__", _escape(data["title"])).replace(
        "__DATA__", json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    )
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(page, encoding="utf-8")
    return path


def _escape(text: str) -> str:
    return (
        str(text)
        .replace("&", "&amp;")
        .replace("<", "&lt;")
        .replace(">", "&gt;")
        .replace('"', "&quot;")
    )


_HTML = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>__TITLE__ - mixdyn</title>
<style>
 body { font-family: system-ui, sans-serif; margin: 1.2em; color: #222; }
 canvas { border: 1px solid #ccc; background: #fff; max-width: 100%; }
 .bar { display: flex; gap: .8em; align-items: center; margin-top: .5em; }
 input[type=range] { flex: 1; }
 .legend span { display: inline-block; margin-right: 1em; }
 .legend i { display: inline-block; width: .9em; height: .9em; margin-right: .3em; }
</style>
</head>
<body>
<h2>__TITLE__</h2>
<canvas id="view" width="800" height="600"></canvas>
<div class="bar">
 <button id="play">Pause</button>
 <input id="slider" type="range" min="0" value="0">
 <span id="time"></span>
</div>
<div class="legend" id="legend"></div>
<script>
"use strict";
const D = __DATA__;
const cv = document.getElementById("view"), cx = cv.getContext("2d");
const slider = document.getElementById("slider"), play = document.getElementById("play");
const label = document.getElementById("time");
const n = D.t.length;
slider.max = n - 1;
const [x0, x1, y0, y1] = D.bounds;
const k = Math.min(cv.width / (x1 - x0), cv.height / (y1 - y0));
const ox = (cv.width - k * (x1 - x0)) / 2, oy = (cv.height - k * (y1 - y0)) / 2;
const X = x => ox + k * (x - x0), Y = y => cv.height - oy - k * (y - y0);
for (const b of D.bodies) {
  const s = document.createElement("span");
  s.innerHTML = '<i style="background:' + b.color + '"></i>' + b.name;
  document.getElementById("legend").appendChild(s);
}
function path(pts, close) {
  cx.beginPath();
  pts.forEach((p, i) => i ? cx.lineTo(X(p[0]), Y(p[1])) : cx.moveTo(X(p[0]), Y(p[1])));
  if (close) cx.closePath();
}
function draw(i) {
  cx.clearRect(0, 0, cv.width, cv.height);
  cx.setLineDash([6, 4]); cx.strokeStyle = "#999"; cx.lineWidth = 1;
  for (const g of D.guides) { path(g, false); cx.stroke(); }
  cx.setLineDash([]);
  cx.fillStyle = "#555";
  for (const g of D.ground) {
    cx.beginPath(); cx.moveTo(X(g[0]), Y(g[1]));
    cx.lineTo(X(g[0]) - 7, Y(g[1]) + 12); cx.lineTo(X(g[0]) + 7, Y(g[1]) + 12);
    cx.closePath(); cx.fill();
  }
  cx.strokeStyle = "#000"; cx.globalAlpha = 0.6;
  for (const tr of D.traces) { path(tr.slice(0, i + 1), false); cx.stroke(); }
  cx.globalAlpha = 1;
  for (const b of D.bodies) {
    const o = b.outline[i], closed = o.length > 2;
    path(o, closed);
    cx.strokeStyle = b.color; cx.lineWidth = closed ? 2 : 6;
    if (closed) { cx.globalAlpha = 0.75; cx.fillStyle = b.color; cx.fill(); cx.globalAlpha = 1; }
    cx.stroke();
  }
  cx.lineWidth = 1.5; cx.strokeStyle = "#000"; cx.fillStyle = "#fff";
  for (const p of (D.pins[i] || [])) {
    cx.beginPath(); cx.arc(X(p[0]), Y(p[1]), 4.5, 0, 2 * Math.PI); cx.fill(); cx.stroke();
  }
  label.textContent = "t = " + D.t[i].toFixed(3) + " " + D.units.time +
    "   (lengths in " + D.units.length + ")";
  slider.value = i;
}
let frame = 0, running = true, last = 0;
function tick(now) {
  if (running && now - last >= 1000 / D.fps) { last = now; frame = (frame + 1) % n; draw(frame); }
  requestAnimationFrame(tick);
}
play.onclick = () => { running = !running; play.textContent = running ? "Pause" : "Play"; };
slider.oninput = () => { frame = +slider.value; draw(frame); };
draw(0);
requestAnimationFrame(tick);
</script>
</body>
</html>
"""

__all__ = ["ANIMATION_SUFFIXES", "Scene", "animate", "html", "movie_data"]

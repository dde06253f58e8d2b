"""The mechanism moving: an animated GIF (or MP4, if ffmpeg exists) and a self-contained HTML
player (:mod:`mixdyn.viz.player`).

Each body is drawn as the outline of its points (their convex hull, or a bar when they are in a
line, or a small block when it has none), joints as pins, the ground's points as small
triangles, and a sliding joint on the ground as its guide line.
"""

from __future__ import annotations

import pathlib
import shutil

import numpy as np

from ..model import Model
from . import _draw
from .arrows import arrow_scale, force_arrows
from .player import applied, html, result_at
from .scene import Scene, _frames, _motion

ANIMATION_SUFFIXES = (".gif", ".mp4", ".html")


def animate(
    result=None,
    path="animation.gif",
    *,
    model: Model | None = None,
    t=None,
    q=None,
    fps: int = 20,
    frames: int | None = None,
    trace=(),
    title: str | None = None,
    size: tuple[float, float] | None = None,
    dpi: int = 100,
    forces=False,
    columns=None,
    plot_x: str = "t",
) -> pathlib.Path:
    """Write an animation of a motion: ``.gif`` (Pillow), ``.mp4`` (needs ffmpeg) or
    ``.html`` (see :func:`html`).

    Args:
        result: a :class:`mixdyn.Result`; or give ``model``, ``t`` (N,) and ``q`` (N, nq).
        path: the output file.
        fps: frames per second.
        frames: the largest number of frames (evenly spaced output times; default 80 for a
            GIF or MP4, every output time for HTML).
        trace: point references (``"coupler.C"``) whose paths are drawn.
        title: a title (default: the model's name).
        size, dpi: figure size [inch] (default: from the scene's proportions) and resolution.
        forces: ``True`` to draw every joint reaction and point force as an arrow (one scale
            for all), or their names (:func:`mixdyn.viz.arrows.force_arrows`).
        columns: the columns the HTML player offers first in its plot (:func:`html`).
        plot_x: the column on the x axis of the HTML player's plot (:func:`html`).

    Returns:
        The path written.
    """
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix == ".html":
        return html(
            result,
            path,
            model=model,
            t=t,
            q=q,
            fps=fps,
            frames=frames,
            trace=trace,
            title=title,
            forces=forces,
            columns=columns,
            plot_x=plot_x,
        )
    if suffix not in (".gif", ".mp4"):
        raise ValueError(
            f"cannot write an animation to {path.name!r}; use {', '.join(ANIMATION_SUFFIXES)}"
        )
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ValueError("writing MP4 needs ffmpeg, which is not installed; write a .gif or .html")
    return _draw.movie(
        movie_data(
            result,
            model=model,
            t=t,
            q=q,
            frames=frames or 80,
            trace=trace,
            title=title,
            forces=forces,
        ),
        path,
        fps=fps,
        size=size,
        dpi=dpi,
    )


def movie_data(
    result=None, *, model=None, t=None, q=None, frames=80, trace=(), title=None, forces=False
):
    """What :func:`animate` draws, as plain data (NumPy arrays, strings): the scene at the
    frames' times, their times, the title and units, the force arrows (scaled to lengths) and
    their scale's note (see :func:`mixdyn.viz._draw.movie`)."""
    model, ts, qs = _motion(result, model, t, q)
    idx = _frames(len(ts), frames)
    scene = Scene(model, qs[idx], trace, *result_at(result, idx))
    arrows, note = [], ""
    if forces:
        if result is None:
            raise ValueError("force arrows need a result (its reaction and force columns)")
        found = [a for a in force_arrows(result, forces) if a["name"] not in applied(model)]
        scale = arrow_scale(found, scene.bounds)
        arrows = [
            {"name": a["name"], "color": a["color"], "at": a["at"][idx], "v": a["F"][idx] * scale}
            for a in found
        ]
        if found and scale:
            big = max(float(np.max(np.hypot(*a["F"].T))) for a in found)
            note = f"arrows: {big:.4g} {found[0]['unit']} = {big * scale:.4g} {model.units.length}"
    return {
        "arrows": arrows,
        "arrow_note": note,
        "outlines": scene.outlines,
        "names": scene.names,
        "pins": scene.pins,
        "ground": scene.ground,
        "guides": scene.guides,
        "traces": scene.traces,
        "symbols": scene.symbols,
        "bounds": scene.bounds,
        "times": ts[idx],
        "title": title if title is not None else model.name,
        "length_unit": model.units.length,
        "time_unit": model.units.time,
    }


__all__ = ["ANIMATION_SUFFIXES", "Scene", "animate", "html", "movie_data"]

"""The HTML player: one self-contained page (data and script inline, no network) that plays a
motion on a canvas.

Controls: play/pause, step back and forward, first and last frame, playback speed as a
multiple of real time (1× plays one second of the model's time in one second), loop, traces
and force arrows on or off, a time slider over every frame of the result. The view has axes
with the model's length unit, zooms with the wheel, pans by dragging, fits on a double click,
and shows a body's coordinates on hover. The canvas is drawn at the screen's pixel density
(sharp on high-DPI screens). Keys: space, arrows, Home, End.

Why a small canvas player rather than plotly's animation frames (``benchmarks/player.py``, the
paper's example, 201 frames, every result column carried for the plot): this page is 665 kB
against plotly's 5.0 MB (plotly.js inline), and headless Chromium loads and runs it in about a
third of plotly's time (``benchmarks/RESULTS.md``); plotly's frames also cannot play at a
multiple of real time or step by key. Under the view, a plot of a result column
against time, or against another column (a phase plot: the slider's position against the crank
angle), has a cursor at the frame shown; a click on it moves the animation to the frame nearest
the click (nearest in time against time, nearest on the screen against another column). The
page carries every column of the result at every frame, so any column can be chosen on either
axis; the chosen columns come first. A URL fragment ``#t=0.5`` (or ``#frame=10``) opens the
page paused at that time, ``#plotcol=crank.phi`` and ``#plotx=crank.phi`` choose the columns
plotted, ``#plotclick=0.75`` clicks the plot at that fraction of its width (``0.75,0.2``: of
its width and of its height from the top); the page states the frame shown, its view transform
and the plot's cursor in ``data-`` attributes of ``<body>`` for automated checks (the browser
test).
"""

from __future__ import annotations

import json
import pathlib

import numpy as np

from ..model import Model, PointForce
from ._draw import COLORS
from .arrows import arrow_scale, force_arrows
from .scene import Scene, _frames, _motion

#: Seconds per time unit of the common spellings (pint is asked for any other: it loads in
#: about 0.4 s, a fifth of a warm run).
_SECONDS = {"s": 1.0, "second": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "min": 60.0,
            "minute": 60.0, "h": 3600.0, "hour": 3600.0}  # fmt: skip


def seconds_per_time_unit(model: Model) -> float:
    """Seconds in one of the model's time units (for real-time playback)."""
    if model.units.time in _SECONDS:
        return _SECONDS[model.units.time]
    from ..units import factor

    return 1.0 / factor("s", "time", model.units)


def nine_digits(a: np.ndarray) -> np.ndarray:
    """``a`` (any shape, finite) rounded to 9 significant digits, as ``float(f"{v:.9g}")``
    rounds each number: ``round(v * 10**p) / 10**p`` is the double nearest to the rounded
    decimal where ``10**p`` is exact (``|p| <= 22``); other numbers are rounded one by one."""
    a = np.asarray(a, dtype=float)
    magnitude = np.abs(a)
    p = np.zeros(a.shape, dtype=int)
    nonzero = magnitude > 0
    p[nonzero] = 8 - np.floor(np.log10(magnitude[nonzero])).astype(int)
    exact = np.abs(p) <= 22
    up = 10.0 ** np.clip(p, 0, 22)
    down = 10.0 ** np.clip(-p, 0, 22)
    out = np.where(p >= 0, np.round(a * up) / up, np.round(a / down) * down)
    for i in zip(*np.nonzero(~exact), strict=True):
        out[i] = float(f"{a[i]:.9g}")
    return out


def plot_columns_data(result, names, idx) -> list[dict]:
    """Columns of a result for the player's plot, at the frames ``idx``: ``name``, ``unit``
    (the result's output units, engineering spelling) and ``v`` (rounded to 9 significant
    digits, :func:`nine_digits`; a non-finite value is ``None``).

    Args:
        result: a :class:`mixdyn.Result`.
        names: column names (a point's ``body.P.x`` too, :func:`mixdyn.viz.result_columns`).
        idx: (F,) indices of the frames among the result's output times.

    Raises:
        ValueError: a name that is not a column of the result.
    """
    from ..units import engineering, in_units
    from .plots import result_columns

    try:
        cols, units = result_columns(result, list(names))
    except KeyError as e:
        raise ValueError(f"cannot plot {e.args[0]}") from None
    cols, units = in_units(result, cols, units, getattr(result, "output_units", None))
    return [
        {
            "name": n,
            "unit": engineering(units.get(n, "")),
            "v": _finite_or_none(np.asarray(cols[n], dtype=float)[idx]),
        }
        for n in names
    ]


def plotted_columns(result, chosen, idx) -> list[dict]:
    """Every column the player can plot (:func:`plot_columns_data`, at the frames ``idx``):
    the ``chosen`` ones first, then the result's other columns in the result's order (time
    is the page's own ``t``)."""
    names = list(dict.fromkeys([*chosen, *(c for c in result.columns() if c != "t")]))
    return plot_columns_data(result, names, idx)


def journal_orbits(result) -> list[dict]:
    """The orbits the page draws in their bearing: per journal bearing of the result's model
    (a revolute joint with ``clearance``), ``x`` and ``y``, the names of its eccentricity
    columns (``B.ex``, ``B.ey``), and ``r``, its radial clearance in the unit those columns
    are plotted in (the result's output units). Plotted one against the other, the page
    draws the clearance circle and scales both axes alike."""
    from ..model import JournalBearing
    from ..units import in_units

    out = []
    for f in result.model.forces:
        if isinstance(f, JournalBearing):
            x = f"{f.name}.ex"
            c, _ = in_units(
                result,
                {x: np.asarray([float(f.clearance)])},
                {x: result.model.units.length},
                getattr(result, "output_units", None),
            )
            out.append({"x": x, "y": f"{f.name}.ey", "r": float(nine_digits(c[x])[0])})
    return out


def _finite_or_none(a: np.ndarray) -> list:
    """``a`` (N,) rounded to 9 significant digits, a non-finite value as ``None``."""
    finite = np.isfinite(a)
    out = nine_digits(np.where(finite, a, 0.0)).tolist()
    return out if finite.all() else [v if f else None for v, f in zip(out, finite, strict=True)]


def player_data(
    model: Model,
    ts,
    qs,
    scene,
    *,
    title=None,
    fps=20,
    arrows=(),
    plots=(),
    shown=None,
    plot_x="t",
    orbits=(),
) -> dict:
    """The page's data: times, bodies' outlines and coordinates, pins, ground, guides, traces,
    force symbols, arrows (already scaled to lengths), units, the columns the page can plot
    (``plots``, :func:`plot_columns_data`), the names of those offered first (``shown``,
    default all of them; the first is plotted on opening) and the column on the plot's x axis
    (``plot_x``: ``"t"`` or a name among ``plots``), the journals' orbits (``orbits``,
    :func:`journal_orbits`). Numbers rounded to 9 significant digits;
    a symbol's pen lift (a NaN row) is ``null``. A plotted column equal to a body's
    coordinate as the page carries it (``crank.phi`` in the model's units) is carried once:
    its ``v`` is replaced by ``q: [body, coordinate]``, the page reading
    ``bodies[body].q[frame][coordinate]``."""

    def r(a):
        a = np.asarray(a, dtype=float)
        finite = np.isfinite(a)
        if finite.all():
            return nine_digits(a).tolist()
        out = nine_digits(np.where(finite, a, 0.0)).astype(object)
        out[~finite] = None  # a pen lift
        return out.tolist()

    body = {name: k for k, name in enumerate(scene.names)}

    def carried(c: dict) -> dict:
        owner, _, coordinate = c["name"].rpartition(".")
        if owner in body and coordinate in ("x", "y", "phi"):
            k, j = body[owner], ("x", "y", "phi").index(coordinate)
            if r(qs[:, 3 * k + j]) == c["v"]:
                return {"name": c["name"], "unit": c["unit"], "q": [k, j]}
        return c

    scale = arrow_scale(arrows, scene.bounds) if arrows else 0.0
    biggest = max((float(np.max(np.hypot(*a["F"].T))) for a in arrows), default=0.0)
    return {
        "title": title if title is not None else model.name,
        "t": r(ts),
        "units": {
            "length": model.units.length,
            "time": model.units.time,
            "seconds": seconds_per_time_unit(model),
        },
        "bounds": r(scene.bounds),
        "fps": int(fps),
        "bodies": [
            {
                "name": n,
                "color": COLORS[k % len(COLORS)],
                "outline": r(o),
                "q": r(qs[:, 3 * k : 3 * k + 3]),
            }
            for k, (n, o) in enumerate(zip(scene.names, scene.outlines, strict=True))
        ],
        "pins": r(scene.pins),
        "ground": r(scene.ground),
        "guides": r(scene.guides),
        "traces": [r(tr) for tr in scene.traces],
        "symbols": [
            {
                "name": m["name"],
                "kind": m["kind"],
                "color": m["color"],
                "label": m["label"],
                "path": r(m["path"]),
            }
            for m in scene.symbols
        ],
        "arrows": [
            {
                "name": a["name"],
                "color": a["color"],
                "at": r(a["at"]),
                "v": r(a["F"] * scale),
                "F": r(np.hypot(*a["F"].T)),
                "unit": a["unit"],
            }
            for a in arrows
        ],
        "plots": [carried(c) for c in plots],
        "shown": [c["name"] for c in plots] if shown is None else list(shown),
        "plotX": plot_x,
        "orbits": list(orbits),
        "arrowNote": (
            f"arrows: {biggest:.4g} {arrows[0]['unit']} = {biggest * scale:.4g} "
            f"{model.units.length}"
            if arrows and scale
            else ""
        ),
    }


def applied(model: Model) -> set[str]:
    """The point forces of ``model``: drawn as symbols of the scene
    (:func:`mixdyn.viz.symbols.symbols`), not among the requested force arrows."""
    return {f.name for f in model.forces if isinstance(f, PointForce)}


def result_at(result, idx) -> tuple[dict | None, dict | None]:
    """A result's columns at the frames ``idx`` and their units (engineering spelling), for
    the scene's torques and forces; ``(None, None)`` without a result."""
    if result is None:
        return None, None
    from ..units import engineering

    cols = {k: np.asarray(v)[idx] for k, v in result.columns().items()}
    return cols, {k: engineering(u) for k, u in result.units().items()}


def html(
    result=None,
    path="animation.html",
    *,
    model: Model | None = None,
    t=None,
    q=None,
    fps: int = 20,
    frames: int | None = None,
    trace=(),
    title: str | None = None,
    forces=False,
    columns=None,
    plot_x: str = "t",
) -> pathlib.Path:
    """Write the player page of a motion.

    Args:
        result: a :class:`mixdyn.Result`; or give ``model``, ``t`` (N,) and ``q`` (N, nq).
        path: the ``.html`` file to write.
        fps: unused by the page's real-time playback; kept for :func:`mixdyn.viz.animate`.
        frames: the largest number of frames (default: every output time of the result).
        trace: point references (``"coupler.C"``) whose paths are drawn.
        title: a title (default: the model's name).
        forces: ``True`` to draw every joint reaction and point force as an arrow, or their
            names (see :func:`mixdyn.viz.arrows.force_arrows`); needs a result with forces.
        columns: the result's columns offered first by the plot under the animation (one
            shown at a time, any other column of the result chosen in the page; a cursor
            follows the frame, a click on the plot moves the animation there); default the
            columns a reader looks at first (:func:`mixdyn.viz.plots.headline_columns`);
            ``()`` for no plot. Needs a result.
        plot_x: the column on the plot's x axis on opening: ``"t"`` (default) or a column
            of the result (``"crank.phi"``: a phase plot), another chosen in the page.

    Returns:
        The path written.
    """
    model, ts, qs = _motion(result, model, t, q)
    idx = np.arange(len(ts)) if frames is None else _frames(len(ts), frames)
    scene = Scene(model, qs[idx], trace, *result_at(result, idx))
    arrows = []
    if forces:
        if result is None:
            raise ValueError("force arrows need a result (its reaction and force columns)")
        arrows = [
            {**a, "at": a["at"][idx], "F": a["F"][idx]}
            for a in force_arrows(result, forces)
            if a["name"] not in applied(model)
        ]
    plots, orbits = [], []
    if result is not None:
        if columns is None:
            from .plots import headline_columns

            columns = headline_columns(result)[:8]
        if columns:
            extra = [] if plot_x == "t" else [plot_x]
            plots = plotted_columns(result, [*columns, *extra], idx)
            orbits = journal_orbits(result)
    elif columns or plot_x != "t":
        raise ValueError("plotted columns need a result")
    data = player_data(
        model,
        ts[idx],
        qs[idx],
        scene,
        title=title,
        fps=fps,
        arrows=arrows,
        plots=plots,
        shown=list(columns or ()),
        plot_x=plot_x,
        orbits=orbits,
    )
    text = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    page = _page().replace("__TITLE__", _escape(data["title"])).replace("__DATA__", text)
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".html.tmp")
    tmp.write_text(page, encoding="utf-8")
    tmp.replace(path)
    return path


def _escape(text: str) -> str:
    return (
        str(text)
        .replace("&", "&amp;")
        .replace("<", "&lt;")
        .replace(">", "&gt;")
        .replace('"', "&quot;")
    )


def _page() -> str:
    """The page's template (``_player.html`` beside this module: the script and its style)."""
    return (pathlib.Path(__file__).parent / "_player.html").read_text(encoding="utf-8")


__all__ = [
    "html",
    "journal_orbits",
    "player_data",
    "plot_columns_data",
    "plotted_columns",
    "seconds_per_time_unit",
]

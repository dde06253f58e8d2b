"""A drawing of a model at one configuration: bodies, joints, ground points, guides and their
names (``mixdyn show``, ``Model._repr_html_``), without running an analysis."""

from __future__ import annotations

import pathlib

import numpy as np

from .._hints import count
from ._draw import COLORS, SYMBOL_WIDTH, body_style, legend
from .labels import place
from .plots import headline_columns
from .scene import Scene

#: File types a drawing may be written to.
SHOW_SUFFIXES = (".png", ".svg", ".pdf", ".html")


def _joint_points(model, q: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """``(name, (2,) global position)`` of each joint's point on its body j (or i)."""
    out = []
    for j in model.joints:
        b, s = (j.bj, j.sj) if j.bj >= 0 else (j.bi, j.si)
        s = np.asarray(s, dtype=float)
        if b < 0:
            out.append((j.name, s))
        else:
            out.append((j.name, Scene._place(q[None], b, s[None])[0, 0]))
    return out


def draw(model, q, path, *, title: str | None = None, dpi: int = 110) -> pathlib.Path:
    """Draw ``model`` at the coordinates ``q`` (nq,) to ``path`` (``.png``, ``.svg``, ``.pdf``
    or ``.html``: the SVG in a page), every body, joint and ground point named.

    Returns:
        The path written.
    """
    import matplotlib

    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix not in SHOW_SUFFIXES:
        raise ValueError(f"cannot draw to {path.name!r}; use {', '.join(SHOW_SUFFIXES)}")
    fig, _ = figure(model, q, title=title, dpi=dpi)
    path.parent.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context({"svg.fonttype": "none"}):  # names as text in an SVG
        if suffix == ".html":
            import io

            buf = io.StringIO()
            fig.savefig(buf, format="svg")
            path.write_text(
                "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>"
                f"{_escape(model.name)}</title></head><body>\n{buf.getvalue()}\n</body></html>\n",
                encoding="utf-8",
            )
        else:
            fig.savefig(path, dpi=dpi)
    return path


def figure(model, q, *, title: str | None = None, dpi: int = 110):
    """The figure of :func:`draw` and where its names are: ``(figure, boxes)``, the names'
    boxes (n, 4) ``(x0, y0, x1, y1)`` in the figure's pixels at ``dpi``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    q = np.asarray(q, dtype=float)
    scene = Scene(model, q[None])
    x0, x1, y0, y1 = scene.bounds
    aspect = (y1 - y0) / max(x1 - x0, 1e-12)
    fig = Figure(  # at the output's resolution: the names are placed in its pixels
        figsize=(7.0, float(np.clip(7.0 * aspect + 0.9, 3.0, 8.0))), dpi=dpi, layout="constrained"
    )
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.25)
    u = model.units.length
    ax.set_xlabel(f"x [{u}]")
    ax.set_ylabel(f"y [{u}]")
    for g in scene.guides:
        ax.plot(g[:, 0], g[:, 1], color="0.55", lw=1.0, ls="-.", zorder=1)
    labels: list[tuple[str, np.ndarray, dict]] = []  # (text, anchor, style)
    for name, p in model.ground.points.items():
        p = np.asarray(p, dtype=float)
        ax.plot([p[0]], [p[1]], "^", color="0.3", ms=9, zorder=2)
        labels.append((f"ground.{name}", p, {"fontsize": 7, "color": "0.3"}))
    for k, outline in enumerate(scene.outlines):
        color = COLORS[k % len(COLORS)]
        closed = outline.shape[1] > 2
        ax.add_patch(
            Polygon(
                outline[0],
                closed=closed,
                zorder=3,
                label=scene.names[k],
                **body_style(color, closed),
            )
        )
        x, y = q[3 * k], q[3 * k + 1]
        ax.plot([x], [y], "+", color="k", ms=6, zorder=6)
        labels.append((scene.names[k], np.array([x, y]),
                       {"fontsize": 9, "weight": "bold", "color": color}))  # fmt: skip
    for m in scene.symbols:
        ax.plot(m["path"][0, :, 0], m["path"][0, :, 1], "-", color=m["color"],
                lw=SYMBOL_WIDTH[m["kind"]], zorder=4)  # fmt: skip
        labels.append((m["label"], m["anchor"][0], {"fontsize": 7, "color": m["color"]}))
    for name, p in _joint_points(model, q):
        ax.plot([p[0]], [p[1]], "o", mfc="white", mec="k", ms=6, zorder=5)
        labels.append((name, p, {"fontsize": 8}))
    ax.set_title(
        title
        or f"{model.name}: {count(len(model.bodies), 'body', 'bodies')}, "
        f"{count(len(model.joints), 'joint')}"
    )
    legend(ax)
    return fig, _write_labels(fig, ax, merge_labels(labels))


def merge_labels(labels):
    """One label per place: the names of things at the same point joined (``O2`` and
    ``ground.O2`` give ``O2``: a ground point's name is left out where a joint of the same
    name sits on it).

    Args:
        labels: ``(text, anchor (2,), style)`` each.

    Returns:
        The labels, those at one place (to 1e-9 of the largest coordinate) merged.
    """
    scale = max((float(np.max(np.abs(a))) for _, a, _ in labels), default=1.0) or 1.0
    spots: dict = {}
    for text, anchor, style in labels:
        key = tuple(np.round(np.asarray(anchor, dtype=float) / (1e-9 * scale)).astype(int))
        spots.setdefault(key, []).append((text, np.asarray(anchor, dtype=float), style))
    out = []
    for group in spots.values():
        texts = [t for t, _, _ in group]
        short = {t for t in texts if not t.startswith("ground.")}
        kept = [t for t in texts if not (t.startswith("ground.") and t[7:] in short)]
        kept = list(dict.fromkeys(kept))
        style = next((st for t, _, st in group if t in kept), group[0][2])
        out.append((", ".join(kept), group[0][1], style))
    return out


def _write_labels(fig, ax, labels) -> np.ndarray:
    """Write ``labels`` (``(text, anchor, style)``) beside their anchors, placed so that
    none covers another, a marker or the legend, inside the axes (:func:`.labels.place`).
    The figure's layout is fixed first (the places are in display pixels).

    Returns:
        (n, 4) the boxes ``(x0, y0, x1, y1)`` [display px].
    """
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    renderer = fig.canvas.get_renderer()
    anchors = ax.transData.transform(np.array([a for _, a, _ in labels]).reshape(-1, 2))
    texts = [ax.text(0, 0, t, zorder=7, ha="left", va="bottom", **st) for t, _, st in labels]
    sizes = []
    for t in texts:
        bb = t.get_window_extent(renderer)
        sizes.append((1.1 * bb.width + 2, bb.height + 1))  # a margin for the font's hinting
    marks = [(x - 5, y - 5, x + 5, y + 5) for x, y in anchors]
    frame = ax.bbox.extents
    boxes = place(anchors, sizes, frame, gap=4.0, obstacles=marks)
    to_data = ax.transData.inverted()
    for t, box in zip(texts, boxes, strict=True):
        t.set_position(to_data.transform(box[:2]))
    return boxes


def svg(model, q, *, title: str | None = None) -> str:
    """The drawing of :func:`draw` as SVG text (for notebooks)."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        return draw(model, q, pathlib.Path(d) / "m.svg", title=title).read_text(encoding="utf-8")


def model_html(model) -> str:
    """A notebook's view of a model (``Model._repr_html_``, attached by the package): a
    drawing at the rough start (``q0``, not assembled: drawing runs no analysis) and tables of
    the bodies and elements with their numbers."""
    from html import escape

    bodies, elements = model._rows()

    def table(head, rows):
        th = "".join(f"<th>{escape(h)}</th>" for h in head)
        trs = "".join(
            "<tr>" + "".join(f"<td>{escape(str(c))}</td>" for c in r) + "</tr>" for r in rows
        )
        return f"<table><tr>{th}</tr>{trs}</table>"

    try:
        drawing = svg(model, np.asarray(model.q0), title=f"{model.name} (rough start q0)")
        drawing = drawing[drawing.find("<svg") :]
    except Exception as e:  # a drawing is a courtesy: the tables still show
        drawing = f"<p>(no drawing: {escape(str(e))})</p>"
    return (
        f"<div><p><b>{escape(model.summary())}</b></p>{drawing}"
        + table(["body", "mass", "inertia", "q0", "points"], bodies)
        + table(["kind", "name", "type", "between", "numbers"], elements)
        + "</div>"
    )


def result_html(result) -> str:
    """A notebook's view of a result (``Result._repr_html_``, attached by the package): the
    summary and solver counters, a plot of :func:`headline_columns` against time (a panel
    per unit) and the columns' ranges with their units."""
    import tempfile
    from html import escape

    from ..units import engineering
    from .plots import plot_columns, result_columns

    units = {c: engineering(u) for c, u in result.units().items()}
    rows = "".join(
        f"<tr><td>{escape(k)}</td><td>{escape(units.get(k, ''))}</td>"
        f"<td>{float(np.min(v)):.6g}</td><td>{float(np.max(v)):.6g}</td></tr>"
        for k, v in result.columns().items()
    )
    stats = ", ".join(
        f"{escape(str(k))} {escape(str(v))}"
        for k, v in result.stats.items()
        if isinstance(v, int | float | str)
    )
    try:
        names = headline_columns(result)
        cols, col_units = result_columns(result, names)
        with tempfile.TemporaryDirectory() as d:
            path = plot_columns(
                cols,
                names,
                pathlib.Path(d) / "r.svg",
                units=col_units,
                title=f"{result.model.name}: {result.kind}",
                size=(6.4, 3.2),
            )
            plot = path.read_text(encoding="utf-8")
        plot = plot[plot.find("<svg") :]
    except Exception as e:  # a plot is a courtesy: the table still shows
        plot = f"<p>(no plot: {escape(str(e))})</p>"
    return (
        f"<div><p><b>{escape(repr(result))}</b></p><p>{stats}</p>{plot}"
        "<table><tr><th>column</th><th>unit</th><th>min</th><th>max</th></tr>"
        f"{rows}</table></div>"
    )


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


__all__ = [
    "SHOW_SUFFIXES",
    "draw",
    "figure",
    "headline_columns",
    "model_html",
    "result_html",
    "svg",
]

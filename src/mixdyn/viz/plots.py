"""Plots of result columns against time (PNG, SVG or PDF), without pyplot's global state."""

from __future__ import annotations

import pathlib

import numpy as np

#: File types a plot may be written to.
PLOT_SUFFIXES = (".png", ".svg", ".pdf")

_POINT_SUFFIXES = {
    "x": (0, 0),
    "y": (0, 1),
    "vx": (1, 0),
    "vy": (1, 1),
    "ax": (2, 0),
    "ay": (2, 1),
}


def result_columns(result, names) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Columns ``names`` of a :class:`mixdyn.Result` with their units, ``t`` included.

    Besides the result's own columns, a point's global coordinates may be asked for as
    ``"body.point.x"`` (also ``.y``, ``.vx``, ``.vy``, ``.ax``, ``.ay``).

    Raises:
        KeyError: an unknown column, with close matches (:meth:`mixdyn.Result.__getitem__`).
    """
    cols = result.columns()
    units = result.units()
    out = {"t": np.asarray(result.t)}
    out_units = {"t": units["t"]}
    for name in names:
        if name in cols:
            out[name] = np.asarray(cols[name])
            out_units[name] = units.get(name, "")
            continue
        parts = name.split(".")
        if len(parts) == 3 and parts[2] in _POINT_SUFFIXES:
            which, axis = _POINT_SUFFIXES[parts[2]]
            try:
                pva = result.point(f"{parts[0]}.{parts[1]}")
            except Exception:
                pva = None
            if pva is not None:
                out[name] = pva[which][:, axis]
                kind = ("length", "velocity", "acceleration")[which]
                out_units[name] = result.model.units.label(kind)
                continue
        result[name]  # raises KeyError naming the column, with close matches
    return out, out_units


def plot_columns(
    table,
    columns,
    path,
    *,
    units: dict[str, str] | None = None,
    title: str | None = None,
    ylabel: str | None = None,
    reference: tuple | None = None,
    size: tuple[float, float] = (7.0, 4.2),
    dpi: int = 120,
) -> pathlib.Path:
    """Plot ``columns`` of ``table`` against its ``t`` and write the figure to ``path``.

    Args:
        table: a mapping (or pandas DataFrame) with a ``t`` column and the columns to plot.
        columns: names of the columns to plot.
        path: the output file; ``.png``, ``.svg`` or ``.pdf``.
        units: unit of each column, for the axis labels.
        title: the figure's title.
        ylabel: the y axis label (default: the unit of the columns).
        reference: optional ``(t, y, label)`` drawn dashed beside the columns.
        size: figure size [inch].
        dpi: resolution of a PNG.

    Returns:
        The path written.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = pathlib.Path(path)
    if path.suffix.lower() not in PLOT_SUFFIXES:
        raise ValueError(f"cannot write a plot to {path.name!r}; use {', '.join(PLOT_SUFFIXES)}")
    units = dict(units or getattr(table, "attrs", {}).get("units", {}) or {})
    t = np.asarray(table["t"], dtype=float)
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    col_units = []
    for name in columns:
        y = np.asarray(table[name], dtype=float)
        u = units.get(name, "")
        col_units.append(u)
        ax.plot(t, y, lw=1.8, label=f"{name} [{u}]" if u else name)
    if reference is not None:
        rt, ry, rlabel = reference
        ax.plot(np.asarray(rt), np.asarray(ry), "--", lw=1.4, color="k", label=rlabel)
    tu = units.get("t", "")
    ax.set_xlabel(f"t [{tu}]" if tu else "t")
    if ylabel is None and len(set(col_units)) == 1:
        name = columns[0] if len(columns) == 1 else ""
        ylabel = f"{name} [{col_units[0]}]" if col_units[0] else name
    if ylabel:
        ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(True, alpha=0.35)
    if len(columns) > 1 or reference is not None:
        ax.legend(loc="best", fontsize="small")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


__all__ = ["PLOT_SUFFIXES", "plot_columns", "result_columns"]

"""Plots of result columns against time or another column (PNG, SVG or PDF), a panel per
unit, without pyplot's global state."""

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
    """Columns ``names`` of a :class:`mixdyn.Result` with their units (engineering labels:
    ``N·m``, ``mm/s²``), ``t`` included.

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
    from ..units import engineering  # here: the figure worker loads this file without mixdyn

    return out, {k: engineering(u) for k, u in out_units.items()}


def plot_columns(
    table,
    columns,
    path=None,
    *,
    units: dict[str, str] | None = None,
    title: str | None = None,
    ylabel: str | None = None,
    reference: tuple | None = None,
    x: str = "t",
    size: tuple[float, float] | None = None,
    dpi: int = 120,
):
    """Plot ``columns`` of ``table`` against its column ``x``: one panel per unit (an angle, a
    speed and an acceleration are not drawn on one axis, where two of them would come out
    flat), the panels sharing the x axis; written to ``path`` where given.

    Args:
        table: a mapping (or pandas DataFrame, e.g. :meth:`mixdyn.Result.table` or
            :func:`mixdyn.read_table`) with the column ``x`` (a DataFrame indexed by ``x``
            also serves) and the columns to plot.
        columns: names of the columns to plot.
        path: the output file (``.png``, ``.svg`` or ``.pdf``), or None: the figure is
            returned, not written.
        units: unit of each column, for the axis labels, as written there (default:
            ``table.attrs["units"]``, engineering labels such as ``N·m``, ``mm/s²``).
        title: the figure's title.
        ylabel: the y axis label (default: the columns' name and unit).
        reference: optional ``(t, y, label)`` drawn dashed beside the columns (against ``t``:
            only with ``x = "t"``), in the panel of the first column.
        x: the column on the x axis (default ``t``), e.g. ``crank.phi`` for the torque against
            the crank angle.
        size: figure size [inch] (default: 7 wide, 3.2 per panel, at least 4.2).
        dpi: resolution of a PNG.

    Returns:
        The path written, or without ``path`` the matplotlib ``Figure``.

    Raises:
        KeyError: a column (or ``x``) the table does not have.
        ValueError: a path that is not ``.png``, ``.svg`` or ``.pdf``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if path is not None:
        path = pathlib.Path(path)
        if path.suffix.lower() not in PLOT_SUFFIXES:
            raise ValueError(
                f"cannot write a plot to {path.name!r}; use {', '.join(PLOT_SUFFIXES)}"
            )
    units = dict(units or getattr(table, "attrs", {}).get("units", {}) or {})
    xs = np.asarray(_column(table, x), dtype=float)
    groups: dict[str, list[str]] = {}
    for name in columns:
        groups.setdefault(units.get(name, ""), []).append(name)
    n = len(groups)
    fig = Figure(figsize=size or (7.0, max(4.2, 3.2 * n)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for ax, (unit, names) in zip(axes, groups.items(), strict=True):
        for name in names:
            y = np.asarray(_column(table, name), dtype=float)
            ax.plot(xs, y, lw=1.8, label=f"{name} [{unit}]" if unit else name)
        if reference is not None and ax is axes[0]:
            rt, ry, rlabel = reference
            ax.plot(np.asarray(rt), np.asarray(ry), "--", lw=1.4, color="k", label=rlabel)
        label = ylabel if (ylabel and n == 1) else None
        if label is None:
            head = names[0] if len(names) == 1 else ""
            label = f"{head} [{unit}]" if unit else head
        if label:
            ax.set_ylabel(label)
        ax.grid(True, alpha=0.35)
        if len(names) > 1 or (reference is not None and ax is axes[0]):
            ax.legend(loc="best", fontsize="small")
    xu = units.get(x, "")
    axes[-1].set_xlabel(f"{x} [{xu}]" if xu else x)
    if title and n > 1:
        fig.suptitle(title)
    elif title:
        axes[0].set_title(title)
    if path is None:
        return fig
    return save_figure(fig, path, dpi)


def save_figure(fig, path, dpi: int = 120) -> pathlib.Path:
    """Write a matplotlib Figure to ``path`` (its folder created) at ``dpi``; the path."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def _column(table, name: str) -> np.ndarray:
    """Column ``name`` of ``table``, or its index where the index is named so (a DataFrame
    indexed by ``t``); a KeyError naming the column and the ones there are."""
    try:
        return table[name]
    except KeyError:
        index = getattr(table, "index", None)
        if index is not None and index.name == name:
            return np.asarray(index)
        names = [str(n) for n in getattr(table, "columns", table)]
        listed = ", ".join(names[:8]) + (f" ... ({len(names)} in all)" if len(names) > 8 else "")
        raise KeyError(f"no column {name!r}; the table has {listed}") from None


def headline_columns(result) -> list[str]:
    """The columns a reader looks at first: the drivers' efforts, else the unknown forces
    (a mixed run), else every body's angle."""
    cols = result.columns()
    efforts = [d.name for d in result.model.drivers if d.name in cols]
    if efforts:
        return efforts
    unknown = [name for name in result.stats.get("unknown_forces", ()) if name in cols]
    return unknown or [f"{b.name}.phi" for b in result.model.bodies]


__all__ = [
    "PLOT_SUFFIXES",
    "headline_columns",
    "plot_columns",
    "result_columns",
    "save_figure",
]

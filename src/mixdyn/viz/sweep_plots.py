"""Figures of sweeps and fits: a per-member number against a swept quantity, a band of time
histories over the members, measurements against a fitted motion (PNG, SVG or PDF), without
pyplot's global state.

Loaded by the figure worker by its path (:mod:`mixdyn.runtime._worker`): NumPy and matplotlib only.
"""

from __future__ import annotations

import pathlib

import numpy as np

#: Most curves of an ``against`` plot (one per value of ``by``), evenly picked.
MAX_CURVES = 8


def _colors(n: int) -> list:
    from matplotlib import colormaps

    return [colormaps["viridis"](v) for v in np.linspace(0.0, 0.9, n)]


def _figure(path, size):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = pathlib.Path(path)
    if path.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise ValueError(f"cannot write a plot to {path.name!r}; use .png, .svg or .pdf")
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return path, fig


def _label(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit else name


def plot_against(
    x: np.ndarray,
    y: np.ndarray,
    path,
    *,
    names: tuple[str, str],
    by: np.ndarray | None = None,
    by_name: str = "",
    units: dict[str, str] | None = None,
    title: str | None = None,
    scatter: bool = False,
    size: tuple[float, float] = (7.0, 4.2),
    dpi: int = 120,
) -> pathlib.Path:
    """A number per member ``y`` (M,) against a swept quantity ``x`` (M,), written to ``path``.

    Args:
        x, y: (M,) the members' values (NaN: a failed member, not drawn).
        path: ``.png``, ``.svg`` or ``.pdf``.
        names: the names of ``x`` and ``y`` (axis labels).
        by: (M,) another swept quantity: one curve per distinct value (at most
            :data:`MAX_CURVES`, evenly picked), or the points' colour when ``scatter``.
        by_name: its name (legend title).
        units: unit of each name.
        title: the figure's title.
        scatter: points instead of curves (a random sampling, whose ``x`` do not repeat).
    """
    units = units or {}
    path, fig = _figure(path, size)
    ax = fig.add_subplot()
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(y)
    if scatter:
        c = None if by is None else np.asarray(by, dtype=float)[ok]
        pts = ax.scatter(x[ok], y[ok], c=c, s=14, cmap="viridis")
        if by is not None:
            fig.colorbar(pts, ax=ax, label=_label(by_name, units.get(by_name, "")))
    elif by is None:
        order = np.argsort(x[ok], kind="stable")
        ax.plot(x[ok][order], y[ok][order], "o-", ms=3, lw=1.6)
    else:
        by = np.asarray(by, dtype=float)
        levels = np.unique(by)
        if len(levels) > MAX_CURVES:
            pick = np.linspace(0, len(levels) - 1, MAX_CURVES).round().astype(int)
            levels = levels[np.unique(pick)]
        for level, color in zip(levels, _colors(len(levels)), strict=True):
            sel = ok & (by == level)
            order = np.argsort(x[sel], kind="stable")
            xs, ys = x[sel][order], y[sel][order]
            ax.plot(xs, ys, "-", lw=1.6, color=color, label=f"{level:.4g}")
        ax.legend(title=_label(by_name, units.get(by_name, "")), fontsize="small", loc="best")
    ax.set_xlabel(_label(names[0], units.get(names[0], "")))
    ax.set_ylabel(_label(names[1], units.get(names[1], "")))
    failed = int((~ok).sum())
    if title or failed:
        ax.set_title(
            (title or "")
            + (
                f" ({failed} failed {'member' if failed == 1 else 'members'} not drawn)"
                if failed
                else ""
            )
        )
    ax.grid(True, alpha=0.35)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def plot_band(
    t: np.ndarray,
    values: np.ndarray,
    path,
    *,
    name: str,
    units: dict[str, str] | None = None,
    title: str | None = None,
    size: tuple[float, float] = (7.0, 4.2),
    dpi: int = 120,
) -> pathlib.Path:
    """The members' time histories of one column as a band: the range over the members, the
    10-90 % band and the median, written to ``path``.

    Args:
        t: (N,) output times.
        values: (M, N) the column of each member that finished.
        path: ``.png``, ``.svg`` or ``.pdf``.
        name: the column's name.
        units: unit of ``t`` and of the column.
        title: the figure's title.
    """
    units = units or {}
    path, fig = _figure(path, size)
    ax = fig.add_subplot()
    v = np.asarray(values, dtype=float)
    lo, p10, med, p90, hi = np.percentile(v, [0, 10, 50, 90, 100], axis=0)
    ax.fill_between(t, lo, hi, color="tab:blue", alpha=0.18, lw=0, label="range")
    ax.fill_between(t, p10, p90, color="tab:blue", alpha=0.35, lw=0, label="10-90 %")
    ax.plot(t, med, color="tab:blue", lw=1.8, label="median")
    ax.set_xlabel(_label("t", units.get("t", "")))
    ax.set_ylabel(_label(name, units.get(name, "")))
    ax.set_title((title + " " if title else "") + f"({len(v)} members)")
    ax.grid(True, alpha=0.35)
    ax.legend(fontsize="small", loc="best")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def plot_fit(
    t: np.ndarray,
    measured: dict[str, np.ndarray],
    fitted: dict[str, np.ndarray],
    path,
    *,
    units: dict[str, str] | None = None,
    title: str | None = None,
    dpi: int = 120,
) -> pathlib.Path:
    """Each measured column (points) against the fitted run's (a line), a panel each, with
    the residuals below, written to ``path``.

    Args:
        t: (N,) the measurement times.
        measured, fitted: column -> (N,) values.
        path: ``.png``, ``.svg`` or ``.pdf``.
        units: unit of ``t`` and of each column.
        title: the figure's title.
    """
    units = units or {}
    names = list(measured)
    path, fig = _figure(path, (7.0, 2.6 * len(names) + 0.6))
    axes = fig.subplots(len(names), 2, squeeze=False, width_ratios=(3, 1))
    for row, name in zip(axes, names, strict=True):
        y, f = np.asarray(measured[name]), np.asarray(fitted[name])
        row[0].plot(t, y, ".", ms=3, color="0.35", label="measured")
        row[0].plot(t, f, "-", lw=1.8, color="tab:blue", label="fitted")
        row[0].set_ylabel(_label(name, units.get(name, "")))
        row[0].grid(True, alpha=0.35)
        row[0].legend(fontsize="small", loc="best")
        row[1].plot(t, y - f, ".", ms=3, color="tab:red")
        row[1].axhline(0.0, color="k", lw=0.8)
        row[1].set_title("residual", fontsize="small")
        row[1].grid(True, alpha=0.35)
    for ax in axes[-1]:
        ax.set_xlabel(_label("t", units.get("t", "")))
    if title:
        fig.suptitle(title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def plot_optimum(
    history: np.ndarray,
    t: np.ndarray,
    first: np.ndarray,
    best: np.ndarray,
    path,
    *,
    column: str,
    reduce: str,
    units: dict[str, str] | None = None,
    title: str | None = None,
    dpi: int = 120,
) -> pathlib.Path:
    """An optimization: the objective per iteration (left) and the objective's column at
    the start and at the optimum against time (right), written to ``path``."""
    units = units or {}
    path, fig = _figure(path, (9.0, 3.8))
    left, right = fig.subplots(1, 2, width_ratios=(1, 2))
    left.plot(np.arange(len(history)), history, "o-", ms=3, lw=1.4)
    left.set_xlabel("iteration")
    left.set_ylabel(_label(f"{reduce} of {column}", units.get(column, "")))
    left.grid(True, alpha=0.35)
    right.plot(t, first, "--", lw=1.4, color="0.4", label="start")
    right.plot(t, best, "-", lw=1.8, color="tab:blue", label="optimum")
    right.set_xlabel(_label("t", units.get("t", "")))
    right.set_ylabel(_label(column, units.get(column, "")))
    right.grid(True, alpha=0.35)
    right.legend(fontsize="small", loc="best")
    if title:
        fig.suptitle(title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


__all__ = ["MAX_CURVES", "plot_against", "plot_band", "plot_fit", "plot_optimum"]

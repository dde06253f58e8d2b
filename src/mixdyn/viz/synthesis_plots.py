"""The figure of a synthesis: the target points (a motion's poses with their angles) and the
candidates' coupler curves, or a function's asked angle pairs and the candidates' rocker angles
(PNG, SVG or PDF), without pyplot's global state.

Loaded by the figure worker by its path (:mod:`mixdyn.runtime._worker`): NumPy and matplotlib only.
"""

from __future__ import annotations

import pathlib

import numpy as np


def plot_synthesis(
    targets: np.ndarray,
    curves: list,
    errors: list,
    path,
    *,
    unit: str | tuple[str, str] = "m",
    axes: tuple[str, str] = ("x", "y"),
    error_unit: str | None = None,
    equal: bool = True,
    title: str | None = None,
    dpi: int = 120,
    angles=None,
) -> pathlib.Path:
    """The targets and the candidates' coupler curves, the best (the first) bold, written to
    ``path`` (``.png``, ``.svg`` or ``.pdf``).

    Args:
        targets: (N, 2) the target points [``unit``].
        curves: per candidate ``(run, rest)``: its coupler curve (K, 2) over the traversed
            motion (solid) and over the rest of the crank's turn (dotted; NaN rows where the
            loop does not close).
        errors: each candidate's path error [``unit``**2], in the legend.
        path: the figure's file.
        unit: the unit of the axes, or of each (a function's crank angle and its output).
        axes: the axes' names (a path: ``x``, ``y``; a function: the crank's angle and the
            output).
        error_unit: the errors' unit (default ``unit``²).
        equal: equal scales on both axes (a path).
        title: the figure's title.
        dpi: resolution of a PNG.
        angles: (N,) the asked angle at each target [rad] (a motion's poses), drawn as a
            short line from the target in that direction (None: points only).
    """
    from matplotlib import colormaps
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = pathlib.Path(path)
    if path.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise ValueError(f"cannot write a plot to {path.name!r}; use .png, .svg or .pdf")
    units = (unit, unit) if isinstance(unit, str) else tuple(unit)
    error_unit = error_unit or f"{units[0]}²"
    fig = Figure(figsize=(6.4, 5.6), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    colors = [colormaps["viridis"](v) for v in np.linspace(0.35, 0.9, max(len(curves), 1))]
    for k in reversed(range(len(curves))):
        best = k == 0
        run, rest = (np.asarray(c) for c in curves[k])
        color = "tab:blue" if best else colors[k]
        label = f"{'best' if best else f'#{k + 1}'}: error {errors[k]:.3g} {error_unit}"
        ax.plot(*run.T, "-", lw=2.2 if best else 1.0, alpha=1.0 if best else 0.7,
                color=color, label=label)  # fmt: skip
        ax.plot(*rest.T, ":", lw=1.0, alpha=0.8 if best else 0.4, color=color)
    ax.plot(*np.asarray(targets).T, "x", ms=9, mew=2, color="tab:red", label="asked")
    if angles is not None:
        pts = np.asarray(targets, dtype=float)
        drawn = np.concatenate([pts, *(np.asarray(c[0]) for c in curves)])
        span = np.nanmax(drawn, axis=0) - np.nanmin(drawn, axis=0)
        reach = 0.12 * max(float(np.max(span)), 1e-12)
        a = np.asarray(angles, dtype=float)
        tips = pts + reach * np.column_stack([np.cos(a), np.sin(a)])
        for p, q in zip(pts, tips, strict=True):
            ax.plot(*np.column_stack([p, q]), "-", lw=2.0, color="tab:red")
    if equal:
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{axes[0]} [{units[0]}]")
    ax.set_ylabel(f"{axes[1]} [{units[1]}]")
    ax.grid(True, alpha=0.35)
    ax.legend(fontsize="small", loc="best")
    if title:
        fig.suptitle(title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


__all__ = ["plot_synthesis"]

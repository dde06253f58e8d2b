"""The result of an analysis: time histories as named columns with units."""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._hints import count, did_you_mean
from ..model import Model
from ..model._element import Resolver
from ..model._geometry import point
from ..units import in_units

#: Per-body columns: (suffix, source array, index in [x, y, phi], kind of quantity).
_BODY_COLUMNS = (
    ("x", "q", 0, "length"),
    ("y", "q", 1, "length"),
    ("phi", "q", 2, "angle"),
    ("vx", "qd", 0, "velocity"),
    ("vy", "qd", 1, "velocity"),
    ("omega", "qd", 2, "angular_velocity"),
    ("ax", "qdd", 0, "acceleration"),
    ("ay", "qdd", 1, "acceleration"),
    ("alpha", "qdd", 2, "angular_acceleration"),
)


def require_finite(result: Result) -> None:
    """No non-finite number leaves mixdyn: the first NaN or infinity of any column (earliest
    time, then column order) is a :class:`~mixdyn.errors.NonFiniteError` naming the column,
    the time and the element the column belongs to."""
    from ..errors import NonFiniteError

    raw = (result.t, result.q, result.qd, result.qdd, *result.extra.values())
    if all(np.all(np.isfinite(np.asarray(a, dtype=float))) for a in raw):
        return  # every other column is a smooth function of these (positions from q...)
    cols = result.columns()
    bad_rows = [np.flatnonzero(~np.isfinite(np.asarray(v, dtype=float))) for v in cols.values()]
    firsts = [(rows[0], k) for k, rows in enumerate(bad_rows) if rows.size]
    if not firsts:
        return
    row, k = min(firsts)
    name = list(cols)[k]
    n_bad = sum(1 for rows in bad_rows if rows.size)
    t = float(result.t[row]) if np.isfinite(result.t[row]) else None
    raise NonFiniteError(
        f"the {result.kind} analysis produced a non-finite value in column {name!r} "
        f"({count(n_bad, 'column')} affected): a force or law that is not finite here (sqrt or log "
        "of a negative number, an overflow), a singular configuration or a diverging motion; "
        "check the element's law and values",
        t,
        (name.split(".")[0],),
    )


def point_columns(result: Result, points=()) -> tuple[dict, dict]:
    """``(columns, units)`` of ``result`` with, for each point reference of ``points``, its
    global position, velocity and acceleration (``coupler.P.x``, ``.y``, ``.vx``, ``.vy``,
    ``.ax``, ``.ay``) [model units]."""
    cols, units = result.columns(), result.units()
    for ref in points:
        for arr, pre, kind in zip(
            result.point(ref), ("", "v", "a"), ("length", "velocity", "acceleration"), strict=True
        ):
            for k, axis in enumerate("xy"):
                cols[f"{ref}.{pre}{axis}"] = arr[:, k]
                units[f"{ref}.{pre}{axis}"] = result.model.units.label(kind)
    return cols, units


#: The columns of :meth:`Result.impacts` and their kinds of quantity (None: no unit).
IMPACT_COLUMNS = {
    "t": "time",
    "contact": None,
    "impulse": "impulse",
    "normal_velocity_before": "velocity",
    "normal_velocity_after": "velocity",
    "friction_impulse": "impulse",
    "tangential_velocity_before": "velocity",
    "tangential_velocity_after": "velocity",
    "sticks": None,
}


@dataclasses.dataclass(frozen=True)
class Result:
    """Time histories of one analysis.

    Attributes:
        kind: ``"kinematic"``, ``"forward"``, ``"inverse"`` or ``"mixed"``.
        model: the model analysed.
        t: (N,) output times [time].
        q, qd, qdd: (N, nq) coordinates, velocities and accelerations (model units, rad).
        extra: further columns by name, each (N,): multipliers, reactions, efforts, energies.
        kinds: kind of quantity of each extra column (a key of ``mixdyn.units.DIMENSIONS``).
        stats: solver counters and settings (iterations, steps, largest violation...).
        output_units: kind of quantity -> unit its columns are shown in by :meth:`table`,
            :meth:`plot` and written results (a model file's ``output_units``, given by
            :func:`mixdyn.run_file`); empty: the model's units.
    """

    kind: str
    model: Model
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    extra: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    kinds: dict[str, str] = dataclasses.field(default_factory=dict)
    stats: dict[str, Any] = dataclasses.field(default_factory=dict)
    output_units: dict[str, str] = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        require_finite(self)

    # ----------------------------------------------------------------- columns
    def columns(self) -> dict[str, np.ndarray]:
        """Every column by name, ``t`` first, each (N,)."""
        cols = {"t": self.t}
        for b, body in enumerate(self.model.bodies):
            for suffix, src, k, _ in _BODY_COLUMNS:
                cols[f"{body.name}.{suffix}"] = getattr(self, src)[:, 3 * b + k]
        cols.update(self.extra)
        return cols

    def units(self) -> dict[str, str]:
        """The unit of every column, in the model's unit system named plainly (pint spelling:
        ``N``, ``N*m``, ``W``; in mm, kg, s ``mN``, ``mN*mm``, ``µW``: see
        :meth:`mixdyn.UnitSystem.label`)."""
        u = self.model.units
        out = {"t": u.label("time")}
        for body in self.model.bodies:
            for suffix, _, _, kind in _BODY_COLUMNS:
                out[f"{body.name}.{suffix}"] = u.label(kind)
        out.update({k: u.label(v) for k, v in self.kinds.items()})
        return out

    def kind_of(self, name: str) -> str | None:
        """The kind of quantity of a column (a key of ``mixdyn.units.DIMENSIONS``): ``time``,
        a body's ``length``/``angle``/``velocity``..., a point's (``body.P.vx``), or an extra
        column's (a force, a torque...); None for an unknown column."""
        if name == "t":
            return "time"
        if name in self.kinds:
            return self.kinds[name]
        parts = name.split(".")
        bodies = {b.name for b in self.model.bodies}
        if len(parts) == 2 and parts[0] in bodies:
            return next((k for s, _, _, k in _BODY_COLUMNS if s == parts[1]), None)
        if len(parts) == 3 and parts[0] in bodies:
            return {"x": "length", "y": "length", "vx": "velocity", "vy": "velocity",
                    "ax": "acceleration", "ay": "acceleration"}.get(parts[2])  # fmt: skip
        return None

    def __getitem__(self, name: str) -> np.ndarray:
        cols = self.columns()
        if name in cols:
            return cols[name]
        raise KeyError(f"no column {name!r}; {did_you_mean(name, cols)}")

    def table(self, points=(), output_units: dict | None = None):
        """A pandas DataFrame of every column, ``t`` first (a column, as in ``results.csv``,
        and the times also its unnamed index: ``df["motor"].plot()`` draws against time);
        ``points`` adds point trajectories.

        Args:
            points: point references (``"crank.B"``) whose global position, velocity and
                acceleration are added as columns ``crank.B.x``, ``.vx``, ``.ax`` (and y).
            output_units: kind of quantity -> unit, e.g. ``{"angle": "deg", "torque":
                "N*m", "time": "ms"}``, or a preset's name (``"SI"``, ``"mm-N-s"``): the
                columns of those kinds converted (default: the
                result's :attr:`output_units`, else the model's units). The kinds are the keys
                of ``mixdyn.units.DIMENSIONS``.

        The units of the columns (engineering labels: ``N·m``, ``mm/s²``) are in
        ``df.attrs["units"]``.
        """
        import pandas as pd

        from ..units import engineering

        shown = self.output_units if output_units is None else output_units
        cols, units = in_units(self, *point_columns(self, points), shown)
        df = pd.DataFrame(cols, index=pd.Index(np.asarray(cols["t"])))
        df.attrs["units"] = {c: engineering(units[c]) for c in cols if c in units}
        df.attrs["kind"] = self.kind
        return df

    def impacts(self, output_units: dict | None = None):
        """A pandas DataFrame of the run's rigid impacts, one row each in the order
        resolved (``stats["impacts"]``): its time ``t``, the contact, the normal impulse
        ``P`` on body j, the normal velocities (the gap's rate: negative approaching) before
        and after, the friction impulse along ``z x n``, the tangential velocities before and
        after and whether the point stuck. Empty for a run without rigid contacts.

        Args:
            output_units: as for :meth:`table` (time, impulse and velocity converted).

        The units (engineering labels) are in ``df.attrs["units"]``.
        """
        import pandas as pd

        from ..units import engineering

        shown = self.output_units if output_units is None else output_units
        found = self.stats.get("impacts") or {}
        kinds = {name: kind for name, kind in IMPACT_COLUMNS.items() if kind is not None}
        numbers = {name: np.asarray(found.get(name, []), dtype=float) for name in kinds}
        labels = {name: self.model.units.label(kind) for name, kind in kinds.items()}
        numbers, labels = in_units(self, numbers, labels, shown, kinds)
        cols = {name: numbers[name] if name in kinds else list(found.get(name, []))
                for name in IMPACT_COLUMNS}  # fmt: skip
        df = pd.DataFrame(cols)
        df.attrs["units"] = {name: engineering(u) for name, u in labels.items()}
        return df

    def plot(self, columns, *, x: str = "t", points=(), output_units: dict | None = None, **kw):
        """A matplotlib Figure of ``columns`` against ``x`` (default ``t``), a panel per unit,
        in the units of :meth:`table` (:func:`mixdyn.viz.plot_columns`, whose keywords
        ``title``, ``ylabel``, ``reference``, ``size`` and ``path`` it passes on: with
        ``path`` the figure is also written there).

        Args:
            columns: column names, e.g. ``["motor"]``, or one name.
            x: the column on the x axis, e.g. ``"crank.phi"``.
            points: point references whose columns (``coupler.P.x``...) may be plotted.
            output_units: as for :meth:`table`.
        """
        from ..viz.plots import plot_columns

        columns = [columns] if isinstance(columns, str) else list(columns)
        table = self.table(points, output_units)
        for name in [*columns, x]:
            if name not in table.columns:
                self[name]  # raises KeyError naming the column, with close matches
        path = kw.pop("path", None)
        fig = plot_columns(table, columns, x=x, **kw)
        if path is not None:
            from ..viz.plots import save_figure

            save_figure(fig, path, kw.get("dpi", 120))
        return fig

    def point(self, ref) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global position, velocity and acceleration of a point, each (N, 2) [model units]."""
        b, s = Resolver(self.model.ground, self.model.bodies).point(ref, "point")

        def pos(q):
            return point(q, b, s)

        def pva(q, qd, qdd):
            p, v = jax.jvp(pos, (q,), (qd,))
            _, a2 = jax.jvp(lambda qq: jax.jvp(pos, (qq,), (qd,))[1], (q,), (qd,))
            return p, v, a2 + jax.jacfwd(pos)(q) @ qdd

        p, v, a = jax.vmap(pva)(jnp.asarray(self.q), jnp.asarray(self.qd), jnp.asarray(self.qdd))
        return np.asarray(p), np.asarray(v), np.asarray(a)

    def at(self, t: float) -> dict[str, float]:
        """The row of the output time nearest to ``t``, as a dict."""
        i = int(np.argmin(np.abs(self.t - t)))
        return {k: float(v[i]) for k, v in self.columns().items()}

    def __repr__(self) -> str:
        return (
            f"Result({self.kind}, {self.model.name}, {len(self.t)} times "
            f"{self.t[0]:.4g}..{self.t[-1]:.4g}, {len(self.columns())} columns)"
        )


@dataclasses.dataclass(frozen=True)
class Partial:
    """What a failed dynamic run computed before it failed: the bodies' coordinates and
    velocities at the output times up to the failure (carried by its
    :class:`~mixdyn.errors.NumericalError` as ``partial``; the other columns of a
    :class:`Result`, which come after the integration, were never computed).

    Attributes:
        model: the mechanism.
        t: (K,) the output times up to the failure [time].
        q, qd: (K, nq) coordinates and velocities there [model units].
    """

    model: Model
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray

    @classmethod
    def before(cls, model: Model, ts, q, qd, t_fail: float | None, strict=False) -> Partial:
        """The rows of ``ts`` (N,), ``q``, ``qd`` (N, nq) at times up to ``t_fail`` (all
        where None; with ``strict`` before it: the failure was at an output time) whose
        states are finite."""
        ts, q, qd = np.asarray(ts, float), np.asarray(q, float), np.asarray(qd, float)
        if t_fail is None:
            keep = np.ones(len(ts), bool)
        else:
            keep = ts < t_fail if strict else ts <= t_fail
        keep &= np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(qd), axis=1)
        k = int(np.argmin(keep)) if not keep.all() else len(ts)  # the first row not kept
        return cls(model, ts[:k], q[:k], qd[:k])

    def columns(self) -> dict[str, np.ndarray]:
        """``t`` and each body's ``x, y, phi, vx, vy, omega``, each (K,)."""
        cols = {"t": self.t}
        for b, body in enumerate(self.model.bodies):
            for suffix, src, k, _ in _BODY_COLUMNS[:6]:
                cols[f"{body.name}.{suffix}"] = getattr(self, src)[:, 3 * b + k]
        return cols

    def kind_of(self, name: str) -> str | None:
        """The kind of quantity of a column (as :meth:`Result.kind_of`)."""
        if name == "t":
            return "time"
        suffix = name.rpartition(".")[2]
        return next((kind for s, _, _, kind in _BODY_COLUMNS if s == suffix), None)

    def units(self) -> dict[str, str]:
        """The unit of every column in the model's unit system."""
        u = self.model.units
        return {c: u.label(self.kind_of(c)) for c in self.columns()}

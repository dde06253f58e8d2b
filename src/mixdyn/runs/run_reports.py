"""The one-page reports (``report.html``, :class:`mixdyn.viz.report.Report`) of the runs that
repeat another run and of a failed run.

- A sweep's: its members (how many, how many failed), each varied number's range and each
  summary's minimum and maximum with their units, the failed members, its figures.
- A fit's (``identify``): the numbers found with their units, start, standard deviation and
  bounds, the residual of each measured column against the noise, the chi-square, its figure.
- An optimization's: the objective at the start and at the optimum, the numbers chosen with
  their units, bounds (its constraints: which are active) and gradient, its figure.
- A failed run's: the failure (the error's class, the time it failed at, its message, the
  elements involved) and what was computed before it.

The numbers are the run's own, as its files hold them (``members.csv``, ``fit.csv``,
``optimum.csv``, ``results.csv``); a page is built with numpy from results already computed,
without running a compiled program or drawing a figure.

Example::

    outputs.add_report(sweep_report(runner, plan, result, seconds, outputs))
"""

from __future__ import annotations

import datetime

import numpy as np

from ..viz.report import Report, Table, number, start_drawing

#: Every run's one-page report.
REPORT_HTML = "report.html"

#: The most failed members a sweep's page lists (members.csv has them all).
_MAX_FAILED_ROWS = 20


def _facts(runner, plan, outputs, status: str, seconds: float | None) -> list:
    from .._version import __version__

    facts = [  # the file's name: its model's, where it has one (not a synthesis file)
        ("model", f"{runner.spec.name} ({outputs.file})"),
        ("run", f"{plan.name} ({plan.spec.kind})"),
        ("status", status),
    ]
    if seconds is not None:
        facts.append(("wall time", f"{seconds:.3f} s"))
    facts.append(("mixdyn", __version__))
    return facts


def _unit(runner, name: str) -> str:
    """The model's unit of a body's or force element's number ``name`` (engineering label;
    ``""`` for a plain number or one of no declared kind)."""
    from ..units import engineering
    from .plan import number_kind

    kind = number_kind(runner, name)
    return engineering(runner.model.units.label(kind)) if kind is not None else ""


def _columns(runner, plan, result) -> tuple[dict, dict]:
    """The columns of a run's result as its ``results.csv`` holds them (output units)."""
    from ..analysis.result import in_units, point_columns
    from ..units import engineering

    points = getattr(plan.base.spec, "outputs", ())
    cols, units = in_units(result, *point_columns(result, points), runner.output_units)
    return cols, {c: engineering(u) for c, u in units.items()}


def _settings(plan) -> dict:
    from ..io.results import run_settings

    return {**run_settings(plan.spec), f"run {plan.base.name}": run_settings(plan.base.spec)}


# --------------------------------------------------------------------------- a sweep
def sweep_report(runner, plan, result, seconds: float, outputs) -> Report:
    """A sweep's page (:class:`~.sweep.FileSweep` ``result``): its members, the varied
    numbers' ranges, the summaries' minimum and maximum over the members that succeeded
    (with the members they belong to), the failed members and the sweep's figures."""
    from ..units import engineering

    members = result.members()
    units = {c: engineering(u) for c, u in result.member_units().items()}
    n, failed = plan.members, len(result.sweep.errors)
    r = plan.spec
    status = "ok" if not failed else f"{failed} of {n} members failed"
    how = "grid" if r.sampling == "grid" else f"Latin hypercube, seed {r.seed}"
    facts = _facts(runner, plan, outputs, status, seconds)
    facts[3:3] = [
        ("swept run", f"{plan.base.name} ({plan.base.spec.kind})"),
        ("members", f"{n} ({how}): {n - failed} ok, {failed} failed"),
    ]
    varied = [
        [
            name,
            units.get(name, ""),
            str(len(np.unique(v))),
            number(np.min(v)),
            number(np.max(v)),
        ]
        for name, v in ((name, np.asarray(v, dtype=float)) for name, v in plan.values.items())
    ]
    ok = members["status"] == "ok"
    summaries = []
    for x in r.summaries:
        v = members.loc[ok, x.name].to_numpy(dtype=float)
        if len(v):
            lo, hi = int(np.argmin(v)), int(np.argmax(v))
            at = members.loc[ok, "member"].to_numpy()
            cells = [number(v[lo]), str(at[lo]), number(v[hi]), str(at[hi])]
        else:
            cells = ["", "", "", ""]
        summaries.append([x.name, f"{x.reduce} of {x.column}", units.get(x.name, ""), *cells])
    tables = [
        Table(
            "Varied numbers",
            ["number", "unit", "values", "min", "max"],
            varied,
            numeric=(2, 3, 4),
            cls="varied",
        ),
        Table(
            f"Summaries over the {n - failed} members that succeeded",
            ["summary", "of", "unit", "min", "member at min", "max", "member at max"],
            summaries,
            numeric=(3, 4, 5, 6),
            cls="summaries",
        ),
    ]
    if failed:
        bad = members.loc[~ok].head(_MAX_FAILED_ROWS)
        names = list(plan.values)
        tables.append(
            Table(
                f"Failed members ({failed}; every member's outcome in members.csv)",
                ["member", *names, "error", "t", "message"],
                [
                    [
                        str(row["member"]),
                        *(number(row[k]) for k in names),
                        row["status"],
                        number(row["t_error"]),
                        row["error"],
                    ]
                    for _, row in bad.iterrows()
                ],
                numeric=tuple(range(len(names) + 1)),
                cls="failed",
            )
        )
    folder = outputs.folder(plan)
    figures = [folder / p.file for p in r.plots] if outputs.figures else []
    return Report(
        path=folder / REPORT_HTML,
        title=f"{runner.model.name}: sweep {plan.name}",
        facts=facts,
        drawing="",
        figures=figures,
        columns={},
        units={},
        settings=_settings(plan),
        tables=tables,
    )


# --------------------------------------------------------------------------- a fit
def fit_report(runner, plan, result, seconds: float, outputs) -> Report:
    """An identification's page (:class:`~.identify.FileFit` ``result``): the numbers found
    (start, estimate, standard deviation, bounds, in model units), each measured column's
    residual against its noise, the chi-square, the figure and the run at the estimate's
    columns."""
    from ..units import engineering

    f = result.fit
    facts = _facts(runner, plan, outputs, "ok", seconds)
    facts[3:3] = [
        ("fitted with", f"{plan.base.name} ({plan.base.spec.kind})"),
        ("data", f"{plan.spec.data}: {len(plan.times)} times of {', '.join(plan.measured)}"),
        ("reduced chi-square", number(f.chi2)),
        ("runs", str(f.evaluations)),
        ("solver", str(f.message)),
    ]
    found = []
    for k, name in enumerate(f.params):
        lo, hi = plan.bounds.get(name, (-np.inf, np.inf))
        sd = float(f.deviations[k])
        est = float(f.values[k])
        rel = f"{abs(sd / est):.2%}" if est != 0 and np.isfinite(sd) else ""
        found.append(
            [
                name,
                _unit(runner, name),
                number(f.start[k]),
                number(est),
                number(sd),
                rel,
                number(lo),
                number(hi),
            ]
        )
    model_units = result.result.units()
    residuals = []
    for col, measured in plan.measured.items():
        e = np.asarray(measured, dtype=float) - np.asarray(result.result[col], dtype=float)
        rms = float(np.sqrt(np.mean(e**2)))
        noise = float(plan.noise.get(col, np.nan))
        residuals.append(
            [
                col,
                engineering(model_units.get(col, "")),
                number(rms),
                number(np.max(np.abs(e))),
                number(noise),
                number(rms / noise) if np.isfinite(noise) and noise > 0 else "",
            ]
        )
    tables = [
        Table(
            "Numbers found (model units, as fit.csv)",
            ["number", "unit", "start", "estimate", "std. deviation", "relative", "low", "high"],
            found,
            numeric=(2, 3, 4, 5, 6, 7),
            cls="fitted",
        ),
        Table(
            "Residuals (measured - fitted, model units)",
            ["measured", "unit", "rms", "max |residual|", "noise", "rms / noise"],
            residuals,
            numeric=(2, 3, 4, 5),
            cls="residuals",
        ),
    ]
    return _study_page(runner, plan, result, outputs, facts, tables, "fit.png", "estimate")


# --------------------------------------------------------------------------- an optimization
def optimum_report(runner, plan, result, seconds: float, outputs) -> Report:
    """An optimization's page (:class:`~.optimize.FileOptimum` ``result``): the objective at
    the start and at the optimum, the numbers chosen (bounds, start, optimum, gradient, in
    model units; the bounds are the constraints, those active named), the figure and the run
    at the optimum's columns."""
    from ..units import engineering, in_units

    o, r = result.optimum, plan.spec
    col = r.objective.column
    unit = result.result.units().get(col, "")  # the objective's: the column's model unit
    shown, shown_units = in_units(
        result.result,
        {col: np.array([o.objective_start, o.objective])},
        {col: unit},
        runner.output_units,
    )
    out_unit, unit = engineering(shown_units[col]), engineering(unit)

    def value(k: int, raw: float) -> str:
        """The objective in the column's output unit (and model unit, where another)."""
        text = f"{number(shown[col][k])} {out_unit}".strip()
        return text + (f" ({number(raw)} {unit})" if out_unit != unit else "")

    change = o.objective - o.objective_start
    rel = f", {change / abs(o.objective_start):+.2%}" if o.objective_start else ""
    facts = _facts(runner, plan, outputs, "ok", seconds)
    facts[3:3] = [
        ("optimized with", f"{plan.base.name} ({plan.base.spec.kind})"),
        ("objective", f"{r.sense} the {r.objective.reduce} of {col}"),
        ("objective at the start", value(0, o.objective_start)),
        ("objective at the optimum", value(1, o.objective) + rel),
        ("iterations", f"{o.iterations} ({o.evaluations} runs)"),
        ("solver", str(o.message)),
    ]
    chosen = []
    bounds = np.asarray(o.bounds, dtype=float)
    for k, name in enumerate(o.params):
        lo, hi = bounds[k]
        x = float(o.values[k])
        span = max(hi - lo, 1e-300) if np.isfinite(hi - lo) else max(abs(x), 1.0)
        active = (
            "low" if abs(x - lo) <= 1e-9 * span else "high" if abs(hi - x) <= 1e-9 * span else ""
        )
        u = _unit(runner, name)
        per = f"{unit}/{u}" if unit and u else unit or (f"1/{u}" if u else "")
        chosen.append(
            [
                name,
                u,
                number(lo),
                number(hi),
                number(o.start[k]),
                number(x),
                active,
                number(o.gradient[k]),
                per,
            ]
        )
    tables = [
        Table(
            "Numbers chosen, within their bounds (the constraints; model units, as optimum.csv)",
            [
                "number",
                "unit",
                "low",
                "high",
                "start",
                "optimum",
                "bound active",
                "gradient",
                "gradient unit",
            ],
            chosen,
            numeric=(2, 3, 4, 5, 7),
            cls="optimum",
        )
    ]
    return _study_page(runner, plan, result, outputs, facts, tables, "optimize.png", "optimum")


def _study_page(runner, plan, result, outputs, facts, tables, figure: str, at: str) -> Report:
    folder = outputs.folder(plan)
    cols, units = _columns(runner, plan, result.result)
    return Report(
        path=folder / REPORT_HTML,
        title=f"{runner.model.name}: {plan.spec.kind} {plan.name}",
        facts=facts,
        drawing=start_drawing(result.result),
        figures=[folder / figure] if outputs.figures else [],
        columns=cols,
        units=units,
        settings=_settings(plan),
        tables=tables,
        columns_heading=f"Result columns of {plan.base.name} at the {at} (results.csv)",
    )


# --------------------------------------------------------------------------- a failure
def failure_report(runner, plan, error, outputs) -> Report:
    """A failed run's page: the failure first (the error's class, the time it failed at,
    its message, the elements involved), then what was computed before it (the states up to
    the failure, as its ``results.csv`` holds them) and the run's settings."""
    from ..analysis.result import in_units
    from ..io.results import run_settings
    from ..units import engineering

    tu = runner.b.units.label("time")  # the model's (a synthesis file has no model)
    at = f" at t = {error.time:g} {tu}" if getattr(error, "time", None) is not None else ""
    name = type(error).__name__
    line = f"The run failed{at}: {name}: {error.message}"
    facts = _facts(runner, plan, outputs, "failed", None)
    facts.insert(-1, ("written", datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")))
    failure = [
        ["error", name],
        ["time", f"{error.time:g} {tu}" if getattr(error, "time", None) is not None else "-"],
        ["message", error.message],
    ]
    if error.elements:
        failure.append(["elements", ", ".join(error.elements)])
    partial = getattr(error, "partial", None)
    cols, units = {}, {}
    if partial is not None and len(partial.t):
        cols, units = in_units(partial, partial.columns(), partial.units(), runner.output_units)
        units = {c: engineering(u) for c, u in units.items()}
        t = np.asarray(cols["t"])
        done = f"{len(t)} rows, t = {number(t[0])} .. {number(t[-1])} {units.get('t', '')}"
    else:
        done = "nothing (no state before the failure)"
    failure.append(["computed before it", done + (" (results.csv)" if cols else "")])
    folder = outputs.folder(plan)
    return Report(
        path=folder / REPORT_HTML,
        title=f"{runner.spec.name}: run {plan.name} failed",
        facts=facts,
        drawing="",
        figures=[],
        columns=cols,
        units=units,
        settings=run_settings(plan.spec),
        tables=[Table("The failure", ["", ""], failure, cls="failure")],
        failure=line,
        columns_heading="Computed before the failure (results.csv)",
    )


__all__ = ["REPORT_HTML", "failure_report", "fit_report", "optimum_report", "sweep_report"]

"""What a run writes and draws, checked when it is planned: figure and animation files of a
known type, each written once, the columns the run's result has (:func:`columns`), the force
arrows it can draw; and the file's ``output_units``, units of their kind
(:func:`output_units`)."""

from __future__ import annotations

import shutil

from ..kinds import kind_of
from ..plan import Plan

#: Suffixes of the per-body columns of a result.
BODY_COLUMNS = ("x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha")


def check_outputs(runner, plan: Plan) -> None:
    """Figure and animation files: a writable type each, no file written twice."""
    r = plan.spec
    seen: dict[str, tuple] = {}

    def claim(name: str, path) -> None:
        key = name.lower()
        if key in seen or key in ("results.csv", "results.parquet", "meta.json"):
            runner.fail(path, f"the run writes {name!r} twice", "give each output its own file")
        seen[key] = path

    for k, plot in enumerate(r.plots):
        claim(plot.file, (*plan.path, "plots", k, "file"))
    for k, ref in enumerate(getattr(r, "outputs", None) or ()):
        runner.b.point(ref, (*plan.path, "outputs", k))
    a = r.animation
    if a is None:
        return
    p = (*plan.path, "animation", "file")
    claim(a.file, p)
    if a.file.lower().endswith(".mp4") and shutil.which("ffmpeg") is None:
        runner.fail(p, "writing MP4 needs ffmpeg, which is not installed", "write a .gif")
    if a.html and not a.file.lower().endswith(".html"):
        stem = a.file.rsplit(".", 1)[0]
        claim(f"{stem}.html", (*plan.path, "animation", "html"))
    _check_arrows(runner, plan, a.forces, (*plan.path, "animation", "forces"))
    for k, col in enumerate(a.plot or ()):
        check_column(runner, col, r, (*plan.path, "animation", "plot", k))
    if a.plot_x != "t":
        p = (*plan.path, "animation", "plot_x")
        if a.plot == []:
            runner.fail(p, "the player has no plot ('plot: []')", "drop plot_x or name columns")
        check_column(runner, a.plot_x, r, p)


def _check_arrows(runner, plan: Plan, forces, path) -> None:
    """Force arrows: not in a kinematic run; each name a joint or a point force."""
    if not forces:
        return
    if kind_of(plan).motion_only:
        runner.fail(
            path,
            "a kinematic run has no forces to draw",
            "drop 'forces', or animate an inverse, forward or mixed run",
        )
    if forces is True:
        return
    from ..._hints import did_you_mean
    from ...model import PointForce
    from ...model._compliant import contacts

    known = [j.name for j in runner.model.joints]
    known += [f.name for f in runner.model.forces if isinstance(f, PointForce)]
    dependent = {f.name: f for f in runner.model.forces if f.needs_reactions}
    known += [name for name, f in dependent.items() if f.no_arrow is None]
    known += [f.name for f in contacts(runner.model)]
    contacts = {
        j.name: j
        for j in runner.model.joints
        if not j.generic_reaction and getattr(j, "motion", "") == "oscillating"
    }
    for k, name in enumerate(forces):
        if name in contacts:
            cols = ", ".join(f"{name}.{c}" for c in contacts[name].contact_kinds)
            runner.fail(
                (*path, k),
                f"{name!r} acts by a moment: it has no arrow",
                f"plot its contact forces instead ({cols})",
            )
        if name in dependent and dependent[name].no_arrow is not None:
            runner.fail(
                (*path, k),
                f"{name!r} {dependent[name].no_arrow}: it has no arrow",
                f"plot its column instead ({name})",
            )
        if name not in known:
            runner.fail(
                (*path, k),
                f"{name!r} is neither a joint nor a point force",
                did_you_mean(name, known),
            )


def output_units(runner) -> dict[str, str]:
    """The file's ``output_units`` checked: a preset's name (``SI``, ``mm-N-s``:
    :data:`mixdyn.units.OUTPUT_PRESETS`) or kinds and their units, a ``preset`` among them
    expanded first; known kinds, units of their dimension; the energy and the power following
    the units given by hand (:func:`mixdyn.units.completed`)."""
    from ..._hints import did_you_mean
    from ...units import DIMENSIONS, OUTPUT_PRESETS, completed

    given = runner.spec.output_units
    if isinstance(given, str):
        given = {"preset": given}
    out = {}
    if "preset" in given:
        name = given["preset"]
        path = (
            ("output_units",)
            if isinstance(runner.spec.output_units, str)
            else ("output_units", "preset")
        )
        if name not in OUTPUT_PRESETS:
            runner.fail(
                path,
                f"no preset of output units {name!r}",
                did_you_mean(name, OUTPUT_PRESETS, "presets"),
            )
        out.update(OUTPUT_PRESETS[name])
    for kind, unit in given.items():
        if kind == "preset":
            continue
        path = ("output_units", kind)
        if kind not in DIMENSIONS:
            runner.fail(
                path, f"no kind of quantity {kind!r}", did_you_mean(kind, DIMENSIONS, "kinds")
            )
        runner.b.factor(unit, kind, path)  # the dimension checked
        out[kind] = unit
    return completed(out, runner.model.units if runner.model is not None else None)


def columns(runner, r) -> tuple[list[str], set[str]]:
    """The columns a run's result has: ``(names, owners of lambda.* columns)`` (the
    multipliers ``lambda.{row}`` of the joints' and drivers' rows; point columns
    ``body.P.x`` are checked apart).

    Args:
        runner: the file's runner.
        r: the description of a run of one analysis.
    """
    kind = kind_of(r)
    model = runner.model
    cols = ["t"] + [f"{b}.{c}" for b in runner.b.body_names for c in BODY_COLUMNS]
    if kind.motion_only:
        return cols, set()
    for j in model.joints:
        if j.generic_reaction:
            cols += [f"{j.name}.Fx", f"{j.name}.Fy"]
            cols += [f"{j.name}.M"] if j.carries_moment else []
        cols += [f"{j.name}.{k}" for k in j.contact_kinds]
    drivers = [d.name for d in model.drivers if r.drivers is None or d.name in r.drivers]
    if not kind.unknown_forces:  # a mixed run's prescribed motions are paired with its unknowns
        drivers += [p.name or f"prescribed {p.coordinate}" for p in r.prescribed]
    unknown = tuple(getattr(r, "unknown", None) or ())
    for name in [*drivers, *unknown]:
        cols += [name, f"{name}.power"]
    if kind.element_columns:
        from ...equations import force_output_kinds

        cols += list(force_output_kinds(model, exclude=unknown))
    cols += ["energy.kinetic", "energy.potential", "energy.total", "constraint.violation"]
    if kind.integrated:
        cols += ["work.nonconservative", "work.constraints"]
    owners = {j.name for j in model.joints} | set(drivers)
    return cols, owners


#: The kind of quantity of each per-body column and point column (``body.P.x``).
_BODY_KINDS = {
    "x": "length",
    "y": "length",
    "phi": "angle",
    "vx": "velocity",
    "vy": "velocity",
    "omega": "angular_velocity",
    "ax": "acceleration",
    "ay": "acceleration",
    "alpha": "angular_acceleration",
}
_POINT_KINDS = {k: v for k, v in _BODY_KINDS.items() if k not in ("phi", "omega", "alpha")}

#: The kinds of the energy and work columns of every result.
_ENERGY_KINDS = {
    "energy.kinetic": "energy",
    "energy.potential": "energy",
    "energy.total": "energy",
    "work.nonconservative": "energy",
    "work.constraints": "energy",
    "constraint.violation": "length",
}


def column_kind(runner, col: str, r) -> str | None:
    """The kind of quantity of a run's column (a key of :data:`mixdyn.units.DIMENSIONS`),
    as its result will name it (:meth:`mixdyn.Result.kind_of`), or None where it is not
    known before the run (a multiplier ``lambda.*``, a prescribed motion's effort).

    Args:
        runner: the file's runner.
        col: a column the run has (:func:`check_column`).
        r: the run's description.
    """
    if col == "t":
        return "time"
    parts = col.split(".")
    if parts[0] in runner.b.body_index:
        if len(parts) == 2:
            return _BODY_KINDS.get(parts[1])
        return _POINT_KINDS.get(parts[-1]) if len(parts) == 3 else None
    if col in _ENERGY_KINDS:
        return _ENERGY_KINDS[col]
    model = runner.model
    name, _, field = col.partition(".")
    if field == "power":
        return "power"
    drivers = {d.name: d for d in model.drivers}
    if not field and name in drivers:
        return drivers[name].effort_kind
    if not field and name in (getattr(r, "unknown", None) or ()):
        return model.element(name).magnitude_kind
    joints = {j.name: j for j in model.joints}
    if name in joints:
        j = joints[name]
        return {"Fx": "force", "Fy": "force", "M": "torque", **j.contact_kinds}.get(field)
    from ...equations import force_output_kinds

    return force_output_kinds(model, exclude=tuple(getattr(r, "unknown", None) or ())).get(col)


def check_column(runner, col: str, r, path) -> None:
    """Refuse a column the run's result does not have (a point's ``body.P.x`` checked as a
    point of the body)."""
    parts = col.split(".")
    if len(parts) == 3 and parts[0] in runner.b.body_index and parts[1] not in BODY_COLUMNS:
        runner.b.point(f"{parts[0]}.{parts[1]}", path)
        if parts[2] in ("x", "y", "vx", "vy", "ax", "ay"):
            return
    names, owners = columns(runner, r)
    if col in names:
        return
    if col.startswith("lambda.") and any(
        col == f"lambda.{o}" or col.startswith(f"lambda.{o}.") for o in owners
    ):
        return
    from ..._hints import did_you_mean

    what = "a kinematic run has the motion only" if kind_of(r).motion_only else ""
    runner.fail(
        path,
        f"no column {col!r} in run {r.name!r}" + (f" ({what})" if what else ""),
        did_you_mean(col, names) + "; points: body.P.x (.y, .vx, .vy, .ax, .ay)",
    )


__all__ = [
    "BODY_COLUMNS",
    "check_column",
    "check_outputs",
    "column_kind",
    "columns",
    "output_units",
]

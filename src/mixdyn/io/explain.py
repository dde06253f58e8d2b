"""Every number of a model file as it was understood, with its unit (``mixdyn check
--explain``): where it is, as the file writes it, in the model's units and in SI.

Example of a line::

    force 'motor', law (line 18): 1.5 -> 1.5 mN*mm (no unit: model units) = 1.5e-06 N*m
"""

from __future__ import annotations

from ..units import DIMENSIONS, SI, kind_of, unit_for
from ._yaml import element_name, line_of
from .readings import Reading, si_value


def lines(builder) -> list[str]:
    """The lines of the explanation of the numbers ``builder`` (a
    :class:`~mixdyn.io.load.Builder`, after building the model and planning the runs) read:
    the parameters, then every number in the order read."""

    b, r = builder, builder.readings
    units = b.units
    out = [
        f"numbers as understood (model units: {units.describe()}; SI: m, kg, s, rad); "
        + ("strict_units: every number has a unit" if r.strict else "a number without a unit "
           "is in the model's units"),
    ]  # fmt: skip
    for name, p in r.parameters.items():
        value = b.parameters[name]
        place = f"parameter {name!r}" + (f" (line {p.line})" if p.line else "")
        if p.dim is None:
            out.append(f"{place}: {p.written} -> {value:.6g} (no unit: a plain number)")
            continue
        exps = tuple(int(e) for e in p.dim)
        model, si = _units(exps, units)
        f = si_value(Reading((), p.written, None, value, p.unit or model or None), units)
        si_text = f" = {f[0]:.6g} {si}".rstrip() if f is not None and p.unit else ""
        out.append(f"{place}: {p.written} -> {value:.6g} {model}".rstrip() + si_text)
    for reading in r.records.values():
        line = line_of(b.lines, reading.path) if b.lines else None
        place = element_name(b.data, reading.path) or "the file"
        place += f" (line {line})" if line else ""
        out.append(f"{place}: {_explained(reading, units)}")
    return out


def _units(exps, units) -> tuple[str, str]:
    """The model's and SI's names of the unit of a dimension."""
    kind = kind_of(exps)
    if kind in DIMENSIONS and kind != "dimensionless":
        return units.label(kind), SI.label(kind)
    return unit_for(exps, units), unit_for(exps, SI)


def _explained(reading: Reading, units) -> str:
    """``written -> value unit = value SI`` of one number, or what an expression is in."""
    kind = reading.kind
    kind_unit = (
        units.label(kind) if isinstance(kind, str) else unit_for(kind, units)
    ) or "dimensionless"
    if reading.value is None:  # a law written as an expression
        unit = reading.unit or f"{kind_unit} (model units)"
        return f"{reading.written} -> an expression whose value is in {unit}"
    value, si, model = si_value(reading, units)
    bare = reading.unit is None and reading.scale == 1.0 and not reading.from_parameters
    note = " (no unit: model units)" if bare and model not in ("", "rad") else ""
    if bare and model == "rad":
        note = " (no unit: radians)"
    if reading.from_parameters:
        note = " (in its parameters' units)"
    model = model or ""
    si_text = f" = {value:.6g} {si}".rstrip() if si != model else ""
    return f"{reading.written} -> {reading.value:.6g} {model}".rstrip() + note + si_text


__all__ = ["lines"]

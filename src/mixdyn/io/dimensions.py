"""Dimensions of expressions: what a law or a constant expression of a model file comes out
as, found from the units of what it uses, and checked against what its field needs.

A dimension is a tuple of exponents of (length, mass, time) as fractions (a square root
halves them); angles are dimensionless. What an expression's names have:

* a parameter written with a unit (``n0: 300 rad/s``): that unit's dimension;
* a parameter written without one (``T0: 1.5``): none, a plain number (:data:`PLAIN`);
* ``t``: time (or the kind of a law's own variable, such as a cam's angle);
* a body's state: ``x``, ``y`` a length, ``phi`` an angle, ``vx``, ``vy`` a velocity,
  ``omega`` an angular velocity (1/time);
* a number written in the expression, ``pi`` and ``e``: whatever the place needs (a
  coefficient such as the ``2*pi`` of ``2*pi*t`` is in the model's units, like a number
  written without a unit in a field): :data:`FREE`.

Rules: ``+``, ``-``, ``%``, comparisons, ``min``, ``max``, ``clip``, ``hypot``, ``atan2``
and the two branches of ``where`` need equal dimensions; ``sin``, ``cos``, ``exp``, ``log``
and the other transcendental functions need a dimensionless argument; ``sqrt`` halves a
dimension; ``x**p`` needs a dimensionless constant ``p``, a whole number or a simple fraction
where ``x`` has a dimension; ``step(x, x0, h0, x1, h1)`` needs ``x``, ``x0``, ``x1`` alike and
comes out as ``h0`` and ``h1``.

:func:`check` applies them to a law of a field of a known kind and, where the law does not
come out as that kind, names the parameter without a unit that would make it right and the
line to write (``T0: 1.5 N*m``).
"""

from __future__ import annotations

import ast
import dataclasses
import itertools
from collections.abc import Mapping
from fractions import Fraction

from ..units import DIMENSIONS, SI, UnitSystem, close_units, exponents, kind_of, unit_for
from .expressions import CONSTANTS, STATE_ATTRIBUTES, ExpressionError, constant_value

Dim = tuple[Fraction, Fraction, Fraction]
"""Exponents of (length, mass, time)."""

#: A dimensionless quantity (an angle, a plain number).
PLAIN: Dim = (Fraction(0), Fraction(0), Fraction(0))
#: What a number written in an expression has: any dimension (None).
FREE = None

#: The dimension of each body state usable in a force's expression.
STATE_DIMS: dict[str, tuple[int, int, int]] = {
    "x": DIMENSIONS["length"],
    "y": DIMENSIONS["length"],
    "phi": DIMENSIONS["angle"],
    "vx": DIMENSIONS["velocity"],
    "vy": DIMENSIONS["velocity"],
    "omega": DIMENSIONS["angular_velocity"],
}
assert set(STATE_DIMS) == set(STATE_ATTRIBUTES)

#: Functions whose argument must be dimensionless and whose value is.
_TRANSCENDENTAL = {
    "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "exp", "log", "log10",
}  # fmt: skip
#: Largest denominator of a fractional exponent of a quantity with a dimension.
MAX_DENOMINATOR = 6


def dim(exps) -> Dim:
    """A dimension from exponents (a kind's tuple of ints)."""
    return tuple(Fraction(e) for e in exps)


def describe(d: Dim | None) -> str:
    """A dimension in words: ``"a torque"``, ``"dimensionless"``, ``"length^1/2"``."""
    if d is None:
        return "any dimension"
    if d == PLAIN:
        return "dimensionless"
    if all(e.denominator == 1 for e in d):
        name = kind_of(tuple(int(e) for e in d))
        if not name.startswith("length^"):
            name = name.replace("_", " ")
            return ("an " if name[0] in "aeiou" else "a ") + name
    parts = [f"{n}^{e}" for n, e in zip(("length", "mass", "time"), d, strict=True) if e]
    return " ".join(parts)


def unit_of(d: Dim, units: UnitSystem) -> str:
    """A unit to suggest for a dimension: the model's for lengths, masses, times and their
    rates, the SI one named plainly for the rest (``N*m``, ``N*m*s/rad``)."""
    if any(e.denominator != 1 for e in d):
        return unit_for(tuple(int(2 * e) for e in d), SI) + " (squared)"
    exps = tuple(int(e) for e in d)
    kind = kind_of(exps)
    if kind in ("length", "mass", "time", "velocity", "acceleration"):
        return units.unit(kind)
    if kind in ("angular_velocity", "angular_acceleration"):
        return units.unit(kind)
    if kind in DIMENSIONS and kind != "dimensionless":
        return SI.label(kind)
    return unit_for(exps, SI) or "1"


class MismatchError(Exception):
    """Dimensions that do not fit inside an expression. Attributes: ``problem``, ``column``
    (1-based, or None)."""

    def __init__(self, problem: str, column: int | None = None):
        self.problem = problem
        self.column = column
        super().__init__(problem)


@dataclasses.dataclass(frozen=True)
class Leaves:
    """What an expression uses: the parameters (in order of first use) and whether it reads
    a body's state."""

    parameters: tuple[str, ...]
    states: bool


def leaves(source: str, parameters) -> Leaves:
    """The parameters (names among ``parameters``) and body states ``source`` uses."""
    used: list[str] = []
    states = False
    for node in ast.walk(ast.parse(source.strip(), mode="eval")):
        if isinstance(node, ast.Attribute):
            states = True
        elif isinstance(node, ast.Name) and node.id in parameters and node.id not in used:
            used.append(node.id)
    return Leaves(tuple(used), states)


class _Infer:
    """Dimensions of the nodes of one parsed (and already accepted) expression."""

    def __init__(self, source: str, dims: Mapping[str, Dim], variable: Dim, values, numbers):
        self.numbers = numbers
        self.text = source.strip()
        self.shift = len(source) - len(source.lstrip())
        self.dims = dims
        self.variable = variable
        self.values = values

    def fail(self, node, problem: str):
        col = getattr(node, "col_offset", None)
        raise MismatchError(problem, None if col is None else col + 1 + self.shift)

    def segment(self, node) -> str:
        text = ast.get_source_segment(self.text, node) or self.text
        return text if len(text) <= 40 else text[:37] + "..."

    def same(self, node, what: str, items) -> Dim | None:
        """The common dimension of ``items`` (nodes), FREE ones taking the others'."""
        out = FREE
        for item in items:
            d = self.of(item)
            if d is FREE:
                continue
            if out is not FREE and d != out:
                self.fail(
                    node,
                    f"{what} {describe(out)} and {describe(d)} in {self.segment(node)!r}",
                )
            out = d
        return out

    def plain(self, node, fn: str, arg) -> None:
        d = self.of(arg)
        if d is not FREE and d != PLAIN:
            self.fail(
                arg,
                f"{fn}() needs a dimensionless argument; {self.segment(arg)!r} is {describe(d)}",
            )

    def of(self, node) -> Dim | None:
        if isinstance(node, ast.Constant):
            return self.numbers
        if isinstance(node, ast.Name):
            if node.id == "t":
                return self.variable
            if node.id in self.dims:
                return self.dims[node.id]
            if node.id in CONSTANTS:
                return self.numbers
            return FREE
        if isinstance(node, ast.Attribute):
            return dim(STATE_DIMS[node.attr])
        if isinstance(node, ast.UnaryOp):
            return self.of(node.operand)
        if isinstance(node, ast.Compare):
            self.same(node, "cannot compare", [node.left, *node.comparators])
            return PLAIN
        if isinstance(node, ast.BinOp):
            return self.binop(node)
        if isinstance(node, ast.Call):
            return self.call(node)
        return FREE  # pragma: no cover - refused by the parser

    def binop(self, node) -> Dim | None:
        op = node.op
        if isinstance(op, ast.Add | ast.Sub):
            what = "cannot add" if isinstance(op, ast.Add) else "cannot subtract"
            return self.same(node, what, [node.left, node.right])
        if isinstance(op, ast.Mod):
            return self.same(node, "'%' needs equal dimensions, got", [node.left, node.right])
        if isinstance(op, ast.Pow):
            return self.power(node)
        a, b = self.of(node.left), self.of(node.right)
        if a is FREE or b is FREE:
            return FREE
        sign = 1 if isinstance(op, ast.Mult) else -1
        return tuple(x + sign * y for x, y in zip(a, b, strict=True))

    def power(self, node) -> Dim | None:
        base, exp = self.of(node.left), self.of(node.right)
        if exp is not FREE and exp != PLAIN:
            self.fail(
                node.right,
                f"an exponent must be dimensionless; {self.segment(node.right)!r} is "
                f"{describe(exp)}",
            )
        if base is FREE or base == PLAIN:
            return base
        try:
            value = constant_value(ast.get_source_segment(self.text, node.right), self.values)
        except ExpressionError:
            self.fail(
                node.right,
                f"{self.segment(node.left)!r} is {describe(base)}: its exponent must be a constant",
            )
        p = Fraction(value).limit_denominator(MAX_DENOMINATOR)
        if abs(float(p) - value) > 1e-12 * max(1.0, abs(value)):
            self.fail(
                node.right,
                f"{self.segment(node.left)!r} is {describe(base)}: its exponent must be a whole "
                f"number or a simple fraction, got {value!r}",
            )
        return tuple(e * p for e in base)

    def call(self, node) -> Dim | None:
        name, args = node.func.id, node.args
        if name in _TRANSCENDENTAL:
            self.plain(node, name, args[0])
            return PLAIN
        if name == "atan2":
            self.same(node, "atan2() needs equal dimensions, got", args)
            return PLAIN
        if name == "sign":
            self.of(args[0])
            return PLAIN
        if name == "sqrt":
            d = self.of(args[0])
            return FREE if d is FREE else tuple(e / 2 for e in d)
        if name in ("abs", "floor", "ceil"):
            return self.of(args[0])
        if name in ("hypot", "min", "max", "clip"):
            return self.same(node, f"{name}() needs equal dimensions, got", args)
        if name == "where":
            self.of(args[0])
            return self.same(node, "where() needs both branches alike, got", args[1:])
        if name in ("step", "step5"):
            self.same(node, f"{name}() needs x, x0 and x1 alike, got", [args[0], args[1], args[3]])
            return self.same(node, f"{name}() needs h0 and h1 alike, got", [args[2], args[4]])
        return FREE  # pragma: no cover - refused by the parser


def infer(
    source: str,
    dims: Mapping[str, Dim],
    *,
    variable: Dim = dim(DIMENSIONS["time"]),
    values: Mapping[str, float] | None = None,
    numbers: Dim | None = FREE,
) -> Dim | None:
    """The dimension of an accepted expression (:func:`mixdyn.io.expressions.parse`), or
    :data:`FREE` where it is made of numbers only.

    Args:
        source: the expression.
        dims: the dimension of every parameter it may use.
        variable: the dimension of ``t`` (time; an angle for a cam's law).
        values: the parameters' values, for constant exponents.
        numbers: the dimension of the numbers written in it (:data:`FREE`; :data:`PLAIN`
            to find the plainest reading of a law, :func:`check`).

    Raises:
        MismatchError: two dimensions that must be equal are not, with the column.
    """
    tree = ast.parse(source.strip(), mode="eval")
    return _Infer(source, dims, variable, dict(values or {}), numbers).of(tree.body)


@dataclasses.dataclass(frozen=True)
class Parameter:
    """A file parameter as the dimension check sees it.

    Attributes:
        name: its name.
        dim: its dimension, or None where it is written without a unit (a plain number).
        written: its value as the file writes it.
        line: its line in the file (None: not known).
        unit: the unit written with it (None: none).
    """

    name: str
    dim: Dim | None
    written: object
    line: int | None = None
    unit: str | None = None


@dataclasses.dataclass(frozen=True)
class Fault:
    """Why a law does not fit its field: ``problem`` and ``hint`` (the line to write), and
    ``parameter``, the parameter at fault (None: none found), with ``dim``, the dimension
    that would make the law fit, and ``dims``, those of all the parameters at fault."""

    problem: str
    hint: str
    parameter: str | None = None
    dim: Dim | None = None
    dims: Mapping[str, Dim] | None = None


#: Dimensions tried for a parameter written without a unit, to find the one a law needs.
_CANDIDATES = tuple(dict.fromkeys(dim(e) for e in DIMENSIONS.values() if any(e)))


def check(
    source: str,
    target: Dim,
    parameters: Mapping[str, Parameter],
    units: UnitSystem,
    *,
    needed: str,
    variable: Dim = dim(DIMENSIONS["time"]),
    values: Mapping[str, float] | None = None,
    strict: bool = False,
    law: bool = True,
) -> Fault | None:
    """Whether the expression ``source`` comes out as ``target``; None where it does.

    An expression that uses neither a body state nor a parameter with a unit of a dimension
    (an angle in ``deg`` has none) is in the model's units as it stands, and is not checked
    unless ``strict``. Parameters without a
    unit are plain numbers; where one of them, given a unit, would make the expression fit,
    the fault names it, its line and the unit (``T0: 1.5 N*m``).

    Args:
        source: an accepted expression.
        target: the dimension its field needs.
        parameters: the file's parameters by name.
        units: the model's unit system (for the units suggested).
        needed: what the field needs, in words (``"a torque"``).
        variable: the dimension of ``t``.
        values: the parameters' values (model units).
        strict: check every expression, and refuse one made of numbers and parameters
            without units only where ``target`` has a dimension (the file's
            ``strict_units``).
        law: ``source`` is a law (else a constant expression in a field, whose unit is
            written after it).
    """
    used = leaves(source, parameters)
    stated = used.states or any(parameters[n].dim not in (None, PLAIN) for n in used.parameters)
    if not (stated or strict):
        return None
    dims = {n: (p.dim if p.dim is not None else PLAIN) for n, p in parameters.items()}
    try:
        got = infer(source, dims, variable=variable, values=values)
    except MismatchError as e:
        got, mismatch = None, e
    else:
        mismatch = None
        if got is FREE:  # a number in it takes the unit its place needs (m*L**2/12)
            if strict and target != PLAIN and not stated:
                unit = unit_of(target, units)
                return Fault(
                    f"the numbers of {source!r} carry no unit (strict_units), {needed} is needed",
                    f"give the law's unit: {{expr: {source}, unit: {unit}}}, or use parameters "
                    "with units"
                    if law
                    else f"write it with its unit: `{source} {unit}`",
                )
            return None
        if got == target:
            return None
    bare = [n for n in used.parameters if parameters[n].dim is None]
    fix = _units_that_fit(source, target, dims, bare, variable, values)
    if fix:
        return _blame([parameters[n] for n in fix], fix, source, got, mismatch, needed, units)
    for name in used.parameters:
        p = parameters[name]
        for spelling in close_units(p.unit) if p.unit else ():
            cand = dim(exponents(spelling))
            try:
                d = infer(source, {**dims, name: cand}, variable=variable, values=values)
            except MismatchError:
                continue
            if d is FREE or d == target:
                line = f" (line {p.line})" if p.line else ""
                number = str(p.written).strip()[: -len(p.unit)].strip()
                return Fault(
                    f"expression {source!r}: parameter {name!r}{line} is in {p.unit!r} "
                    f"({describe(p.dim)}), so the expression does not come out as {needed}",
                    f"did you mean `{name}: {number} {spelling}`?",
                    name,
                    cand,
                )
    where = f"column {mismatch.column} of " if mismatch and mismatch.column else ""
    what = mismatch.problem if mismatch else f"it comes out as {describe(got)}, not {needed}"
    plain = f"; {', '.join(bare)} without a unit: plain numbers" if bare else ""
    return Fault(
        f"{where}expression {source!r}: {what}{plain}",
        "give the parameters the units they have ('w: 3 rad/s' for sin(w*t)); a number written "
        "in the expression takes the unit its place needs (sin(2*pi*t))",
    )


#: Most parameters without units given units together to find a law's fix.
MAX_FIXED_TOGETHER = 2


def _units_that_fit(source, target, dims, bare, variable, values) -> dict[str, Dim]:
    """Dimensions of the fewest of the parameters ``bare`` that make ``source`` come out as
    ``target`` (empty: none found), the plainest reading first: with the numbers written in
    it dimensionless (the ``1`` of ``1 - w/n0``), then as any dimension."""
    for numbers in (PLAIN, FREE):
        for k in range(1, min(MAX_FIXED_TOGETHER, len(bare)) + 1):
            for names in itertools.combinations(bare, k):
                for cands in itertools.product(_CANDIDATES, repeat=k):
                    trial = {**dims, **dict(zip(names, cands, strict=True))}
                    try:
                        d = infer(source, trial, variable=variable, values=values, numbers=numbers)
                    except MismatchError:
                        continue
                    if d == target or (d is FREE and numbers is FREE):
                        return dict(zip(names, cands, strict=True))
    return {}


def _blame(ps: list[Parameter], fix: dict, source, got, mismatch, needed, units) -> Fault:
    if mismatch is not None:
        outcome = f"its units do not fit ({mismatch.problem})"
    else:
        outcome = f"it comes out as {describe(got)}, not {needed}"
    named = " and ".join(
        f"parameter {p.name!r}" + (f" (line {p.line})" if p.line else "") for p in ps
    )
    verb = "is" if len(ps) == 1 else "are"
    fixes = ", ".join(
        f"`{p.name}: {_shown(p.written)} {unit_of(fix[p.name], units)}` ({describe(fix[p.name])})"
        for p in ps
    )
    return Fault(
        f"expression {source!r}: {named} {verb} written without a unit, so a plain number "
        f"here and {outcome}",
        f"write the unit you mean, e.g. {fixes}",
        ps[0].name,
        fix[ps[0].name],
        fix,
    )


def _shown(value) -> str:
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return str(value)


__all__ = [
    "FREE",
    "PLAIN",
    "STATE_DIMS",
    "Dim",
    "Fault",
    "Leaves",
    "MismatchError",
    "Parameter",
    "check",
    "describe",
    "dim",
    "infer",
    "leaves",
    "unit_of",
]

"""Write a description (or a model built in Python) back to a model file.

``reads(dumps(spec)) == spec`` for every description, and ``build(reads(dumps(model)))`` equals
``model`` for a model whose laws a file can hold (constants, polynomials, harmonics, splines,
piecewise polynomials, expressions; not Python functions).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import re

import numpy as np
import yaml

from .. import model as m
from ..errors import ModelError
from ..model._declare import TIME, Variable
from ..units import unit_for
from . import dimensions as d
from . import schema as s
from ._errors import FileError
from .expressions import ExpressionFunction, ExpressionLaw
from .load import Builder
from .readings import spec_units


class _Dumper(yaml.SafeDumper):
    """Safe dumper: short lists of scalars in flow style; strings that would read back as
    numbers quoted."""


_Dumper.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(
        r"""^(?:[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?(?:[eE][-+]?[0-9]+)
        |[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?)$""",
        re.X,
    ),
    list("-+0123456789."),
)


def _represent_list(dumper, data):
    flow = len(data) <= 12 and all(
        isinstance(x, int | float | str) and (not isinstance(x, str) or len(x) < 30) for x in data
    )
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _represent_list)


def to_data(spec: s.ModelFile) -> dict:
    """Plain data of a description, defaults left out (``mixdyn``, names and kinds kept)."""
    data = spec.model_dump(mode="json", exclude_defaults=True)
    data["units"] = spec.units.model_dump(mode="json")
    data["runs"] = [{"name": r["name"], "kind": r["kind"], **r} for r in data.get("runs", [])]
    if not data["runs"]:
        del data["runs"]
    order = [k for k in s.ModelFile.model_fields if k in data]
    return {"mixdyn": s.FORMAT_VERSION, **{k: data[k] for k in order if k != "mixdyn"}}


def dumps(obj) -> str:
    """YAML text of a description (:class:`~mixdyn.io.schema.ModelFile`) or a
    :class:`mixdyn.Model`."""
    spec = describe(obj) if isinstance(obj, m.Model) else obj
    if not isinstance(spec, s.ModelFile):
        raise TypeError(f"expected a ModelFile or a Model, got {type(obj).__name__}")
    return yaml.dump(
        to_data(spec),
        Dumper=_Dumper,
        sort_keys=False,
        allow_unicode=True,
        width=100,
        default_flow_style=False,
    )


def dumps_keeping(source: str, spec: s.ModelFile) -> str:
    """:func:`dumps` of ``spec`` (read from the YAML text ``source``) with ``source``'s
    comments, key order and flow style kept where its keys remain: the normal form's values
    are written into ``source``'s own tree (ruamel.yaml's round trip); keys the normal form
    leaves out (defaults) go, with their comments. ``reads`` of the result equals ``spec``."""
    import io

    from ruamel.yaml import YAML
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    rt = YAML(typ="rt")
    rt.width = 100
    rt.preserve_quotes = True
    rt.indent(mapping=2, sequence=4, offset=2)  # "  - item", as the examples are written
    tree = rt.load(source)

    def fresh(value):
        if isinstance(value, dict):
            out = CommentedMap()
            for k, v in value.items():
                out[k] = fresh(v)
            return out
        if isinstance(value, list):
            out = CommentedSeq(fresh(v) for v in value)
            flow = len(value) <= 12 and all(
                isinstance(x, int | float | str) and (not isinstance(x, str) or len(x) < 30)
                for x in value
            )
            if flow:
                out.fa.set_flow_style()
            return out
        return value

    def merge(old, new):
        if isinstance(old, CommentedMap) and isinstance(new, dict):
            for k in [k for k in old if k not in new]:
                del old[k]
            for pos, (k, v) in enumerate(new.items()):
                if k in old:
                    old[k] = merge(old[k], v)
                else:
                    old.insert(min(pos, len(old)), k, fresh(v))
            return old
        if isinstance(old, CommentedSeq) and isinstance(new, list) and len(old) == len(new):
            for i, v in enumerate(new):
                old[i] = merge(old[i], v)
            return old
        if not isinstance(old, dict | list) and not isinstance(new, dict | list):
            if type(old) is not bool and type(new) is not bool and old == new:
                return old  # the user's spelling of an equal value (1.0 vs 1, quotes)
            if type(old) is type(new) is bool and old == new:
                return old
        return fresh(new)

    data = to_data(spec)
    if not isinstance(tree, CommentedMap):
        return dumps(spec)
    merged = merge(tree, data)
    buf = io.StringIO()
    rt.dump(merged, buf)
    return buf.getvalue()


def dump(obj, path) -> None:
    """Write :func:`dumps` of ``obj`` to ``path``."""
    text = dumps(obj)
    tmp = os.fspath(path) + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


# --------------------------------------------------------------------------- Model -> description
def _f(x) -> float:
    return float(np.asarray(x))


def _v(x) -> list[float]:
    return [float(v) for v in np.asarray(x).ravel()]


class _Describer:
    def __init__(self, model: m.Model):
        self.model = model
        self.parameters: dict[str, float] = {}

    def law(self, law, element: str, variable: Variable = TIME):
        """A law's description; a law of another variable than time (a cam's angle) names
        it in its expression."""
        out = self._law(law, element)
        if variable == TIME:
            return out
        if isinstance(out, str):
            return re.sub(r"\bt\b", variable.name, out)
        if isinstance(out, dict) and "expr" in out:
            return {**out, "expr": re.sub(r"\bt\b", variable.name, out["expr"])}
        return out

    def _law(self, law, element: str):
        if law is None:
            return 0.0
        if isinstance(law, m.StateFunction):
            fn = law.fn
            if not isinstance(fn, ExpressionFunction):
                raise ModelError(
                    "a force given by a Python function cannot be written to a file; write it "
                    "as an expression of t and body states",
                    element,
                )
            return self._expr(fn.source, fn.parameters, fn.unit, element)
        if isinstance(law, ExpressionLaw):
            return self._expr(law.source, law.parameters, law.unit, element)
        if isinstance(law, m.Constant):
            return _f(law.value)
        if isinstance(law, m.Polynomial):
            return {"polynomial": _v(law.coeffs)}
        if isinstance(law, m.Harmonic):
            return {
                "harmonic": {
                    "amplitude": _f(law.amplitude),
                    "omega": _f(law.omega),
                    "phase": _f(law.phase),
                    "offset": _f(law.offset),
                }
            }
        if isinstance(law, m.PiecewisePolynomial):
            c = np.asarray(law.coeffs, dtype=float)
            return {"piecewise": {"breaks": _v(law.breaks), "coeffs": c.tolist()}}
        raise ModelError(
            f"a law of type {type(law).__name__} cannot be written to a file; use an expression, "
            "a polynomial, a harmonic or a spline",
            element,
        )

    def _expr(self, source, params, unit, element):
        for k, v in params.items():
            if k in self.parameters and self.parameters[k] != v:
                raise ModelError(
                    f"parameter {k!r} has two values ({self.parameters[k]:g} and {v:g}) in "
                    "different expressions; a file has one value per parameter",
                    element,
                )
            self.parameters[k] = v
        return {"expr": source} if unit is None else {"expr": source, "unit": unit}

    def joint(self, j):
        spec = s.JOINT_SPECS.get(type(j).__name__)
        if spec is None:
            raise ModelError(f"a {type(j).__name__} joint cannot be written to a file", j.name)
        return spec.from_element(j, self)

    @staticmethod
    def axis(a):
        return a if isinstance(a, str) else tuple(float(x) for x in a)

    def driver(self, d):
        spec = s.DRIVER_SPECS.get(type(d).__name__)
        if spec is None:
            raise ModelError(f"a {type(d).__name__} driver cannot be written to a file", d.name)
        return spec.from_element(d, self)

    def force(self, f):
        spec = s.FORCE_SPECS.get(type(f).__name__)
        if spec is None:
            raise ModelError(
                f"a {type(f).__name__} force (a Python function) cannot be written to a file",
                f.name,
            )
        return spec.from_element(f, self)


def describe(model: m.Model, runs=()) -> s.ModelFile:
    """The description of a model built in Python (numbers in the model's units).

    Args:
        model: the model.
        runs: run descriptions to include (:class:`~mixdyn.io.schema.ModelFile` runs).

    Raises:
        ModelError: an element that a file cannot hold (a Python function).
    """
    d = _Describer(model)
    bodies = [
        s.BodySpec(
            name=b.name,
            mass=_f(b.mass),
            inertia=_f(b.inertia),
            q0=tuple(_v(b.q0)),
            points={k: tuple(_v(v)) for k, v in b.points.items()},
            vectors={k: tuple(_v(v)) for k, v in b.vectors.items()},
        )
        for b in model.bodies
    ]
    joints = [d.joint(j) for j in model.joints]
    drivers = [d.driver(x) for x in model.drivers]
    forces = [d.force(f) for f in model.forces]
    u = model.units
    out = s.ModelFile(
        name=model.name,
        units=s.UnitsSpec(length=u.length, mass=u.mass, time=u.time),
        gravity=tuple(_v(model.gravity)),
        parameters=dict(d.parameters),
        ground=s.GroundSpec(points={k: tuple(_v(v)) for k, v in model.ground.points.items()}),
        bodies=bodies,
        joints=joints,
        drivers=drivers,
        forces=forces,
        runs=list(runs),
    )
    # The parameters are numbers in model units: those that laws need with a dimension
    # (``c`` of ``-c*rod.omega``) are written with the model's unit of it.
    needed = parameter_units(out) if out.parameters else {}
    if not needed:
        return out
    params = {k: f"{v!r} {needed[k]}" if k in needed else v for k, v in out.parameters.items()}
    return out.model_copy(update={"parameters": params})


def parameter_units(spec) -> dict[str, str]:
    """The units (model units, pint spelling) that the parameters written without one in
    ``spec`` need for its laws to fit their fields, by name: what a description written from
    a model (:func:`mixdyn.io.dump.describe`, whose parameters are numbers in model units)
    gives its parameters."""
    found: dict[str, d.Dim] = {}
    for _ in range(len(spec.parameters) + 1):
        b = Builder(spec)
        b.readings.needed = {}
        for name, dim in found.items():  # the units found so far, as if written
            p = b.readings.parameters[name]
            b.readings.parameters[name] = dataclasses.replace(p, dim=dim)
        with contextlib.suppress(FileError):
            b.model()
        new = {k: v for k, v in b.readings.needed.items() if k not in found}
        if not new:
            break
        found.update(new)
    return {k: unit_for(tuple(int(e) for e in v), spec_units(spec)) for k, v in found.items()}


__all__ = ["describe", "dump", "dumps", "to_data"]

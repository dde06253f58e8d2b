"""Model files: read, validate, build and write back.

A model file (YAML) describes a mechanism in one unit system and named runs of analyses on it.
It is read safely (no code, no aliases), validated by a pydantic schema
(:class:`ModelFile`, exportable as JSON Schema), and built into a :class:`mixdyn.Model`;
quantities may carry units (``"500 N*mm"``) and laws of time are safe expressions
(``"10*sin(pi*t/2)"``). Every fault is a :class:`FileError` naming the file, line and element.

This package holds the file formats (the model file, the written results). Running a file's
runs is :mod:`mixdyn.runs`; its :class:`Runner`, :class:`Plan` and :func:`execute` are also
reached here (looked up in :mod:`mixdyn.runs` when first used).

Example::

    import mixdyn.io as mio
    spec = mio.read("examples/antonya.yaml")
    model = mio.build(spec)
    results = mio.execute(spec)          # every run, by name
    mio.write_result(results["forward"], "out/forward")
"""

from ._errors import FileError
from .dump import describe, dump, dumps
from .expressions import FUNCTIONS, ExpressionError, ExpressionFunction, ExpressionLaw
from .load import build, load, read, reads, source_of
from .quantities import DimensionError, QuantityError, convert
from .results import read_result, write_result
from .schema import ModelFile, json_schema

#: Names of :mod:`mixdyn.runs` reached from here.
_RUNS = ("Plan", "Runner", "execute")


def __getattr__(name: str):
    if name in _RUNS:
        from .. import runs

        return getattr(runs, name)
    raise AttributeError(f"module 'mixdyn.io' has no attribute {name!r}")


__all__ = [
    "FUNCTIONS",
    "DimensionError",
    "ExpressionError",
    "ExpressionFunction",
    "ExpressionLaw",
    "FileError",
    "ModelFile",
    "Plan",
    "QuantityError",
    "Runner",
    "build",
    "convert",
    "describe",
    "dump",
    "dumps",
    "execute",
    "json_schema",
    "load",
    "read",
    "read_result",
    "reads",
    "source_of",
    "write_result",
]

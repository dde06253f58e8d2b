"""Model files: read, validate, build and write back.

A model file (YAML) describes a mechanism in one unit system and named runs of analyses on it.
It is read safely (no code, no aliases), validated by a pydantic schema
(:class:`ModelFile`, exportable as JSON Schema), and built into a :class:`mixdyn.Model`;
quantities may carry units (``"500 N*mm"``) and laws of time are safe expressions
(``"10*sin(pi*t/2)"``). Every fault is a :class:`FileError` naming the file, line and element.

This package holds the file formats (the model file, the written results). Running a file's
runs is :mod:`mixdyn.runs` (``mixdyn.io.Runner``, ``Plan`` and ``execute`` are deprecated
spellings of its names: a DeprecationWarning names them).

Example::

    import mixdyn.io as mio
    import mixdyn.runs
    spec = mio.read("examples/antonya.yaml")
    model = mio.build(spec)
    results = mixdyn.runs.execute(spec)  # every run, by name
    mio.write_result(results["forward"], "out/forward")
"""

from .._moved import old_name
from ._errors import FileError
from .dump import describe, dump, dumps
from .expressions import FUNCTIONS, ExpressionError, ExpressionFunction, ExpressionLaw
from .load import build, load, read, reads, source_of
from .quantities import DimensionError, QuantityError, convert
from .results import read_result, read_table, write_result
from .schema import ModelFile, json_schema


def __getattr__(name: str):
    # Runner, Plan and execute moved up to mixdyn.runs, which mixdyn's top level registers.
    return old_name(__name__, name)


__all__ = [
    "FUNCTIONS",
    "DimensionError",
    "ExpressionError",
    "ExpressionFunction",
    "ExpressionLaw",
    "FileError",
    "ModelFile",
    "QuantityError",
    "build",
    "convert",
    "describe",
    "dump",
    "dumps",
    "json_schema",
    "load",
    "read",
    "read_result",
    "read_table",
    "reads",
    "source_of",
    "write_result",
]

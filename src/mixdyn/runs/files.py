"""A model file from Python: :func:`load` (its model and its runs) and :func:`run_file`
(its runs executed, their results returned and, with ``out``, written as ``mixdyn run``
writes them).

Example::

    import mixdyn as md
    f = md.load("examples/antonya.yaml")        # f.model, f.runs, f.units, f.output_units
    results = md.run_file("examples/antonya.yaml")
    results["forward"].table()                  # in the file's output_units, t a column
    results["forward"].plot(["crank.phi"])      # a matplotlib Figure
"""

from __future__ import annotations

import dataclasses
import os
import pathlib

from .. import model as m
from ..analysis import Result
from ..io import schema as s
from ..units import UnitSystem


@dataclasses.dataclass(frozen=True)
class LoadedFile:
    """A model file read, validated and built, its runs checked (nothing computed).

    Attributes:
        path: the file.
        spec: its validated description (:class:`mixdyn.io.ModelFile`).
        model: its model; None for a file of synthesis runs alone (no bodies).
        runs: its runs' descriptions by name, in the file's order (their ``kind``, ``t_end``,
            ``dt``...).
        units: the model's unit system.
        output_units: kind of quantity -> unit of the results shown and written (the file's
            ``output_units``, a preset expanded; empty: the model's units).
    """

    path: pathlib.Path
    spec: s.ModelFile = dataclasses.field(repr=False)
    model: m.Model | None = dataclasses.field(repr=False)
    runs: dict[str, s.RunSpec]
    units: UnitSystem
    output_units: dict[str, str]
    _runner: object = dataclasses.field(repr=False, compare=False)

    def run(
        self,
        names=None,
        *,
        out=None,
        parquet: bool = False,
        excel: bool = False,
        figures: bool = False,
    ) -> dict[str, Result]:
        """Execute runs ``names`` (default all, with the runs they need) and return their
        results by name, in execution order; each :class:`~mixdyn.Result` shows its columns
        in the file's ``output_units`` (:meth:`mixdyn.Result.table`).

        Args:
            names: a run's name, a list of names, or None for every run.
            out: a folder to write each run's outputs to (``out/NAME/results.csv``,
                ``meta.json``...: what ``mixdyn run --out`` writes), or None.
            parquet: with ``out``, also write ``results.parquet``.
            excel: with ``out``, also write ``results.xlsx`` (a sweep's ``sweep.xlsx``;
                needs openpyxl: ``pip install "mixdyn[excel]"``).
            figures: with ``out``, also draw the plots and animations the runs ask for.

        Raises:
            FileError: a run or an output the file cannot have (named at its line).
            NumericalError: a run failed (with ``out``, its folder holds what it computed).
        """
        from . import outputs as o

        runner = self._runner
        names = [names] if isinstance(names, str) else names
        plans = runner.order(names or None)
        for plan in plans:  # ill-posed runs refused before anything computes
            runner.check_masses(plan)
            runner.mobility(plan)
        if out is None:
            results = runner.execute([p.name for p in plans])
        else:
            out = pathlib.Path(out)
            o.check_run_outputs(out, plans, figures, runner)
            if excel:
                from ..io.tables import excel_module

                excel_module(self.path, "writing")
                o.check_excel_rows(plans, self.path)
            painter = None
            if o.draws(runner, plans, figures):
                from ..viz.painter import Painter

                painter = Painter()
            outputs = o.Outputs(
                out, self.path, parquet=parquet, excel=excel, figures=figures, painter=painter
            )
            results = {}
            o.write_runs(runner, plans, outputs, "off", results)
        return {name: shown(r, self.output_units) for name, r in results.items()}


def shown(result, output_units: dict[str, str]):
    """``result`` (a :class:`~mixdyn.Result`) carrying ``output_units``, which its table,
    plots and written files use; any other result (a sweep's, a fit's) as it is."""
    if isinstance(result, Result) and output_units and result.output_units != output_units:
        return dataclasses.replace(result, output_units=dict(output_units))
    return result


def load(path: str | os.PathLike) -> LoadedFile:
    """Read a model file, build its model and check its runs (nothing is computed).

    Args:
        path: the model file (YAML).

    Returns:
        A :class:`LoadedFile`: ``.model``, ``.runs``, ``.units``, ``.output_units``, and
        ``.run()`` to execute its runs.

    Raises:
        FileError: unreadable file, bad YAML, a description of the wrong form, unknown
            names, wrong dimensions... (named at the file's line, like ``mixdyn check``).
    """
    from ..io.load import read
    from .runner import Runner

    path = pathlib.Path(path)
    spec = read(path)
    runner = Runner(spec)
    return LoadedFile(
        path=path,
        spec=spec,
        model=runner.model,
        runs={r.name: r for r in spec.runs},
        units=runner.b.units,
        output_units=dict(runner.output_units),
        _runner=runner,
    )


def run_file(
    path: str | os.PathLike,
    out=None,
    *,
    runs=None,
    parquet: bool = False,
    excel: bool = False,
    figures: bool = False,
) -> dict[str, Result]:
    """Run a model file's runs from Python: ``load(path).run(runs, out=out, ...)``.

    Args:
        path: the model file (YAML).
        out: a folder to write each run's outputs to, as ``mixdyn run --out`` (None: nothing
            written).
        runs: a run's name or a list of names (with the runs they need); None: every run.
        parquet, excel, figures: as for :meth:`LoadedFile.run`.

    Returns:
        The results by run name, in execution order (a :class:`~mixdyn.Result` per analysis,
        in the file's ``output_units``; a sweep's, a fit's or an optimization's own result).
    """
    return load(path).run(runs, out=out, parquet=parquet, excel=excel, figures=figures)


__all__ = ["LoadedFile", "load", "run_file", "shown"]

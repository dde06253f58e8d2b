"""``mixdyn run``'s job: a model file read, every run checked before any computes, the runs
run in the order of their dependencies and each written as it ends
(:func:`~.outputs.write_runs`), the figures drawn by the figure worker meanwhile.

Example::

    written, failed = run_job("examples/antonya.yaml", out=pathlib.Path("out"))
"""

from __future__ import annotations

import pathlib
import sys


def run_job(
    file,
    runs: list[str] | None = None,
    out: pathlib.Path = pathlib.Path("out"),
    *,
    parquet: bool = False,
    netcdf: bool = False,
    excel: bool = False,
    figures: bool = True,
    progress: bool | None = None,
) -> tuple[list[pathlib.Path], list[str]]:
    """Run a file's runs (or ``runs`` and the runs they need) and write them under ``out``.

    Everything that can be checked without computing is checked first: the formats asked for,
    the file, every output path and each run's masses and mobility. The file's warnings go to
    stderr.

    Args:
        file: the model file.
        runs: the runs to run; None: all.
        out: the output folder; each run writes ``out/NAME/``.
        parquet: also write ``results.parquet``.
        netcdf: also write each sweep as ``sweep.nc`` (needs xarray).
        excel: also write ``results.xlsx`` (a sweep's ``sweep.xlsx``; needs openpyxl).
        figures: write the plots and animations the runs ask for.
        progress: True: a bar per run following the simulated time; False: nothing; None: a
            line per run on a terminal, else the notice of the first compile
            (:func:`.console.compiling`).

    Returns:
        The files written, and the first line of each sweep with failed members (its other
        members are written).

    Raises:
        FileError: the file, an option or an output is wrong, before anything is computed.
        NumericalError: a run failed (what it computed up to then is written).
    """
    if netcdf:
        import importlib.util

        from ..io import FileError

        if importlib.util.find_spec("xarray") is None:
            raise FileError(
                "--netcdf needs xarray, which is not installed",
                file="mixdyn",
                hint="pip install 'mixdyn[xarray]' (or leave --netcdf out)",
            )
    # The figures' worker starts first: its imports (matplotlib) overlap reading the file and
    # the checks; it is closed again if the runs draw nothing.
    painter = None
    if figures:
        from ..viz.painter import Painter

        painter = Painter()
    from .console import clean, compiling
    from .outputs import Outputs, check_excel_rows, check_run_outputs, draws, write_runs

    try:
        from ..io import FileError, read
        from ..io.tables import excel_module, parquet_module
        from .checks import require_size
        from .runner import Runner

        if parquet:  # refused before anything runs
            parquet_module(file, "writing", "--parquet")
        if excel:
            excel_module(file, "writing", "--excel")
        spec = read(file)
        require_size(spec, file)
        runner = Runner(spec)
        for w in runner.b.readings.warnings:
            sys.stderr.write(f"{clean(file)}: warning: {clean(w)}\n")
        if not spec.runs:
            raise FileError(
                "the file has no runs", "runs", file=str(file), hint="add a runs: section"
            )
        plans = runner.order(runs or None)
        check_run_outputs(out, plans, figures, runner)
        if excel:
            check_excel_rows(plans, file)
        if painter is not None and not draws(runner, plans, figures):
            painter.abort()  # nothing to draw
            painter = None
        for plan in plans:  # fail fast on ill-posed runs, before any long computation
            runner.check_masses(plan)
            runner.mobility(plan)
    except BaseException:
        if painter is not None:
            painter.abort()  # nothing was drawn yet
        raise
    if progress is None:
        mode = "runs" if sys.stderr.isatty() else "off"
    else:
        mode = "steps" if progress else "off"
    outputs = Outputs(
        out, file, parquet=parquet, netcdf=netcdf, excel=excel, figures=figures, painter=painter
    )
    from ..runtime._command import import_ahead
    from ..runtime._programs import on_first_compile

    notice = progress is None and mode == "off"  # no line per run: what takes long is said

    def first_compile():
        if notice:
            compiling(file)
        import_ahead()

    on_first_compile(first_compile)
    try:
        written = write_runs(runner, plans, outputs, mode)
    finally:
        on_first_compile(None)
    return written, outputs.failed


__all__ = ["run_job"]

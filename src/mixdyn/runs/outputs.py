"""What ``mixdyn run`` writes: each run's folder, checked before anything runs, cleared of
the run's previous outputs as it starts (:func:`clear_outputs`) and written as the run ends,
by its kind (:meth:`.kinds.RunKind.write`); the figures drawn by the figure worker
(:class:`mixdyn.viz.painter.Painter`) while the next runs compute. A run that fails
numerically writes what it computed up to the failure, a ``meta.json`` saying
``status: failed``, with the failure's time and cause, and a ``report.html`` stating the
failure (:func:`write_failed`); a run that succeeds says ``status: ok``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import pathlib

from ..errors import NumericalError
from ..io._errors import FileError
from . import execute as _execute
from .console import RunProgress
from .kinds import kind_of


@dataclasses.dataclass
class Outputs:
    """Where and how a file's runs are written.

    Attributes:
        out: the output folder; each run writes ``out/NAME/``.
        file: the model file (named in each ``meta.json``).
        parquet: also write ``results.parquet``.
        netcdf: also write each sweep as ``sweep.nc``.
        excel: also write ``results.xlsx`` (a sweep's ``sweep.xlsx``).
        figures: write the plots and animations the runs ask for.
        painter: the figure worker (:class:`~mixdyn.viz.painter.Painter`), None where
            nothing is drawn.
        failed: the first line of each sweep with failed members (its members are written).
        reports: the runs' reports (:class:`mixdyn.viz.report.Report`) waiting for their
            figures: written once the painter has drawn them.
    """

    out: pathlib.Path
    file: str | pathlib.Path
    parquet: bool = False
    netcdf: bool = False
    excel: bool = False
    figures: bool = True
    painter: object | None = None
    failed: list[str] = dataclasses.field(default_factory=list)
    reports: list = dataclasses.field(default_factory=list)

    def folder(self, plan) -> pathlib.Path:
        """The run's folder."""
        return pathlib.Path(self.out) / plan.name

    def add_report(self, report) -> list[pathlib.Path]:
        """Write a run's report now where no figures are drawn (returns its path), else keep
        it in :attr:`reports` until the painter has drawn them (returns nothing yet)."""
        if self.painter is None:
            return [report.write()]
        self.reports.append(report)
        return []


# --------------------------------------------------------------------------- output paths
def _refuse(path, problem: str, option: str, hint: str) -> None:
    raise FileError(problem, option, file=str(path), hint=hint)


def _existing_ancestor(path: pathlib.Path, option: str) -> pathlib.Path:
    """The nearest folder above ``path`` that exists (refusing a file on the way)."""
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if parent.exists() and not parent.is_dir():
        _refuse(parent, "is a file, not a folder", option, "give a path inside a folder")
    return parent


def check_output(path: pathlib.Path, option: str, *, folder: bool = False) -> None:
    """Refuse, before anything is computed, an output that cannot be written: a folder where a
    file is wanted or the reverse, a parent that is a file, no permission to write.

    Args:
        path: the file (or with ``folder``, the folder) to be written.
        option: the command-line option that named it, for the message.
        folder: whether ``path`` is a folder (created if missing).

    Raises:
        FileError: the output cannot be written, named by ``option``.
    """
    path = pathlib.Path(path)
    if path.exists() or path.is_symlink():
        if folder and not path.is_dir():
            _refuse(path, "exists and is not a folder", option, "give a folder for the results")
        if not folder and path.is_dir():
            _refuse(path, "is a folder", option, "give a file name")
        if not os.access(path, os.W_OK | (os.X_OK if folder else 0)):
            _refuse(path, "is not writable", option, "check its permissions or write elsewhere")
        return
    parent = _existing_ancestor(path, option)
    if not os.access(parent, os.W_OK | os.X_OK):
        _refuse(path, f"cannot be created: {parent} is not writable", option, "write elsewhere")


def check_run_outputs(out: pathlib.Path, plans, figures: bool, runner) -> None:
    """The output folder and every file the runs will write (:meth:`.kinds.RunKind.output_files`),
    checked before running."""
    check_output(out, "--out", folder=True)
    for plan in plans:
        folder = out / plan.name
        check_output(folder, "--out", folder=True)
        for name in kind_of(plan).output_files(runner, plan, figures):
            check_output(folder / name, "--out")


def check_excel_rows(plans, file) -> None:
    """Refuse, before anything is computed, an Excel sheet longer than Excel holds
    (:data:`mixdyn.io.results.EXCEL_ROWS`): a run's output times, a sweep's members times
    their output times.

    Raises:
        FileError: the first run whose table is too long, named as ``--excel``.
    """
    from ..io.results import EXCEL_ROWS

    for plan in plans:
        own = getattr(plan, "member_times", None)
        if own is not None:
            rows = sum(len(t) for t in own)
        else:
            rows = len(plan.times) * getattr(plan, "members", 1)
        if rows + 1 > EXCEL_ROWS:
            raise FileError(
                f"run {plan.name!r} writes {rows:,} rows, more than an Excel sheet holds "
                f"({EXCEL_ROWS - 1:,})",
                "--excel",
                file=str(file),
                hint="write fewer output times, or leave --excel out (the CSV has them all)",
            )


def animation_targets(outputs, file) -> list[pathlib.Path]:
    """The files ``mixdyn animate --output`` writes, checked: a GIF, an MP4 (with ffmpeg) or
    an HTML page each; a name without a suffix gives both ``NAME.gif`` and ``NAME.html``.

    Args:
        outputs: the ``--output`` paths.
        file: the model file, for the messages.

    Raises:
        FileError: a type that cannot be written, or an output that cannot be written there.
    """
    import shutil

    targets = []
    for o in outputs:
        if o.suffix == "":
            targets += [o.with_suffix(".gif"), o.with_suffix(".html")]
        elif o.suffix.lower() == ".mp4" and shutil.which("ffmpeg") is None:
            raise FileError(
                "writing MP4 needs ffmpeg, which is not installed",
                "--output",
                file=str(file),
                hint="write a .gif or .html instead",
            )
        elif o.suffix.lower() in (".gif", ".mp4", ".html"):
            targets.append(o)
        else:
            raise FileError(
                f"cannot write an animation to {o.name!r}",
                "--output",
                file=str(file),
                hint="use .gif, .mp4 or .html",
            )
    for target in targets:
        check_output(target, "--output")
    return targets


#: The files a run writes in some invocations only (``--parquet``, ``--netcdf``,
#: ``--excel``; ``impacts.csv``: a run with rigid contacts), by a file its kind always writes.
_FORMAT_FILES = {
    "results.csv": ("results.parquet", "results.xlsx", "impacts.csv"),
    "table.csv": ("table.parquet", "sweep.nc", "sweep.xlsx"),
}


def run_outputs(runner, plan) -> list[str]:
    """Every file the run writes in its folder in any invocation: its kind's
    (:meth:`.kinds.RunKind.output_files`, figures included) and those of the optional
    formats (``results.parquet``, ``results.xlsx``; a sweep's ``table.parquet``,
    ``sweep.nc`` and ``sweep.xlsx``)."""
    names = list(kind_of(plan).output_files(runner, plan, True))
    for name in list(names):
        names += [n for n in _FORMAT_FILES.get(name, ()) if n not in names]
    return names


def clear_outputs(runner, plan, folder: pathlib.Path) -> None:
    """Remove the run's previous outputs from its folder before it runs, so that a failed
    run leaves no earlier answer beside its own: only the files it writes
    (:func:`run_outputs`), and only files (a folder of that name is left as it is)."""
    for name in run_outputs(runner, plan):
        path = folder / name
        if path.is_symlink() or path.is_file():
            path.unlink()


def write_failed(runner, plan, error, outputs: Outputs) -> list[pathlib.Path]:
    """A failed run's folder: the states computed up to the failure, ``meta.json`` with
    ``status: failed``, the failure's time and cause (:func:`mixdyn.io.results.write_failure`)
    and ``report.html`` stating them (:func:`.run_reports.failure_report`)."""
    from ..io.results import run_settings, write_failure
    from .run_reports import REPORT_HTML, failure_report

    extra = {"file": str(outputs.file), "run": plan.name, "kind": plan.spec.kind}
    extra["report"] = REPORT_HTML
    written = write_failure(
        error,
        outputs.folder(plan),
        settings=run_settings(plan.spec),
        extra=extra,
        output_units=runner.output_units,
        model=runner.model,
    )
    return [*written, failure_report(runner, plan, error, outputs).write()]


def draws(runner, plans, figures: bool) -> bool:
    """Whether any of the runs draws a figure or an animation (with ``figures``)."""
    return figures and any(kind_of(p).draws(runner, p) for p in plans)


# --------------------------------------------------------------------------- writing
def write_runs(
    runner, plans, outputs: Outputs, mode: str, results: dict | None = None
) -> list[pathlib.Path]:
    """Execute the plans, writing each run's outputs as it ends. ``mode``: ``"off"``,
    ``"runs"`` (a line per run) or ``"steps"`` (a bar following the simulated time);
    ``results``: a dict given receives each run's result by name.

    The figures and animations are drawn by ``outputs.painter`` (None: no figures), a worker
    process that draws while the next runs compute (matplotlib is imported there while the
    runs are checked, on another core); a failure there is raised here as if drawn in turn.
    The painter is closed on return. A sweep with failed members adds its line to
    ``outputs.failed``.

    Returns:
        The files written.
    """
    written: list[pathlib.Path] = []
    painter = outputs.painter
    by_name = {p.name: p for p in plans}
    running = []  # the run started last
    try:
        with RunProgress(plans, mode) as progress:

            def start(plan):
                running[:] = [plan]
                clear_outputs(runner, plan, outputs.folder(plan))
                progress.start(plan)

            def done(plan, result, seconds):
                progress.done(plan)
                if results is not None:
                    results[plan.name] = result
                kind = kind_of(plan)
                written.extend(kind.write(runner, plan, result, seconds, outputs))
                progress.say(kind.done(plan, result, seconds, outputs.folder(plan)))

            try:
                _execute.execute(
                    runner,
                    [p.name for p in plans],
                    progress=progress.hook,
                    on_start=start,
                    on_done=done,
                )
            except NumericalError as e:  # in the run, or in writing it (a NaN refused)
                plan = by_name.get(getattr(e, "run", None)) or (running or [None])[0]
                if plan is not None:
                    written.extend(write_failed(runner, plan, e, outputs))
                raise
        if painter is not None:  # in order: the first failure is raised, as if drawn in turn
            written.extend(painter.results())
        written.extend(_reports(outputs))
    except KeyboardInterrupt:
        raise
    except Exception:  # a run failed: its predecessors' figures and reports are still written
        if painter is not None:
            with contextlib.suppress(Exception):
                painter.results()
        with contextlib.suppress(Exception):
            _reports(outputs)
        raise
    finally:
        if painter is not None:
            painter.close()
    return written


def _reports(outputs: Outputs) -> list[pathlib.Path]:
    """Write the reports waiting for their figures (:attr:`Outputs.reports`)."""
    reports, outputs.reports = outputs.reports, []
    return [r.write() for r in reports]


def write_study_run(
    runner, plan, run, seconds: float, outputs: Outputs, key: str, details: dict, figure: str
) -> list[pathlib.Path]:
    """The run at a fit's estimate or an optimum, written like any run (``results.csv``,
    ``meta.json``), the study's numbers under ``key`` in its ``meta.json`` and its figure
    ``figure`` named there when drawn."""
    from ..io.results import run_settings, write_result

    extra = {
        "file": str(outputs.file),
        "run": plan.name,
        "kind": plan.spec.kind,
        "wall_time_s": round(seconds, 3),
        key: details,
        "figures": [figure] if outputs.painter is not None else [],
        "report": "report.html",
    }
    return write_result(
        run,
        outputs.folder(plan),
        parquet=outputs.parquet,
        excel=outputs.excel,
        settings=run_settings(plan.base.spec),
        extra=extra,
        output_units=runner.output_units,
        points=getattr(plan.base.spec, "outputs", ()),
    )


__all__ = [
    "Outputs",
    "animation_targets",
    "check_excel_rows",
    "check_output",
    "check_run_outputs",
    "clear_outputs",
    "draws",
    "run_outputs",
    "write_failed",
    "write_runs",
    "write_study_run",
]

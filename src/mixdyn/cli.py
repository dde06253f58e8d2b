"""The ``mixdyn`` command line: a thin shell over :mod:`mixdyn.io` and :mod:`mixdyn.viz`.

Commands: ``check``, ``show``, ``run``, ``plot``, ``animate``, ``schema``, ``dump``; ``--help``
on each.

Exit codes: 0 success; 2 bad input (one line on stderr: ``FILE:LINE: element: problem; what to
do``); 1 a numerical failure (singularity, divergence) with its time and cause. Every input
error that can be found without computing is found by ``mixdyn check`` and by ``mixdyn run``
before it computes anything (run settings, options, output paths). A model file is a regular
file of UTF-8 text of at most 20 MB (:data:`mixdyn.io._yaml.MAX_BYTES`).

Traced and compiled programs are kept between invocations (per model structure: a file with
other numbers reuses them), in ``$MIXDYN_CACHE_DIR`` or ``$XDG_CACHE_HOME/mixdyn/jax``
(``~/.cache/mixdyn/jax``); set ``MIXDYN_NO_CACHE=1`` to turn that off (see
:mod:`mixdyn.runtime`). ``MIXDYN_DEBUG=1`` shows tracebacks of unexpected errors.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import re
import sys
import time
from typing import Annotated

import typer

from .runtime._private import exit_now, roomy, use_roomy_frames

app = typer.Typer(
    name="mixdyn",
    help="Kinematics and forward, inverse and mixed dynamics of planar mechanisms, from model "
    "files (YAML).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)

EXIT_OK, EXIT_NUMERICAL, EXIT_INPUT = 0, 1, 2

FileArg = Annotated[pathlib.Path, typer.Argument(help="The model file (YAML).", show_default=False)]


# --------------------------------------------------------------------------- plumbing
#: Characters never sent to the terminal as they are: C0 and C1 controls (escape sequences),
#: DEL, and the bidirectional overrides that reorder what is shown.
_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def clean(text) -> str:
    """``text`` with every control character (except newlines and tabs) shown as an escape
    (``\\x1b``), so that names and paths from a file cannot drive the terminal."""
    return _CONTROL.sub(lambda m: ascii(m.group())[1:-1], str(text))


def _say(text: str = "") -> None:
    from rich.console import Console

    Console(soft_wrap=True, highlight=False).print(clean(text))


def _esc(text) -> str:
    """User text (names, paths) made safe inside rich markup and on the terminal."""
    from rich.markup import escape

    return escape(clean(text))


def _fail(code: int, line: str) -> None:
    """Print one line on stderr and exit with ``code``."""
    sys.stderr.write(" ".join(clean(line).split()) + "\n")
    sys.stderr.flush()
    raise typer.Exit(code)


@contextlib.contextmanager
def _guard(file: pathlib.Path | str | None):
    """Turn mixdyn's errors into one line and an exit code."""
    from pydantic import ValidationError

    from .errors import AssemblyError, MixdynError, ModelError, NumericalError
    from .io import FileError

    where = str(file) if file is not None else "mixdyn"
    try:
        yield
    except typer.Exit:
        raise
    except FileError as e:
        _fail(EXIT_INPUT, e.one_line())
    except AssemblyError as e:  # no start closes the joints: the description is at fault
        _fail(
            EXIT_INPUT,
            f"{getattr(e, 'file', where)}: the start cannot be assembled: {e}; check the "
            "geometry, q0, initial and hold",
        )
    except NumericalError as e:
        run = getattr(e, "run", None)
        what = f"run {run!r}: " if run else ""
        _fail(
            EXIT_NUMERICAL,
            f"{getattr(e, 'file', where)}: {what}numerical failure ({type(e).__name__}): {e}",
        )
    except ModelError as e:
        _fail(EXIT_INPUT, f"{where}: {e}")
    except MixdynError as e:
        _fail(EXIT_NUMERICAL, f"{where}: {type(e).__name__}: {e}")
    except ValidationError as e:
        first = e.errors()[0]
        loc = ".".join(str(p) for p in first["loc"])
        _fail(EXIT_INPUT, f"{where}: {loc}: {first['msg']}")
    except KeyboardInterrupt:
        _fail(130, f"{where}: interrupted")
    except OSError as e:  # a file that cannot be read or written: the path is the fault
        name = e.filename if e.filename is not None else where
        _fail(EXIT_INPUT, f"{name}: {e.strerror or e}; check the path and its permissions")
    except RecursionError:
        _fail(EXIT_INPUT, f"{where}: the input is nested too deeply; simplify it")
    except Exception as e:
        if os.environ.get("MIXDYN_DEBUG"):
            raise
        _fail(
            EXIT_NUMERICAL,
            f"{where}: internal error ({type(e).__name__}: {e}); please report it "
            "(MIXDYN_DEBUG=1 shows the traceback)",
        )


def _version(value: bool):
    if value:
        from . import __version__

        typer.echo(f"mixdyn {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_version, is_eager=True, help="Show the version and exit."
        ),
    ] = False,
):
    """Kinematics and forward, inverse and mixed dynamics of planar mechanisms.

    A model file (YAML) describes the mechanism in one unit system and named runs of analyses
    on it; see examples/ and `mixdyn schema`.
    """


def configure_cache() -> str | None:
    """Turn on mixdyn's persistent caches (see the module's documentation) unless
    ``MIXDYN_NO_CACHE`` is set (:func:`mixdyn.set_cache`).

    Returns:
        The cache folder, or None when turned off.
    """
    from .runtime._programs import configure_from_env

    return configure_from_env()


# --------------------------------------------------------------------------- output paths
def _refuse(path, problem: str, option: str, hint: str) -> None:
    from .io import FileError

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


def _check_run_outputs(out: pathlib.Path, plans, figures: bool, runner) -> None:
    """The output folder and every file the runs will write, checked before running."""
    check_output(out, "--out", folder=True)
    for plan in plans:
        folder = out / plan.name
        check_output(folder, "--out", folder=True)
        if plan.spec.kind == "sweep":
            names = ["members.csv", "table.csv", "meta.json"]
        elif plan.spec.kind == "identify":
            names = ["fit.csv", "results.csv", "meta.json"] + (["fit.png"] if figures else [])
        elif plan.spec.kind == "optimize":
            names = ["optimum.csv", "results.csv", "meta.json"]
            names += ["optimize.png"] if figures else []
        else:
            names = ["results.csv", "meta.json"]
        if figures:
            plots = plan.spec.plots if plan.spec.kind == "sweep" else runner.plots(plan)
            names += [p.file for p in plots]
            if getattr(plan.spec, "animation", None) is not None:
                names.append(plan.spec.animation.file)
        for name in names:
            check_output(folder / name, "--out")


def _require_size(spec, file) -> None:
    """Refuse, before building anything, a model too large to check in bounded time."""
    from .analysis._structure import require_checkable

    require_checkable(len(spec.bodies), str(file))


def _in_unit(table, units: dict, spec: str, results, k: int):
    """``table`` with the column of ``spec`` (``COLUMN=UNIT``) converted from its written
    unit (meta.json, or the Parquet file's) into UNIT; a unit of another dimension, an unknown
    column or unit is an input error naming ``--unit``."""
    from .io import FileError
    from .io.quantities import QuantityError, exponents, factor
    from .units import SI

    col, sep, target = spec.partition("=")
    col, target = col.strip(), target.strip()
    where = dict(file=str(results), hint="write --unit COLUMN=UNIT, e.g. crank.phi=deg")
    if not sep or not col or not target:
        raise FileError(f"{spec!r} is not COLUMN=UNIT", f"--unit {k + 1}", **where)
    if col not in table.columns:
        raise FileError(f"no column {col!r}", f"--unit {k + 1}", **where)
    source = units.get(col) or ""
    try:
        same = exponents(source or "1") == exponents(target)
        scale = factor(source or "1", None, SI) / factor(target, None, SI)
    except QuantityError as e:
        raise FileError(f"{target!r}: {e.problem}", f"--unit {k + 1}", **where) from None
    if not same:
        raise FileError(
            f"column {col!r} is in {source or 'no unit'}, which {target!r} is not a unit of",
            f"--unit {k + 1}",
            **where,
        )
    table = table.copy()
    table[col] = table[col] * scale
    return table, {**units, col: target}


# --------------------------------------------------------------------------- show
@app.command()
def show(
    file: FileArg,
    output: Annotated[
        pathlib.Path | None,
        typer.Option(
            "--output", "-o", help="The drawing: .png, .svg, .pdf or .html (default FILE.png)."
        ),
    ] = None,
):
    """Draw the model at its assembled start (bodies, joints, ground points and their names),
    without running an analysis."""
    with _guard(file):
        from . import analysis as an
        from .io import FileError, read
        from .runs import Runner
        from .runs.runner import start_q
        from .viz.show import SHOW_SUFFIXES, draw

        target = output or pathlib.Path(file).with_suffix(".png")
        if target.suffix.lower() not in SHOW_SUFFIXES:
            raise FileError(
                f"cannot draw to {target.name!r}",
                "--output",
                file=str(file),
                hint=f"use {', '.join(SHOW_SUFFIXES)}",
            )
        check_output(target, "--output")
        spec = read(file)
        _require_size(spec, file)
        model = Runner(spec).model
        asm = an.assemble(model, start_q(model), hold=spec.assembly.hold)
        draw(model, asm.q, target, title=f"{model.name} at its assembled start")
        _say(f"wrote {_esc(target)}")


# --------------------------------------------------------------------------- check
@app.command()
def check(file: FileArg):
    """Check a model file: form, names, units, expressions, degrees of freedom, and that
    every run is well posed (options, steps, outputs, laws). Prints the degrees of freedom,
    redundant equations, the driver/DOF balance of each run and warnings; changes nothing.
    A model file is UTF-8 text of at most 20 MB with at most 50,000 bodies (checked at
    about 2 s and 50 MB per 1,000 bodies)."""
    with _guard(file):
        from . import analysis as an
        from .io import read
        from .io import schema as s
        from .runs import Runner
        from .runs.runner import start_q

        spec = read(file)
        _require_size(spec, file)
        runner = Runner(spec)
        model = runner.model
        asm = an.assemble(model, start_q(model), hold=spec.assembly.hold)
        report = an.degrees_of_freedom(model, asm.q)
        _say(f"[bold]{_esc(file)}[/bold]: {_esc(model.summary())}")
        _say(f"assembled start: residual {asm.residual:.2e} in {asm.iterations} iteration(s)")
        _say(f"degrees of freedom: {report.dof}")
        _say(f"redundant joint equations: {', '.join(report.redundant) or 'none'}")
        _say(
            f"model drivers: {report.n_drivers}"
            + (
                f" (redundant: {', '.join(report.redundant_drivers)})"
                if report.redundant_drivers
                else ""
            )
        )
        warnings = _warnings(spec, model, report)
        for plan in runner.order():
            r = plan.spec
            if r.kind != "kinematic":
                runner.check_masses(plan)
            rep = runner.mobility(plan)
            runner.check_solvable(plan)
            if r.kind == "optimize":
                o = r.objective
                _say(
                    f"run [bold]{_esc(r.name)}[/bold] (optimize with {_esc(r.run)}): "
                    f"{r.sense} the {o.reduce} of {_esc(o.column)} over {_esc(', '.join(r.vary))}"
                )
                continue
            if r.kind == "identify":
                _say(
                    f"run [bold]{_esc(r.name)}[/bold] (identify with {_esc(r.run)}): "
                    f"{_esc(', '.join(r.fit))} from {len(plan.times)} times of "
                    f"{_esc(', '.join(plan.measured))}"
                )
                continue
            if r.kind == "sweep":
                how = "grid" if r.sampling == "grid" else f"Latin hypercube, seed {r.seed}"
                _say(
                    f"run [bold]{_esc(r.name)}[/bold] (sweep of {_esc(r.run)}): "
                    f"{plan.members} members ({how}) over {_esc(', '.join(r.vary))}"
                )
                continue
            extra = ""
            if isinstance(r, s.MixedRunSpec):
                extra = f", unknown {', '.join(r.unknown)}, solver {r.solver}"
            n = rep.n_drivers
            state = "balanced" if n == rep.dof else f"{rep.dof - n} free degree(s) of freedom"
            _say(
                f"run [bold]{_esc(r.name)}[/bold] ({r.kind}): {len(plan.times)} output times "
                f"{plan.times[0]:g}..{plan.times[-1]:g} {model.units.time}, "
                f"{n} prescribed motion(s) for {rep.dof} DOF ({state}){extra}"
            )
        for w in warnings:
            _say(f"[yellow]warning[/yellow]: {_esc(w)}")
        _say("[green]ok[/green]")


def _warnings(spec, model, report) -> list[str]:
    out = []
    if not spec.runs:
        out.append("the file has no runs; `mixdyn run` has nothing to do")
    if report.redundant:
        out.append(
            f"redundant joint equations {', '.join(report.redundant)} are dropped by the solvers "
            "(their reactions are not unique)"
        )
    used = set()
    for j in (*model.joints, *model.drivers, *model.forces):
        used.update(j.body_indices())
    for i, b in enumerate(model.bodies):
        if i not in used:
            out.append(f"body {b.name!r} is not connected to anything")
    if model.forces and spec.runs and all(r.kind == "kinematic" for r in spec.runs):
        out.append("the forces have no effect: every run is kinematic")
    return out


# --------------------------------------------------------------------------- run
@app.command()
def run(
    file: FileArg,
    runs: Annotated[
        list[str] | None,
        typer.Option("--run", "-r", help="Run only this run (and the runs it needs); repeatable."),
    ] = None,
    out: Annotated[
        pathlib.Path,
        typer.Option("--out", "-o", help="Output folder; each run writes OUT/NAME/."),
    ] = pathlib.Path("out"),
    parquet: Annotated[bool, typer.Option("--parquet", help="Also write results.parquet.")] = False,
    netcdf: Annotated[
        bool,
        typer.Option(
            "--netcdf",
            help="Also write each sweep as sweep.nc: a labelled array on (member, t) with the "
            "varied numbers as coordinates (needs xarray: pip install mixdyn[xarray]).",
        ),
    ] = False,
    figures: Annotated[
        bool,
        typer.Option(
            "--figures/--no-figures", help="Write the plots and animations the file asks for."
        ),
    ] = True,
    progress: Annotated[
        bool | None,
        typer.Option(
            "--progress/--no-progress",
            help="--progress: a bar per run following the simulated time (the bar is a "
            "callback inside the compiled loop, which JAX cannot keep between invocations: "
            "each invocation compiles the integrator again, once); --no-progress: nothing. "
            "Default: one line per run with its elapsed time, when the terminal is "
            "interactive.",
        ),
    ] = None,
):
    """Run the file's runs (or those named by --run) and write, per run, OUT/NAME/results.csv
    (columns t, {body}.x ..., {joint}.Fx ..., driver efforts and unknown forces by name),
    OUT/NAME/meta.json (units of every column, solver, tolerances, counters, version) and the
    figures and animation the run asks for."""
    from .runtime import _command, _programs

    # The programs this job used last time are read from the cache beside the checks below
    # (from the import of mixdyn on, where it could read the command line: _command.job_tag).
    with _programs.job(_command.run_tag(file, runs)):
        _run(file, runs, out, parquet, figures, progress, netcdf)


def _run(file, runs, out, parquet, figures, progress, netcdf=False):
    if netcdf:
        import importlib.util

        if importlib.util.find_spec("xarray") is None:
            _fail(
                2,
                "mixdyn: --netcdf needs xarray, which is not installed; "
                "pip install 'mixdyn[xarray]' (or leave --netcdf out)",
            )
    # The figures' worker starts first: its imports (matplotlib) overlap reading the file and
    # the checks; it is closed again if the runs draw nothing.
    painter = _Painter() if figures else None
    with _guard(file):
        try:
            from .io import read
            from .runs import Runner

            spec = read(file)
            _require_size(spec, file)
            runner = Runner(spec)
            if not spec.runs:
                from .io import FileError

                raise FileError(
                    "the file has no runs", "runs", file=str(file), hint="add a runs: section"
                )
            plans = runner.order(runs or None)
            _check_run_outputs(out, plans, figures, runner)
            drawing = figures and any(
                getattr(p.spec, "plots", None)
                or runner.plots(p)
                or getattr(p.spec, "animation", None) is not None
                or p.spec.kind in ("identify", "optimize")
                for p in plans
            )
            if painter is not None and not drawing:
                painter.abort()  # nothing to draw
                painter = None
            for plan in plans:  # fail fast on ill-posed runs, before any long computation
                if plan.spec.kind != "kinematic":
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
        failed: list = []  # sweeps with failed members
        written = _execute(
            runner, plans, out, parquet, figures, painter, mode, file, failed, netcdf
        )
        _say(f"wrote {len(written)} file(s) under {_esc(out)}")
        if failed:
            plan, res = failed[0]
            errors = res.sweep.errors
            i = min(errors)
            e = errors[i]
            at = f" at t = {e.time:g}" if getattr(e, "time", None) is not None else ""
            _fail(
                EXIT_NUMERICAL,
                f"{file}: run {plan.name!r}: {len(errors)} of {plan.members} members failed "
                f"(first: member {i}, {plan.describe(i)}{at}: {type(e).__name__}: "
                f"{getattr(e, 'message', None) or e}); the others are written, each member's "
                f"outcome in {pathlib.Path(out) / plan.name / 'members.csv'}",
            )


def _execute(runner, plans, out, parquet, figures, painter, mode, file, failed=None, netcdf=False):
    """Execute the plans, writing each run's outputs as it ends. ``mode``: ``"off"``,
    ``"runs"`` (a line per run) or ``"steps"`` (a bar following the simulated time).

    The figures and animations are drawn by ``painter`` (None: no figures), a worker process
    that draws while the next runs compute (:class:`_Painter`: matplotlib is imported there
    while the runs are checked, on another core); a failure there is raised here as if drawn
    in turn. The painter is closed on return. A sweep with failed members is appended to
    ``failed`` as ``(plan, result)``."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        Progress,
        SpinnerColumn,
        TaskProgressColumn,
        TextColumn,
        TimeElapsedColumn,
    )

    from .io.results import run_settings, write_frame, write_result

    written = []

    def _study_written(plan, run, seconds, folder, key, details, painter):
        """The run at a fit's estimate or an optimum written like any run, the study's
        numbers under ``key`` in its meta.json."""
        figure = {"fit": "fit.png", "optimize": "optimize.png"}[key]
        extra = {
            "file": str(file),
            "run": plan.name,
            "kind": plan.spec.kind,
            "wall_time_s": round(seconds, 3),
            key: details,
            "figures": [figure] if painter is not None else [],
        }
        return write_result(
            run,
            folder,
            parquet=parquet,
            settings=run_settings(plan.base.spec),
            extra=extra,
            output_units=runner.output_units,
            points=getattr(plan.base.spec, "outputs", ()),
        )

    def _optimum_done(plan, result, seconds, folder, painter):
        import numpy as np

        o, r = result.optimum, plan.spec
        details = {
            "objective": r.objective.model_dump(),
            "sense": r.sense,
            "parameters": list(o.params),
            "optimum": o.values,
            "start": o.start,
            "bounds": o.bounds,
            "gradient": o.gradient,
            "objective_start": o.objective_start,
            "objective_optimum": o.objective,
            "history": o.history,
            "iterations": o.iterations,
            "evaluations": o.evaluations,
            "message": o.message,
        }
        files = _study_written(plan, result.result, seconds, folder, "optimize", details, painter)
        files.append(write_frame(o.table(), folder / "optimum.csv"))
        if painter is not None:
            from .viz.plots import result_columns

            col = r.objective.column
            first, units = result_columns(result.first, [col])
            best, _ = result_columns(result.result, [col])
            painter.draw(
                "optimum",
                np.asarray(o.history),
                np.asarray(plan.times),
                np.asarray(first[col]),
                np.asarray(best[col]),
                folder / "optimize.png",
                column=col,
                reduce=r.objective.reduce,
                units=units,
                title=f"{plan.name}: {r.sense} the {r.objective.reduce} of {col}",
            )
        return files

    def _fit_done(plan, result, seconds, folder, painter):
        import numpy as np

        f = result.fit
        details = {
            "parameters": list(f.params),
            "estimate": f.values,
            "std_dev": f.deviations,
            "start": f.start,
            "chi2_reduced": f.chi2,
            "evaluations": f.evaluations,
            "message": f.message,
            "noise": plan.noise,
        }
        files = _study_written(plan, result.result, seconds, folder, "fit", details, painter)
        files.append(write_frame(f.table(), folder / "fit.csv"))
        if painter is not None:
            from .viz.plots import result_columns

            cols, units = result_columns(result.result, list(plan.measured))
            painter.draw(
                "fit",
                np.asarray(plan.times),
                {k: np.asarray(v) for k, v in plan.measured.items()},
                {k: np.asarray(cols[k]) for k in plan.measured},
                folder / "fit.png",
                units=units,
                title=f"{plan.name}: measured and fitted ({', '.join(f.params)})",
            )
        return files

    def _sweep_done(runner, plan, result, seconds, folder, painter):
        from .io.results import write_sweep

        files = write_sweep(
            result,
            folder,
            parquet=parquet,
            netcdf=netcdf,
            settings=run_settings(plan.spec),
            extra={
                "file": str(file),
                "run": plan.name,
                "wall_time_s": round(seconds, 3),
                "figures": [p.file for p in plan.spec.plots] if figures else [],
                "base_settings": run_settings(plan.base.spec),
            },
        )
        if painter is not None:
            _sweep_figures(plan, result, folder, painter)
        if result.sweep.errors and failed is not None:
            failed.append((plan, result))
        return files

    console = Console(stderr=True)
    if mode == "steps" and not console.is_terminal:
        mode = "log"  # no bar off a terminal: a plain line every few seconds instead
    columns = (
        SpinnerColumn(),
        TextColumn("{task.description}"),
        BarColumn(),
        TaskProgressColumn(),
        TimeElapsedColumn(),
    )
    disable = mode in ("off", "log")
    drawing = painter is not None
    try:
        with Progress(*columns, console=console, disable=disable, transient=False) as bar:
            tasks = {}
            for plan in plans:
                span = float(plan.times[-1] - plan.times[0]) or 1.0
                if plan.spec.kind == "sweep":  # a bar of members, on a terminal
                    total = plan.members
                    label = f"{plan.name} (sweep of {plan.base.name}: {total} members)"
                elif plan.spec.kind in ("identify", "optimize"):
                    total, label = None, f"{plan.name} ({plan.spec.kind} with {plan.base.name})"
                else:
                    total = span if mode == "steps" else None
                    label = f"{plan.name} ({plan.spec.kind})"
                tasks[plan.name] = bar.add_task(label, total=total, start=False)

            def hook(plan):
                if plan.spec.kind == "sweep":
                    if mode == "log":
                        return _members_log(plan)
                    task = tasks[plan.name]
                    return lambda i: bar.advance(task)
                if mode not in ("steps", "log") or plan.spec.kind not in ("forward", "mixed"):
                    return None
                if mode == "log":
                    return _progress_log(plan)
                task, t0 = tasks[plan.name], float(plan.times[0])

                def at(t):
                    bar.update(task, completed=float(t) - t0)

                return at

            def done(plan, result, seconds):
                total = bar.tasks[tasks[plan.name]].total or 1.0
                bar.update(tasks[plan.name], total=total, completed=total)
                folder = pathlib.Path(out) / plan.name
                if plan.spec.kind == "sweep":
                    written.extend(_sweep_done(runner, plan, result, seconds, folder, painter))
                    console.print(
                        f"{plan.name}: sweep of {plan.base.name}, {plan.members} members "
                        f"({len(result.sweep.errors)} failed), {seconds:.2f} s -> {folder}",
                        highlight=False,
                        soft_wrap=True,
                    )
                    return
                if plan.spec.kind == "optimize":
                    written.extend(_optimum_done(plan, result, seconds, folder, painter))
                    o = result.optimum
                    console.print(
                        f"{plan.name}: optimize, {plan.spec.objective.reduce} of "
                        f"{plan.spec.objective.column} {o.objective_start:.6g} -> "
                        f"{o.objective:.6g} in {o.iterations} iterations, {seconds:.2f} s -> "
                        f"{folder}",
                        highlight=False,
                        soft_wrap=True,
                    )
                    return
                if plan.spec.kind == "identify":
                    written.extend(_fit_done(plan, result, seconds, folder, painter))
                    f = result.fit
                    console.print(
                        f"{plan.name}: identify, {len(f.params)} number(s), chi-square "
                        f"{f.chi2:.3g}, {f.evaluations} runs, {seconds:.2f} s -> {folder}",
                        highlight=False,
                        soft_wrap=True,
                    )
                    return
                figs = [p.file for p in runner.plots(plan)] if figures else []
                anim = []
                if figures and plan.spec.animation is not None:
                    a = plan.spec.animation
                    anim = [a.file] + (
                        [str(pathlib.Path(a.file).with_suffix(".html"))] if a.html else []
                    )
                written.extend(
                    write_result(
                        result,
                        folder,
                        parquet=parquet,
                        settings=run_settings(plan.spec),
                        output_units=runner.output_units,
                        points=plan.spec.outputs,
                        extra={
                            "file": str(file),
                            "run": plan.name,
                            "wall_time_s": round(seconds, 3),
                            "figures": figs,
                            "animation": anim,
                        },
                    )
                )
                if drawing:
                    _figures(runner, plan, result, folder, painter)
                console.print(
                    f"{plan.name}: {result.kind}, {len(result.t)} rows, {seconds:.2f} s -> "
                    f"{folder}",
                    highlight=False,
                    soft_wrap=True,
                )

            runner.execute(
                [p.name for p in plans],
                progress=hook,
                on_start=lambda plan: bar.start_task(tasks[plan.name]),
                on_done=done,
            )
        if painter is not None:  # in order: the first failure is raised, as if drawn in turn
            written.extend(painter.results())
    except KeyboardInterrupt:
        raise
    except Exception:  # a run failed: its predecessors' figures are still written
        if painter is not None:
            with contextlib.suppress(Exception):
                painter.results()
        raise
    finally:
        if painter is not None:
            painter.close()
    return written


class _Painter:
    """Draws the figures and animations of ``mixdyn run`` in a worker process
    (:mod:`mixdyn.runtime._worker`: matplotlib, no JAX) while the runs compute, and here where
    no worker can be started or it is lost.

    On Linux the worker forks once it has imported matplotlib and serves two channels, so
    that two figures are drawn at once (an animation beside the plots) for one import: a
    task goes to the channel with the least work queued (an animation counts as
    :data:`MOVIE_COST` plots).

    :meth:`draw` hands over a task, :meth:`done` a file already written (to keep the order),
    :meth:`results` waits for all of them in order and raises the first failure.
    """

    #: An animation's drawing time in plots (the paper's example: 81 frames ~0.34 s, a
    #: plot ~0.11 s).
    MOVIE_COST = 3

    def __init__(self):
        import tempfile

        from .runtime import _command

        self.tasks: list = []  # (task or None, path or None, channel or None)
        self.tmp = tempfile.mkdtemp(prefix="mixdyn-figures-")
        self.channels: list = []  # (tasks writer, replies reader) or None where lost
        self.proc, second = _command.worker()  # started with the command where it could be
        if self.proc is None:
            return
        self.channels.append((self.proc.stdin, self.proc.stdout))
        if second is not None:
            writer = open(second[0], "w", encoding="utf-8")  # noqa: SIM115 - closed in close()
            self.channels.append((writer, open(second[1], encoding="utf-8")))  # noqa: SIM115
        self.queued = [0] * len(self.channels)

    def draw(self, kind: str, *args, **kwargs) -> None:
        import pickle

        task = (kind, args, kwargs)
        live = [k for k, c in enumerate(self.channels) if c is not None]
        if live:
            k = min(live, key=lambda i: self.queued[i])
            name = os.path.join(self.tmp, f"task{len(self.tasks)}.pickle")
            try:
                with open(name, "wb") as f:
                    pickle.dump(task, f, protocol=pickle.HIGHEST_PROTOCOL)
                self.channels[k][0].write(name + "\n")
                self.channels[k][0].flush()
                self.queued[k] += self.MOVIE_COST if kind == "movie" else 1
                self.tasks.append((task, None, k))
                return
            except (OSError, ValueError, pickle.PicklingError):
                self._lose(k)
        self.tasks.append((task, None, None))

    def done(self, path) -> None:
        self.tasks.append((None, path, None))

    def results(self) -> list[pathlib.Path]:
        import pickle

        out = []
        tasks, self.tasks = self.tasks, []
        for task, path, k in tasks:
            if task is None:
                out.append(path)
                continue
            reply = None
            if k is not None and self.channels[k] is not None:
                line = self.channels[k][1].readline()
                if line.strip():
                    reply = pickle.loads(bytes.fromhex(line.strip()))
                else:
                    self._lose(k)
            if reply is None:  # no worker: drawn here
                out.append(_draw_here(*task))
                continue
            status, value = reply
            if status == "error":
                raise value
            out.append(pathlib.Path(value))
        return out

    def _drop(self, k: int) -> None:
        """Close channel ``k`` (the end of its tasks: the copy serving it ends)."""
        for end in self.channels[k] or ():
            with contextlib.suppress(OSError, ValueError):
                end.close()
        self.channels[k] = None

    def _lose(self, k: int) -> None:
        """Give up channel ``k`` (its tasks are drawn here); the worker with the last one."""
        self._drop(k)
        if not any(self.channels):
            self._stop()

    def _stop(self) -> None:
        """Stop the worker (and its copy) at once."""
        from .runtime import _command

        if self.proc is not None:
            _command.stop(self.proc)
            self.proc = None

    def abort(self) -> None:
        """Close without waiting for the worker (it may still be importing): for a run that
        has nothing for it to draw."""
        self._stop()
        self.close()

    def close(self) -> None:
        import shutil
        import subprocess

        for k in range(len(self.channels)):
            self._drop(k)
        if self.proc is not None:
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._stop()
            self.proc = None
        shutil.rmtree(self.tmp, ignore_errors=True)


def _draw_here(kind: str, args, kwargs) -> pathlib.Path:
    from .viz import _draw, plot_columns, sweep_plots

    do = {
        "plot": plot_columns,
        "movie": _draw.movie,
        "against": sweep_plots.plot_against,
        "band": sweep_plots.plot_band,
        "fit": sweep_plots.plot_fit,
        "optimum": sweep_plots.plot_optimum,
    }
    return do[kind](*args, **kwargs)


#: Seconds between two progress lines when stderr is not a terminal.
PROGRESS_LOG_EVERY = 5.0


def _progress_log(plan, every: float = PROGRESS_LOG_EVERY):
    """A progress callback ``f(t)`` writing a plain line on stderr at most every ``every``
    seconds: the run, the simulated time, the fraction done and the time elapsed."""
    t0, t1 = float(plan.times[0]), float(plan.times[-1])
    start = time.monotonic()
    last = [start]

    def at(t):
        now = time.monotonic()
        if now - last[0] < every:
            return
        last[0] = now
        done = (float(t) - t0) / ((t1 - t0) or 1.0)
        sys.stderr.write(
            clean(
                f"{plan.name}: t = {float(t):.6g} of {t1:.6g} ({100 * done:.0f}%), "
                f"{now - start:.0f} s\n"
            )
        )
        sys.stderr.flush()

    return at


def _members_log(plan, every: float = PROGRESS_LOG_EVERY):
    """A per-member progress callback writing a plain line on stderr at most every
    ``every`` seconds: the sweep, the members done and the time elapsed."""
    import threading

    start = time.monotonic()
    state = {"last": start, "done": 0}
    lock = threading.Lock()

    def at(i):
        with lock:
            state["done"] += 1
            now = time.monotonic()
            if now - state["last"] < every and state["done"] < plan.members:
                return
            state["last"] = now
            sys.stderr.write(
                clean(f"{plan.name}: {state['done']} of {plan.members} members, ")
                + f"{now - start:.0f} s\n"
            )
            sys.stderr.flush()

    return at


def _sweep_figures(plan, result, folder, painter: _Painter) -> None:
    """Hand a sweep's plots to ``painter``: a summary against a swept quantity, or a band."""
    import numpy as np

    from .viz.plots import result_columns

    units = dict(result.units)
    model = next((r.model for r in result.sweep.results if r is not None), None)
    for name in plan.values:  # a swept body number has the unit of its kind
        kind = {"mass": "mass", "inertia": "inertia"}.get(name.rsplit(".", 1)[-1])
        if kind and model is not None:
            units[name] = model.units.label(kind)
    for p in plan.spec.plots:
        if p.band is not None:
            ok = [r for r in result.sweep.results if r is not None]
            if not ok:
                continue
            rows = [np.asarray(result_columns(r, [p.band])[0][p.band]) for r in ok]
            units["t"] = ok[0].units()["t"]
            painter.draw(
                "band",
                np.asarray(plan.times),
                np.stack(rows),
                folder / p.file,
                name=p.band,
                units=units,
                title=p.title,
            )
            continue
        painter.draw(
            "against",
            plan.values[p.x],
            result.summaries[p.y],
            folder / p.file,
            names=(p.x, p.y),
            by=None if p.by is None else plan.values[p.by],
            by_name=p.by or "",
            units=units,
            title=p.title,
            scatter=plan.spec.sampling == "latin_hypercube",
        )


def _figures(runner, plan, result, folder, painter: _Painter) -> None:
    """Hand the plots and animation a run asks for to ``painter`` (the data is prepared
    here: columns, references, the scene; the HTML page is written here)."""
    import shutil

    from .io.quantities import factor
    from .io.results import in_units
    from .viz import html, movie_data, result_columns

    for k, p in enumerate(runner.plots(plan)):
        try:
            cols, units = result_columns(result, [*p.columns, p.x])
        except KeyError as e:
            runner.fail((*plan.path, "plots", k, "columns"), str(e.args[0]), "fix the column name")
        shown, units = in_units(result, cols, units, runner.output_units)
        reference = None
        if p.reference is not None:
            y = _reference(runner, p.reference, result.t)
            kind = result.kind_of(p.columns[0])  # drawn in the first column's unit
            if kind in runner.output_units:
                y = y / factor(runner.output_units[kind], kind, result.model.units)
            reference = (result.t, y, p.reference.label or p.reference.expr)
        cols = shown
        painter.draw(
            "plot",
            cols,
            p.columns,
            folder / p.file,
            units=units,
            title=p.title,
            ylabel=p.ylabel,
            reference=reference,
            x=p.x,
        )
    a = plan.spec.animation
    if a is not None:
        path = folder / a.file
        if path.suffix.lower() == ".mp4" and shutil.which("ffmpeg") is None:
            raise ValueError(
                "writing MP4 needs ffmpeg, which is not installed; write a .gif or .html"
            )
        if path.suffix.lower() == ".html":
            painter.done(html(result, path, fps=a.fps, trace=a.trace, forces=a.forces))
        else:
            data = movie_data(result, frames=a.frames, trace=a.trace, forces=a.forces)
            painter.draw("movie", data, path, fps=a.fps)
        if a.html:
            painter.done(
                html(result, path.with_suffix(".html"), fps=a.fps, trace=a.trace, forces=a.forces)
            )


def _reference(runner, ref, t):
    import numpy as np

    from .io import ExpressionLaw
    from .io.expressions import evaluate
    from .io.quantities import factor

    scale = 1.0 if ref.unit is None else factor(ref.unit, None, runner.b.units)
    law = ExpressionLaw(ref.expr, runner.b.parameters, ref.unit, scale)
    # evaluated by NumPy: each jax.numpy operation outside a compiled program is one of its own
    t = np.asarray(t, dtype=float)
    values = np.asarray(law.values)
    return float(law.scale) * (np.asarray(evaluate(law.tree, t, values, xp=np)) + 0.0 * t)


# --------------------------------------------------------------------------- plot
@app.command()
def plot(
    results: Annotated[
        pathlib.Path,
        typer.Argument(help="A run's output folder (OUT/NAME) or its results.csv / .parquet."),
    ],
    columns: Annotated[
        list[str],
        typer.Option("--column", "-c", help="A column to plot; repeatable (a panel per unit)."),
    ],
    x: Annotated[str, typer.Option("--x", help="The column on the x axis, e.g. crank.phi.")] = "t",
    output: Annotated[
        pathlib.Path | None,
        typer.Option("--output", "-o", help="The figure (.png, .svg or .pdf)."),
    ] = None,
    title: Annotated[str | None, typer.Option("--title", help="The figure's title.")] = None,
    unit: Annotated[
        list[str] | None,
        typer.Option(
            "--unit", "-u", help="COLUMN=UNIT: draw a column in another unit, e.g. crank.phi=deg."
        ),
    ] = None,
):
    """Plot chosen columns of written results against time (or --x), to PNG, SVG or PDF."""
    with _guard(results):
        from ._hints import did_you_mean
        from .io import FileError, read_result
        from .viz import PLOT_SUFFIXES, plot_columns

        try:
            table, meta = read_result(results)
        except FileNotFoundError as e:
            raise FileError(
                str(e), file=str(results), hint="give a folder written by `mixdyn run`"
            ) from None
        missing = [c for c in [*columns, x] if c not in table.columns]
        if missing:
            raise FileError(
                f"no column {missing[0]!r}",
                "--x" if missing[0] == x and x not in columns else "--column",
                file=str(results),
                hint=did_you_mean(missing[0], table.columns)
                + " (the first line of results.csv lists them all)",
            )
        if output is None:
            folder = results if results.is_dir() else results.parent
            stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", "_".join(columns))[:80]
            output = folder / f"{stem}.png"
        if output.suffix.lower() not in PLOT_SUFFIXES:
            raise FileError(
                f"cannot write a plot to {output.name!r}",
                "--output",
                file=str(results),
                hint=f"use {', '.join(PLOT_SUFFIXES)}",
            )
        check_output(output, "--output")
        units = dict(meta.get("units") or {})
        for k, spec in enumerate(unit or ()):
            table, units = _in_unit(table, units, spec, results, k)
        plot_columns(table, columns, output, units=units, title=title, x=x)
        _say(f"wrote {_esc(output)}")


# --------------------------------------------------------------------------- animate
@app.command()
def animate(
    file: FileArg,
    run_name: Annotated[str, typer.Option("--run", "-r", help="The run to animate.")],
    output: Annotated[
        list[pathlib.Path],
        typer.Option(
            "--output",
            "-o",
            help="Output: .gif, .mp4 (needs ffmpeg) or .html; without a suffix, both "
            "OUT.gif and OUT.html. Repeatable.",
        ),
    ],
    results: Annotated[
        pathlib.Path | None,
        typer.Option(
            "--results", help="Take the motion from this run's written results instead of running."
        ),
    ] = None,
    fps: Annotated[int | None, typer.Option(help="Frames per second.", min=1, max=120)] = None,
    frames: Annotated[int | None, typer.Option(help="Most frames.", min=2, max=2000)] = None,
    trace: Annotated[
        list[str] | None, typer.Option("--trace", help="A point whose path is drawn; repeatable.")
    ] = None,
):
    """Animate the mechanism moving in a run: a GIF (MP4 only if ffmpeg exists) and a
    self-contained HTML page."""
    with _guard(file):
        import shutil

        import numpy as np

        from .io import FileError, read, read_result
        from .runs import Runner
        from .viz import animate as write_animation

        spec = read(file)
        _require_size(spec, file)
        runner = Runner(spec)
        plan = runner.order([run_name])[-1]
        if plan.spec.kind == "sweep":
            raise FileError(
                f"run {run_name!r} is a sweep: its members have no single motion to animate",
                "--run",
                file=str(file),
                hint=f"animate the run it sweeps, {plan.spec.run!r}",
            )
        a = plan.spec.animation
        fps = fps or (a.fps if a else 20)
        frames = frames or (a.frames if a else 80)
        trace = list(trace or (a.trace if a else []))
        for k, ref in enumerate(trace):
            runner.b.point(ref, ("--trace", k))
        targets = []
        for o in output:
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
        model = runner.model
        if results is not None:
            try:
                table, _ = read_result(results)
            except FileNotFoundError as e:
                raise FileError(str(e), "--results", file=str(file)) from None
            names = [f"{b.name}.{c}" for b in model.bodies for c in ("x", "y", "phi")]
            missing = [n for n in names if n not in table.columns]
            if missing:
                raise FileError(
                    f"the results lack column {missing[0]!r}; they are not of this model",
                    "--results",
                    file=str(file),
                    hint="give the results of this file's run",
                )
            t, q = table["t"].to_numpy(), table[names].to_numpy()
        else:
            for p in runner.order([run_name]):
                if p.spec.kind != "kinematic":
                    runner.check_masses(p)
                runner.mobility(p)
            res = runner.execute([run_name])[run_name]
            res = getattr(res, "result", res)  # an identify run: the run at the estimate
            t, q = res.t, res.q
        forces = a.forces if a else False
        if forces and (results is not None or res.kind == "kinematic"):
            _say(
                "[yellow]note[/]: no force arrows: "
                + (
                    "written results carry no model to place them"
                    if results is not None
                    else "a kinematic run has no forces"
                )
            )
            forces = False
        for target in targets:
            write_animation(
                res if forces else None,
                target,
                model=model,
                t=np.asarray(t),
                q=np.asarray(q),
                fps=fps,
                frames=frames if target.suffix.lower() != ".html" else None,
                trace=trace,
                forces=forces,
            )
            _say(f"wrote {_esc(target)}")


# --------------------------------------------------------------------------- schema, dump
@app.command()
def schema(
    output: Annotated[
        pathlib.Path | None, typer.Option("--output", "-o", help="Write to this file.")
    ] = None,
):
    """Print (or write) the JSON Schema of model files, for editors and validators."""
    with _guard(output):
        import json

        from .io import json_schema

        text = json.dumps(json_schema(), indent=2)
        if output is None:
            typer.echo(text)
        else:
            _write_text(output, text + "\n")
            _say(f"wrote {_esc(output)}")


@app.command()
def dump(
    file: FileArg,
    output: Annotated[
        pathlib.Path | None, typer.Option("--output", "-o", help="Write to this file.")
    ] = None,
):
    """Read, validate and build a model file, then write it back in normal form (defaults
    left out), keeping its comments, key order and flow style where its keys remain; loading
    the output gives the same model."""
    with _guard(file):
        from .io import build, read
        from .io.dump import dumps_keeping

        if output is not None:
            check_output(output, "--output")
        spec = read(file)
        _require_size(spec, file)
        build(spec)
        text = dumps_keeping(pathlib.Path(file).read_text(encoding="utf-8"), spec)
        if output is None:
            typer.echo(text, nl=False)
        else:
            _write_text(output, text)
            _say(f"wrote {_esc(output)}")


def _write_text(path: pathlib.Path, text: str) -> None:
    """Write ``text`` to ``path`` (its folder created), after :func:`check_output`."""
    check_output(path, "--output")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


def main() -> None:
    """Entry point of the ``mixdyn`` command.

    The command ends with :func:`_leave`: its exit code once everything it writes is
    written, without the interpreter's teardown of every module and object (~0.2 s after a
    run, a tenth of a warm run). An exception that escapes (a bug; with ``MIXDYN_DEBUG=1``)
    ends the usual way, with its traceback.
    """
    configure_cache()
    use_roomy_frames()
    t0 = time.perf_counter()
    try:
        roomy(app)  # tracing outside the exports (the cache off) on a roomy frame stack
    except SystemExit as exc:
        code = exc.code
    else:
        code = EXIT_OK
    finally:
        if os.environ.get("MIXDYN_TIMING"):
            sys.stderr.write(f"mixdyn: {time.perf_counter() - t0:.2f} s\n")
    _leave(code)


def _leave(code) -> None:
    """End the process with ``code`` (as :class:`SystemExit` reads it: ``None`` is 0, a
    text is printed on stderr and gives 1), without the interpreter's teardown where
    :func:`mixdyn.runtime._private.exit_now` may skip it."""
    from .runtime import _programs

    if code is None:
        code = EXIT_OK
    elif not isinstance(code, int):
        sys.stderr.write(f"{code}\n")
        code = 1  # what Python gives for a message
    _programs.stop_prefetch()  # programs still being read ahead: not awaited to the last
    exit_now(code)


if __name__ == "__main__":  # pragma: no cover
    main()

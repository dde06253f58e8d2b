"""The ``mixdyn`` command line: a thin shell over :mod:`mixdyn.io` (the files),
:mod:`mixdyn.runs` (running a file's runs and writing them) and :mod:`mixdyn.viz`.

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

from ._hints import count
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
def _say(text: str = "") -> None:
    """Print ``text`` (rich markup) on stdout, its control characters made harmless."""
    from rich.console import Console

    from .runs.console import clean

    Console(soft_wrap=True, highlight=False).print(clean(text))


def _esc(text) -> str:
    """User text (names, paths) made safe inside rich markup and on the terminal."""
    from .runs.console import esc

    return esc(text)


def _fail(code: int, line: str) -> None:
    """Print one line on stderr and exit with ``code``."""
    from .runs.console import clean

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
        from .runs.checks import require_size
        from .runs.outputs import check_output
        from .runs.setup import start_q
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
        require_size(spec, file)
        model = Runner(spec).model
        asm = an.assemble(model, start_q(model), hold=spec.assembly.hold)
        draw(model, asm.q, target, title=f"{model.name} at its assembled start")
        _say(f"wrote {_esc(target)}")


# --------------------------------------------------------------------------- check
@app.command()
def check(
    file: FileArg,
    explain: Annotated[
        bool,
        typer.Option(
            "--explain",
            help="Also print every number as understood: where it is, as written, in the "
            "model's units and in SI.",
        ),
    ] = False,
):
    """Check a model file: form, names, units, expressions, degrees of freedom, and that
    every run is well posed (options, steps, outputs, laws). Prints the degrees of freedom,
    redundant equations, the driver/DOF balance of each run and warnings; changes nothing.
    A model file is UTF-8 text of at most 20 MB with at most 50,000 bodies (checked at
    about 2 s and 50 MB per 1,000 bodies)."""
    with _guard(file):
        from . import analysis as an
        from .io import read
        from .runs import Runner, kind_of
        from .runs.checks import file_warnings, require_size
        from .runs.setup import start_q

        spec = read(file)
        require_size(spec, file)
        runner = Runner(spec)
        model = runner.model
        asm = an.assemble(model, start_q(model), hold=spec.assembly.hold)
        report = an.degrees_of_freedom(model, asm.q)
        _say(f"[bold]{_esc(file)}[/bold]: {_esc(model.summary())}")
        _say(
            f"assembled start: residual {asm.residual:.2e} in {count(asm.iterations, 'iteration')}"
        )
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
        warnings = [*runner.b.readings.warnings, *file_warnings(spec, model, report)]
        for plan in runner.order():
            runner.check_masses(plan)
            rep = runner.mobility(plan)
            runner.check_solvable(plan)
            _say(kind_of(plan).describe(plan, rep, model))
        for w in warnings:
            _say(f"[yellow]warning[/yellow]: {_esc(w)}")
        if explain:
            from .io.explain import lines

            for line in lines(runner.b):
                _say(_esc(line))
        _say("[green]ok[/green]")


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
            "varied numbers as coordinates (needs xarray: pip install 'mixdyn\\[xarray]').",
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
    (columns t, {body}.x ..., {joint}.Fx ..., driver efforts and unknown forces by name, each
    header "name \\[unit]"), OUT/NAME/meta.json (units of every column, solver, tolerances,
    counters, version) and the figures and animation the run asks for."""
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
    painter = None
    if figures:
        from .viz.painter import Painter

        painter = Painter()
    with _guard(file):
        from .runs.console import clean
        from .runs.outputs import Outputs, check_run_outputs, draws, write_runs

        try:
            from .io import FileError, read
            from .io.tables import parquet_module
            from .runs import Runner
            from .runs.checks import require_size

            if parquet:  # refused before anything runs
                parquet_module(file, "writing", "--parquet")
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
            out, file, parquet=parquet, netcdf=netcdf, figures=figures, painter=painter
        )
        from .runtime._programs import on_first_compile

        if progress is None and mode == "off":  # no line per run: what takes long is said
            on_first_compile(lambda: _compiling(file))
        try:
            written = write_runs(runner, plans, outputs, mode)
        finally:
            on_first_compile(None)
        _say(f"wrote {count(len(written), 'file')} under {_esc(out)}")
        if outputs.failed:  # a sweep with failed members: the others are written
            _fail(EXIT_NUMERICAL, outputs.failed[0])


def _compiling(file) -> None:
    """The one line ``mixdyn run`` writes off a terminal as it first compiles (on stdout,
    beside the files written: stderr holds a failure's one line alone)."""
    from .runs.console import clean

    sys.stdout.write(
        f"{clean(file)}: compiling the model's programs (the first time for this model, "
        "up to a minute; later runs read them from the cache)\n"
    )
    sys.stdout.flush()


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
        from .io.results import column_in_unit
        from .io.tables import require_numbers
        from .runs.outputs import check_output
        from .units import engineering
        from .viz import PLOT_SUFFIXES, plot_columns

        try:
            table, _ = read_result(results)
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
        require_numbers(table, [x], results, "--x")
        require_numbers(table, columns, results, "--column")
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
        units = dict(table.attrs.get("units") or {})
        for k, spec in enumerate(unit or ()):
            table, units = column_in_unit(table, units, spec, results, k)
        units = {c: engineering(u) for c, u in units.items()}
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
        import numpy as np

        from .io import FileError, read
        from .io.results import read_motion
        from .runs import Runner, kind_of
        from .runs.checks import require_size
        from .runs.outputs import animation_targets
        from .viz import animate as write_animation

        spec = read(file)
        require_size(spec, file)
        runner = Runner(spec)
        plan = runner.order([run_name])[-1]
        refusal = kind_of(plan).animation_refusal(plan)
        if refusal is not None:
            raise FileError(refusal[0], "--run", file=str(file), hint=refusal[1])
        a = plan.spec.animation
        fps = fps or (a.fps if a else 20)
        frames = frames or (a.frames if a else 80)
        trace = list(trace or (a.trace if a else []))
        for k, ref in enumerate(trace):
            runner.b.point(ref, ("--trace", k))
        targets = animation_targets(output, file)
        model = runner.model
        if results is not None:
            t, q = read_motion(results, model, file)
        else:
            for p in runner.order([run_name]):
                runner.check_masses(p)
                runner.mobility(p)
            res = runner.execute([run_name])[run_name]
            res = getattr(res, "result", res)  # a fit or an optimum: the run at it
            t, q = res.t, res.q
        forces = a.forces if a else False
        if forces and (results is not None or kind_of(res).motion_only):
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
        from .runs.checks import require_size
        from .runs.outputs import check_output

        if output is not None:
            check_output(output, "--output")
        spec = read(file)
        require_size(spec, file)
        build(spec)
        text = dumps_keeping(pathlib.Path(file).read_text(encoding="utf-8"), spec)
        if output is None:
            typer.echo(text, nl=False)
        else:
            _write_text(output, text)
            _say(f"wrote {_esc(output)}")


def _write_text(path: pathlib.Path, text: str) -> None:
    """Write ``text`` to ``path`` (its folder created), after
    :func:`~mixdyn.runs.outputs.check_output`."""
    from .runs.outputs import check_output

    check_output(path, "--output")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


def _one_line_summaries() -> None:
    """Each command's summary in ``mixdyn --help``: its docstring's first paragraph as one
    line, wrapped by the formatter (typer's rich mode keeps the docstring's line breaks
    there, breaking lines mid-sentence)."""
    import inspect

    for info in app.registered_commands:
        if info.short_help is None and info.callback is not None and info.callback.__doc__:
            first = inspect.cleandoc(info.callback.__doc__).split("\n\n")[0]
            info.short_help = " ".join(first.split())


_one_line_summaries()


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

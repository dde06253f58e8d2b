"""The ``mixdyn`` command line: the commands, their arguments and options and their exit
codes, each command a call into the module that does its job: :mod:`mixdyn.runs.report`
(``check``), :mod:`mixdyn.runs.job` (``run``), :mod:`mixdyn.runs.pictures` (``show``,
``plot``, ``animate``) and :mod:`mixdyn.runs.texts` (``schema``, ``dump``); an error ends it
with one line and the exit code of :mod:`mixdyn.runs.exits`.

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
import sys
import time
from typing import Annotated

import typer

from ._help import one_line_summaries
from ._hints import count
from .runtime._private import exit_now, roomy, use_roomy_frames
from .runtime._programs import configure_from_env as configure_cache

app = typer.Typer(
    name="mixdyn",
    help="Kinematics and forward, inverse and mixed dynamics of planar mechanisms, from model "
    "files (YAML).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)

FileArg = Annotated[pathlib.Path, typer.Argument(help="The model file (YAML).", show_default=False)]


def _fail(code: int, line: str) -> None:
    """Print one line on stderr and exit with ``code``."""
    from .runs.console import clean

    sys.stderr.write(" ".join(clean(line).split()) + "\n")
    sys.stderr.flush()
    raise typer.Exit(code)


@contextlib.contextmanager
def _guard(file: pathlib.Path | str | None):
    """Turn mixdyn's errors into one line and an exit code (:func:`mixdyn.runs.exits.exit_for`)."""
    try:
        yield
    except typer.Exit:
        raise
    except BaseException as e:
        from .runs.exits import exit_for

        ending = exit_for(e, file)
        if ending is None:
            raise
        _fail(*ending)


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
        from .runs.console import esc, say
        from .runs.pictures import show as draw_start

        say(f"wrote {esc(draw_start(file, output))}")


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
        from .runs.console import say
        from .runs.report import report

        for line in report(file, explain):
            say(line)


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
    excel: Annotated[
        bool,
        typer.Option(
            "--excel",
            help="Also write results.xlsx (a sweep's sweep.xlsx): the table with its units and "
            "a sheet of settings (needs openpyxl: pip install 'mixdyn\\[excel]').",
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
    counters, version), the figures and animation the run asks for and OUT/NAME/report.html
    (one page: the drawing, the figures, each column's range, the energy balance, the
    settings)."""
    from .runtime import _command, _programs

    # The programs this job used last time are read from the cache beside the checks below
    # (from the import of mixdyn on, where it could read the command line: _command.job_tag).
    with _programs.job(_command.run_tag(file, runs)), _guard(file):
        from .runs.console import esc, say
        from .runs.exits import EXIT_NUMERICAL
        from .runs.job import run_job

        written, failed = run_job(
            file,
            runs,
            out,
            parquet=parquet,
            netcdf=netcdf,
            excel=excel,
            figures=figures,
            progress=progress,
        )
        say(f"wrote {count(len(written), 'file')} under {esc(out)}")
        if failed:  # a sweep with failed members: the others are written
            _fail(EXIT_NUMERICAL, failed[0])


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
        from .runs.console import esc, say
        from .runs.pictures import plot as plot_results

        written = plot_results(results, columns, x, output, title, unit)
        say(f"wrote {esc(written)}")


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
        from .runs.console import say
        from .runs.pictures import animate as animate_run

        for line in animate_run(file, run_name, output, results, fps, frames, trace):
            say(line)


@app.command()
def schema(
    output: Annotated[
        pathlib.Path | None, typer.Option("--output", "-o", help="Write to this file.")
    ] = None,
):
    """Print (or write) the JSON Schema of model files, for editors and validators."""
    with _guard(output):
        from .runs.console import esc, say
        from .runs.texts import schema_text, write_text

        text = schema_text()
        if output is None:
            typer.echo(text)
        else:
            write_text(output, text + "\n")
            say(f"wrote {esc(output)}")


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
        from .runs.console import esc, say
        from .runs.texts import normal_form, write_text

        text = normal_form(file, output)
        if output is None:
            typer.echo(text, nl=False)
        else:
            write_text(output, text)
            say(f"wrote {esc(output)}")


@app.command()
def server(
    action: Annotated[
        str,
        typer.Argument(help="start, stop or status.", show_default=False),
    ] = "status",
):
    """The command server: a process with mixdyn imported that answers check, show, plot and
    schema at once (MIXDYN_SERVER=1 starts it when none runs, 0 never uses it; unset, a
    command from a terminal starts it). It stops after 10 minutes unused."""
    from .runs.console import esc, say
    from .runtime import _server

    if action not in ("start", "stop", "status"):
        _fail(2, f"mixdyn server: unknown action {action!r}; use start, stop or status")
    path = _server.address()
    if action == "stop":
        say("stopped the command server" if _server.stop() else "no command server runs")
    elif _server.running():
        say(f"the command server runs at {esc(path)}")
    elif action == "status":
        say(f"no command server runs (MIXDYN_SERVER={_server.policy()})")
    else:
        if len(os.fsencode(path)) > _server.MAX_PATH_BYTES:
            _fail(
                2,
                f"mixdyn server: the socket path {path} is longer than "
                f"{_server.MAX_PATH_BYTES} bytes; set MIXDYN_SERVER_DIR to a shorter folder",
            )
        if not _server._own_folder(path.parent) or not _server.start(path):
            _fail(
                1,
                f"mixdyn server: could not start a command server at {path} (its folder must "
                "be this user's alone: mode 0700)",
            )
        deadline = time.monotonic() + _server.STARTING_SECONDS
        while not _server.running() and time.monotonic() < deadline:
            time.sleep(0.1)
        if not _server.running():
            _fail(
                1,
                f"mixdyn server: the command server did not start; see {path.with_suffix('.log')}",
            )
        say(f"started the command server at {esc(path)}")


one_line_summaries(app)  # `mixdyn --help` lists each command on one line


def main() -> None:
    """Entry point of the ``mixdyn`` command.

    The command ends with :func:`_leave`: its exit code once everything it writes is
    written, without the interpreter's teardown of every module and object (~0.2 s after a
    run, a tenth of a warm run). An exception that escapes (a bug; with ``MIXDYN_DEBUG=1``)
    ends the usual way, with its traceback.
    """
    prepare_command()
    t0 = time.perf_counter()
    try:
        code = command(None)
    finally:
        if os.environ.get("MIXDYN_TIMING"):
            sys.stderr.write(f"mixdyn: {time.perf_counter() - t0:.2f} s\n")
    _leave(code)


def prepare_command() -> None:
    """What a process does once before running command lines: the program cache as the
    environment sets it, and roomy frames for tracing."""
    configure_cache()
    use_roomy_frames()


def command(args: list[str] | None) -> int:
    """Run one command line (``args``: the words after ``mixdyn``; None: this process's)
    in this process: its exit code. An error of mixdyn's ends as its exit code and one
    line; an unexpected exception (a bug) propagates."""
    try:
        roomy(app, args=args, prog_name="mixdyn")  # tracing on a roomy frame stack
    except SystemExit as exc:
        return _exit_code(exc.code)
    return 0


def serve(path: str) -> None:
    """The command server's process (:mod:`mixdyn.runtime._server`): prepared as the
    command's own, it answers command lines at the socket ``path`` with :func:`command`."""
    from .runtime import _server

    prepare_command()
    _server.serve(pathlib.Path(path), command)


def _exit_code(code) -> int:
    """The exit code :class:`SystemExit` gives for ``code``: ``None`` is 0, a text is printed
    on stderr and gives 1."""
    if code is None:
        return 0
    if not isinstance(code, int):
        sys.stderr.write(f"{code}\n")
        return 1  # what Python gives for a message
    return code


def _leave(code) -> None:
    """End the process with ``code`` (as :class:`SystemExit` reads it: :func:`_exit_code`),
    without the interpreter's teardown where :func:`mixdyn.runtime._private.exit_now` may
    skip it."""
    from .runtime import _programs

    code = _exit_code(code)
    _programs.stop_prefetch()  # programs still being read ahead: not awaited to the last
    exit_now(code)


if __name__ == "__main__":  # pragma: no cover
    main()

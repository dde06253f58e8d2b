"""The pictures the ``mixdyn`` command draws on request: a file's model at its assembled start
(``mixdyn show``: :func:`show`), chosen columns of written results (``mixdyn plot``:
:func:`plot`) and a run's motion (``mixdyn animate``: :func:`animate`). Every output is checked
before anything is computed or drawn.

Example::

    show("examples/four_bar.yaml", pathlib.Path("four_bar.svg"))
"""

from __future__ import annotations

import pathlib
import re
from collections.abc import Iterator

from .console import esc


def show(file, output: pathlib.Path | None = None) -> pathlib.Path:
    """Draw the model of ``file`` at its assembled start (bodies, joints, ground points and
    their names), without running an analysis.

    Args:
        file: the model file.
        output: the drawing, ``.png``, ``.svg`` or ``.pdf``, or ``.html``: the HTML player
            (:func:`mixdyn.viz.player.html`) at the start, to zoom, pan and read coordinates;
            None: ``FILE.png``.

    Returns:
        The file drawn.
    """
    import numpy as np

    from .. import analysis as an
    from ..io import FileError, read
    from ..viz.show import SHOW_SUFFIXES, draw
    from .checks import require_size
    from .outputs import check_output
    from .runner import Runner
    from .setup import start_q

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
    if model is None:  # a file of synthesis runs alone
        raise FileError(
            "the file describes no mechanism (its runs are synthesis runs)",
            file=str(file),
            hint="mixdyn run it, then show the best.yaml it writes",
        )
    asm = an.assemble(model, start_q(model), hold=spec.assembly.hold)
    title = f"{model.name} at its assembled start"
    if target.suffix.lower() == ".html":  # the player, at the start: one frame
        from ..viz.player import html

        q = np.asarray(asm.q, dtype=float)[None]
        html(model=model, t=np.zeros(1), q=q, path=target, title=title)
        return target
    draw(model, asm.q, target, title=title)
    return target


def plot(
    results: pathlib.Path,
    columns: list[str],
    x: str = "t",
    output: pathlib.Path | None = None,
    title: str | None = None,
    units: list[str] | None = None,
) -> pathlib.Path:
    """Plot columns of a run's written results against ``x`` (a panel per unit).

    Args:
        results: a run's output folder (``OUT/NAME``) or its ``results.csv`` / ``.parquet``.
        columns: the columns to plot.
        x: the column on the x axis.
        output: the figure, ``.png``, ``.svg`` or ``.pdf``; None: the columns' names as a
            ``.png`` beside the results.
        title: the figure's title.
        units: ``COLUMN=UNIT`` each: a column drawn in another unit (``--unit``).

    Returns:
        The figure written.
    """
    from .._hints import did_you_mean
    from ..io import FileError, read_result
    from ..io.results import column_in_unit
    from ..io.tables import require_numbers
    from ..units import engineering
    from ..viz import PLOT_SUFFIXES, plot_columns
    from .outputs import check_output

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
    column_units = dict(table.attrs.get("units") or {})
    for k, spec in enumerate(units or ()):
        table, column_units = column_in_unit(table, column_units, spec, results, k)
    column_units = {c: engineering(u) for c, u in column_units.items()}
    plot_columns(table, columns, output, units=column_units, title=title, x=x)
    return output


def animate(
    file,
    run_name: str,
    outputs: list[pathlib.Path],
    results: pathlib.Path | None = None,
    fps: int | None = None,
    frames: int | None = None,
    trace: list[str] | None = None,
) -> Iterator[str]:
    """Animate the mechanism moving in a run: GIF, MP4 (with ffmpeg) or HTML files.

    Args:
        file: the model file.
        run_name: the run to animate.
        outputs: the files (``--output``); a name without a suffix gives ``NAME.gif`` and
            ``NAME.html`` (:func:`~.outputs.animation_targets`).
        results: take the motion from this run's written results instead of running it.
        fps: frames per second; None: the run's ``animation:`` or 20.
        frames: the most frames; None: the run's ``animation:`` or 80.
        trace: points whose paths are drawn; None: the run's ``animation:``.

    Yields:
        The lines to show (rich markup), as they come: a note where the force arrows the
        run asks for cannot be drawn, then ``wrote PATH`` as each file is written.
    """
    import numpy as np

    from ..io import FileError, read
    from ..io.results import read_motion
    from ..viz import animate as write_animation
    from .checks import require_size
    from .kinds import kind_of
    from .outputs import animation_targets
    from .runner import Runner

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
    targets = animation_targets(outputs, file)
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
        yield "[yellow]note[/]: no force arrows: " + (
            "written results carry no model to place them"
            if results is not None
            else "a kinematic run has no forces"
        )
        forces = False
    for target in targets:
        write_animation(
            res if results is None else None,  # a run's result: its symbols and plot too
            target,
            model=model,
            t=np.asarray(t),
            q=np.asarray(q),
            fps=fps,
            frames=frames if target.suffix.lower() != ".html" else None,
            trace=trace,
            forces=forces,
            columns=(a.plot if a else None) if results is None else None,
            plot_x=a.plot_x if a and results is None else "t",
        )
        yield f"wrote {esc(target)}"


__all__ = ["animate", "plot", "show"]

"""A process that draws figures and animations for ``mixdyn run`` while it computes.

Run as a script (``python .../mixdyn/runtime/_worker.py``): it imports neither mixdyn nor JAX,
only NumPy, matplotlib and Pillow, and loads :mod:`mixdyn.viz.plots` and
:mod:`mixdyn.viz._draw` by their paths (and :mod:`mixdyn.runtime._private`, whose
:func:`~mixdyn.runtime._private.shared_palette` its GIFs are written in). Each line on
standard input names a file holding a pickled task ``(kind, args, kwargs)`` (``kind``:
``"plot"``, ``"movie"``, ``"against"`` or ``"band"``); for each it
writes one line on standard output, the hex of a pickled ``("ok", path)`` or
``("error", exception)``. An empty line or the end of the input ends it.

With ``--fork TASKS REPLIES`` (two inherited file descriptors) the worker forks once its
imports are done: the copy serves a second channel (tasks read from ``TASKS``, replies
written to ``REPLIES``) beside the first, so that two figures are drawn at once for the
price of one import of matplotlib (where ``os.fork`` is missing or fails, the second
channel's ends are closed and its tasks come back to the caller, which draws them itself).
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import pathlib
import pickle
import sys


def _load(name: str, room: str = "viz"):
    path = pathlib.Path(__file__).parent.parent / room / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"_mixdyn_worker_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    plots, draw, sweeps = _load("plots"), _load("_draw"), _load("sweep_plots")
    synthesis = _load("synthesis_plots")
    draw.GIF_CONTEXT = _load("_private", "runtime").shared_palette  # this process only
    from matplotlib.figure import Figure

    Figure()  # matplotlib reads its settings and fonts once, before the first task
    do = {
        "plot": plots.plot_columns,
        "movie": draw.movie,
        "against": sweeps.plot_against,
        "band": sweeps.plot_band,
        "fit": sweeps.plot_fit,
        "optimum": sweeps.plot_optimum,
        "synthesis": synthesis.plot_synthesis,
    }
    tasks, replies = sys.stdin, sys.stdout
    if len(sys.argv) == 4 and sys.argv[1] == "--fork":
        fds = int(sys.argv[2]), int(sys.argv[3])
        tasks, replies = _fork(fds)
    serve(tasks, replies, do)


def _fork(fds: tuple[int, int]):
    """Fork; return the channel this process serves: the copy the second one (``fds``:
    tasks, replies), this one standard input and output. Each closes the other's ends (a
    channel ends when its last writer closes it)."""
    pid = -1
    with contextlib.suppress(AttributeError, OSError):
        pid = os.fork()
    if pid == 0:
        devnull = os.open(os.devnull, os.O_RDWR)
        os.dup2(devnull, 0)
        os.dup2(devnull, 1)
        return open(fds[0], encoding="utf-8"), open(fds[1], "w", encoding="utf-8")
    for fd in fds:
        os.close(fd)
    return sys.stdin, sys.stdout


def serve(tasks, replies, do) -> None:
    """Draw the tasks named on ``tasks`` in turn, a reply line each on ``replies``."""
    for line in tasks:
        name = line.strip()
        if not name:
            break
        try:
            with open(name, "rb") as f:
                kind, args, kwargs = pickle.load(f)
            os.unlink(name)
            reply = ("ok", str(do[kind](*args, **kwargs)))
        except Exception as e:
            try:
                pickle.dumps(e)
            except Exception:
                e = RuntimeError(f"{type(e).__name__}: {e}")
            reply = ("error", e)
        replies.write(pickle.dumps(reply).hex() + "\n")
        replies.flush()


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    os._exit(0)  # every reply is written: skip the interpreter's slow tear-down of matplotlib

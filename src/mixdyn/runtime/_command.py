"""What the ``mixdyn`` command does before anything else: its figure worker and the
garbage collector's pace.

The figure worker of ``mixdyn run`` is started as early as the command line allows.

``mixdyn run`` draws its figures in a worker process (:mod:`mixdyn.runtime._worker`: matplotlib,
no JAX). Importing matplotlib and drawing a first figure costs the worker ~0.5 s; started
when the command begins, before mixdyn imports JAX (:func:`start_for_command_line`, called
first thing by ``mixdyn/__init__.py``), the worker is ready by the time the first run ends.
:func:`worker` hands it to :class:`mixdyn.viz.painter.Painter` (or starts one then). A worker
nobody took is stopped when the process exits.

``mixdyn run FILE`` reads the programs its last run of the file used (its manifest:
:func:`mixdyn.runtime._programs.prefetch`) from the moment JAX is imported, while the rest of mixdyn
and the command's modules import (~0.3 s): :func:`job_tag` reads the job's tag from the
command line as the ``run`` command forms it (:func:`run_tag`).

An empty-cache run imports what tracing needs (:data:`TRACING_IMPORTS`) in a background
thread from its first compile on (:func:`import_ahead`), overlapping XLA's compiles.

The command collects reference cycles less often (:func:`pace_collector`): with Python's
default thresholds the paper example spent ~0.18 s of a ~2 s warm run and ~1 s of an
empty-cache run in the cyclic garbage collector (its full collections walk every object the
imports made), against 0.04 s and 0.14 s with :data:`GC_THRESHOLDS`, for the same peak
memory within 5%. Cycles are still collected; only the command's own process is paced, not
a program that imports mixdyn.

This module imports nothing from mixdyn, nor JAX.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import os
import pathlib
import signal
import subprocess
import sys

#: The worker started for this command line, not yet taken: ``(process, (tasks writer fd,
#: replies reader fd) or None)``.
_started: list = []


def spawn():
    """Start a worker: ``(process or None, second channel's ends or None)``.

    On Linux the worker forks once matplotlib is imported and serves a second channel (see
    :mod:`mixdyn.runtime._worker`); the ends returned are this side's file descriptors of it
    (tasks writer, replies reader)."""
    worker = pathlib.Path(__file__).with_name("_worker.py")
    command = [sys.executable, str(worker)]
    second = sys.platform.startswith("linux") and hasattr(os, "fork")
    ends = (*os.pipe(), *os.pipe()) if second else ()  # tasks r, w; replies r, w
    if second:
        command += ["--fork", str(ends[0]), str(ends[3])]
    proc = None
    try:
        proc = subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            pass_fds=(ends[0], ends[3]) if second else (),
            start_new_session=True,  # the worker and its copy: one group, stopped at once
            env=_worker_environment(),
        )
    except OSError:
        pass
    finally:
        for fd in ends[:1] + ends[3:]:
            os.close(fd)  # the worker's ends
    if proc is None:
        for fd in ends[1:3]:
            os.close(fd)
        return None, None
    return proc, (ends[1], ends[2]) if second else None


def _worker_environment() -> dict[str, str]:
    """The worker's environment: this process's, with NumPy's OpenBLAS on one thread unless
    the user chose (matplotlib's few small matrix products: the pool's threads only spun,
    ~0.1 s of CPU a run, beside the compiling)."""
    return {"OPENBLAS_NUM_THREADS": "1", **os.environ}


def stop(proc) -> None:
    """Stop a worker (and its copy) at once."""
    if hasattr(os, "killpg"):  # the worker's group: its copy too (POSIX)
        with contextlib.suppress(OSError):
            os.killpg(proc.pid, signal.SIGKILL)
    with contextlib.suppress(OSError):
        proc.kill()
    proc.wait()


#: The collector's thresholds for the ``mixdyn`` command (Python's default: 700, 10, 10).
GC_THRESHOLDS = (50_000, 20, 100)


def is_command(argv: list[str]) -> bool:
    """Whether ``argv`` is the command line of the ``mixdyn`` command."""
    return bool(argv) and os.path.basename(argv[0]) == "mixdyn"


def pace_collector() -> None:
    """Collect cycles less often (:data:`GC_THRESHOLDS`) if this process is the ``mixdyn``
    command."""
    if is_command(sys.argv):
        gc.set_threshold(*GC_THRESHOLDS)


def run_tag(file, runs) -> str:
    """The tag of a ``mixdyn run`` job (:func:`mixdyn.runtime._programs.job`): the file and
    its runs."""
    return f"run:{pathlib.Path(file).resolve()}:{','.join(runs or ())}"


#: ``mixdyn run``'s options that take no value, and those that take one (its next word,
#: or after ``=``): whether that value names a run.
_RUN_FLAGS = {
    "--parquet",
    "--netcdf",
    "--excel",
    "--figures",
    "--no-figures",
    "--progress",
    "--no-progress",
}
_RUN_VALUED = {"--run": True, "-r": True, "--out": False, "-o": False}


def job_tag(argv: list[str]) -> str | None:
    """The job tag (:func:`run_tag`) of a ``mixdyn run`` command line, read from ``argv``
    before the command line is parsed; None for any other command line or where it is not
    plain (an option written otherwise, two files): ``run`` then reads its programs itself."""
    if len(argv) < 3 or not is_command(argv) or argv[1] != "run":
        return None
    file, runs = None, []
    words = iter(argv[2:])
    for word in words:
        name, eq, value = word.partition("=")
        if name in _RUN_VALUED:
            value = value if eq else next(words, None)
            if value is None:
                return None
            if _RUN_VALUED[name]:
                runs.append(value)
        elif word in _RUN_FLAGS:
            continue
        elif word.startswith("-") or file is not None:
            return None
        else:
            file = word
    return None if file is None else run_tag(file, runs)


def draws(argv: list[str]) -> bool:
    """Whether ``argv`` is a ``mixdyn run`` command line that may draw figures."""
    if len(argv) < 3 or not is_command(argv) or argv[1] != "run":
        return False
    return not any(a in ("--no-figures", "-h", "--help") for a in argv[2:])


#: What a program traced from scratch imports on its way (diffrax, ~0.3 s): imported ahead,
#: beside the first compile (:func:`import_ahead`).
TRACING_IMPORTS = ("diffrax",)


def import_ahead(modules=TRACING_IMPORTS) -> None:
    """Import ``modules`` in a background thread, now: called by ``mixdyn run`` as it first
    compiles a program from scratch, so that the imports the integrators' tracing needs run
    while XLA compiles the first programs (which releases the interpreter) rather than in the
    middle of the tracing. Where a module is imported already, nothing happens; a failed
    import is left for the tracing to meet and report."""
    todo = [m for m in modules if m not in sys.modules]
    if not todo:
        return
    import importlib
    import threading

    def run():
        for m in todo:
            with contextlib.suppress(Exception):
                importlib.import_module(m)

    threading.Thread(target=run, name="mixdyn-imports", daemon=True).start()


def hand_over() -> None:
    """If this process is ``mixdyn check``, ``show``, ``plot`` or ``schema`` and a command
    server answers it (:mod:`mixdyn.runtime._server`), end with the server's exit code;
    otherwise return (and the command runs here)."""
    if not is_command(sys.argv) or len(sys.argv) < 2:
        return
    from . import _server

    if sys.argv[1] not in _server.SERVED:
        return
    try:
        code = _server.forward(sys.argv)
    except Exception:  # the server's side is a shortcut, never a failure: run here
        code = None
    if code is not None:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)


def start_for_command_line() -> None:
    """Start the worker now if this process is ``mixdyn run`` with figures (see above)."""
    if _started or not draws(sys.argv):
        return
    proc, second = spawn()
    if proc is not None:
        _started.append((proc, second))
        atexit.register(_stop_untaken)


def worker():
    """The worker started for the command line (taken: later calls start new ones), else a
    new one: ``(process or None, second channel's ends or None)``."""
    if _started:
        return _started.pop()
    return spawn()


def _stop_untaken() -> None:
    while _started:
        proc, second = _started.pop()
        stop(proc)
        for fd in second or ():
            with contextlib.suppress(OSError):
                os.close(fd)
